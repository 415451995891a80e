// Replay throughput (issue: the engine must not be the bottleneck): frames per second through the
// pipeline alone, on a flat scene and over textures, and with evemu parsing and writing included.
// Input: the shared real recordings beside the project when present, else a generated random stream.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/default_scene.hpp"
#include "core/replay.hpp"
#include "recording/evemu.hpp"

namespace {

// One long mouse stream: the real recordings end to end (repeated to ~200k frames), or a random walk.
const ph::Recording& stream() {
  static const ph::Recording recording = [] {
    ph::Recording r;
    for (const char* name : {"saitek-cyborg-rat5.evemu", "ps2-generic-mouse.evemu"}) {
      std::ifstream in(std::filesystem::path(PH_SHARED_RECORDINGS_DIR) / name);
      if (!in) continue;
      const ph::Recording one = ph::read_evemu(in, name);
      if (r.events.empty()) r.device = one.device;
      r.events.insert(r.events.end(), one.events.begin(), one.events.end());
    }
    if (r.events.empty()) {
      std::mt19937 rng(1);
      std::uniform_int_distribution<int> d(-6, 6);
      for (int i = 0; i < 5000; ++i) {
        r.events.push_back({i * 8000, ph::ev::kRel, ph::ev::kRelX, d(rng)});
        r.events.push_back({i * 8000, ph::ev::kRel, ph::ev::kRelY, d(rng)});
        r.events.push_back({i * 8000, ph::ev::kSyn, ph::ev::kSynReport, 0});
      }
    }
    const std::vector<ph::InputEvent> once = r.events;
    while (r.events.size() < 600'000) r.events.insert(r.events.end(), once.begin(), once.end());
    return r;
  }();
  return recording;
}

std::size_t frames_in(const ph::Recording& r) {
  std::size_t n = 0;
  for (const ph::InputEvent& e : r.events) n += e.type == ph::ev::kSyn && e.code == ph::ev::kSynReport;
  return n;
}

// A sink that only counts, so the figure is the pipeline's own cost.
class CountingSink final : public ph::EventSink {
 public:
  void write(const ph::Frame& frame) override { events += frame.events.size(); }
  std::size_t events = 0;
};

void run_engine(benchmark::State& state, const ph::Scene& scene) {
  const ph::Recording& input = stream();
  const auto shared = std::shared_ptr<const ph::Scene>(std::shared_ptr<const ph::Scene>(), &scene);
  for (auto _ : state) {
    // Start near the middle of the desktop, on the default scene's first target, every pass.
    ph::PipelineConfig config;
    config.start = ph::Vec2{385.5, 540.5};
    ph::Pipeline pipeline(shared, config);
    ph::RecordingSource source(input.events);
    CountingSink sink;
    ph::run_stream(source, pipeline, sink);
    benchmark::DoNotOptimize(sink.events);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * frames_in(input)));
  state.counters["frames"] = static_cast<double>(frames_in(input));
}

void BM_EngineFlat(benchmark::State& state) {
  static const ph::Scene flat;
  run_engine(state, flat);
}

void BM_EngineTextured(benchmark::State& state) {
  static const ph::Scene scene = ph::default_scene();
  run_engine(state, scene);
}

// Parse the evemu text, replay over the default scene, write the evemu text.
void BM_ParseReplayWrite(benchmark::State& state) {
  static const ph::Scene scene = ph::default_scene();
  std::ostringstream text;
  ph::write_evemu(text, stream());
  const std::string input = text.str();
  for (auto _ : state) {
    std::istringstream in(input);
    const ph::Recording recording = ph::read_evemu(in, "bench");
    std::ostringstream out;
    ph::write_evemu(out, ph::replay(recording, scene, ph::PipelineConfig{}));
    benchmark::DoNotOptimize(out.str().size());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * frames_in(stream())));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * input.size()));
}

BENCHMARK(BM_EngineFlat)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EngineTextured)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParseReplayWrite)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
