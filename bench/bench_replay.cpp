// Replay throughput (the engine must not be the bottleneck): frames per second through the
// pipeline alone, on flat scenes (no region; a region of C/D 1 everywhere), over the default scene (where
// the recorded hand touches a texture in a small part of the frames) and with the cursor model kept inside
// one of its targets (every frame that moves walks the texture), and with evemu parsing and writing included.
// Input: the two real recordings of tests/data/recordings end to end (a random walk if they cannot be read).
// Counters: `textured` is the fraction of frames whose C/D range differs from 1 (the texture changed the
// motion), `in_region` the fraction that end with the cursor inside a region.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

#include "core/default_scene.hpp"
#include "core/method_curvature.hpp"
#include "core/method_flat.hpp"
#include "core/replay.hpp"
#include "recording/evemu.hpp"

namespace {

// One long mouse stream: the real recordings end to end (repeated to ~200k frames), or a random walk.
const ph::Recording& stream() {
  static const ph::Recording recording = [] {
    ph::Recording r;
    for (const char* name : {"saitek-cyborg-rat5.evemu", "ps2-generic-mouse.evemu"}) {
      std::ifstream in(std::filesystem::path(PH_RECORDINGS_DIR) / name);
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

// The cursor model's start in every engine benchmark: the centre of the default scene's first target, the
// Gaussian bump (500 x 500 at 135, 290; radius 200).
constexpr ph::Vec2 kStart{385.5, 540.5};
// A desktop that keeps the cursor model inside that bump: the square inscribed in its circle of relief, so
// that every frame that moves walks the texture.
constexpr ph::Rect kInsideTheBump{385 - 141, 540 - 141, 282, 282};

ph::PipelineConfig engine_config(const ph::Rect& desktop) {
  ph::PipelineConfig config;
  config.start = kStart;
  config.desktop = desktop;
  return config;
}

// One untimed pass with per-frame reports: the fraction of frames the texture changed and the fraction
// that end inside a region.
void count_frames(benchmark::State& state, const ph::Scene& scene, const ph::Recording& input,
                  const ph::PipelineConfig& config) {
  std::vector<ph::FrameReport> reports;
  ph::replay(input, scene, config, &reports);
  std::size_t textured = 0, in_region = 0;
  for (const ph::FrameReport& r : reports) {
    textured += r.cd_min != 1.0 || r.cd_max != 1.0;
    const ph::Texel t{static_cast<std::int32_t>(std::floor(r.cursor.x)),
                      static_cast<std::int32_t>(std::floor(r.cursor.y))};
    in_region += scene.owner(t).has_value();
  }
  const double frames = static_cast<double>(reports.size());
  state.counters["textured"] = static_cast<double>(textured) / frames;
  state.counters["in_region"] = static_cast<double>(in_region) / frames;
}

void run_engine(benchmark::State& state, const ph::Scene& scene, const ph::Rect& desktop = {0, 0, 1920, 1080}) {
  const ph::Recording& input = stream();
  const auto shared = std::shared_ptr<const ph::Scene>(std::shared_ptr<const ph::Scene>(), &scene);
  const ph::PipelineConfig config = engine_config(desktop);
  for (auto _ : state) {
    ph::Pipeline pipeline(shared, config);  // from kStart, every pass
    ph::RecordingSource source(input.events);
    CountingSink sink;
    ph::run_stream(source, pipeline, sink);
    benchmark::DoNotOptimize(sink.events);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * frames_in(input)));
  state.counters["frames"] = static_cast<double>(frames_in(input));
  count_frames(state, scene, input, config);
}

// One region over the whole 1920 x 1080 desktop with C/D 1 everywhere.
ph::Scene flat_region(ph::MethodPtr method, ph::RegionFields fields) {
  std::vector<ph::Region> regions(1);
  regions[0].name = "flat";
  regions[0].rect = {0, 0, 1920, 1080};
  regions[0].fields = std::move(fields);
  regions[0].method = std::move(method);
  return ph::Scene(std::move(regions));
}

void BM_EngineFlat(benchmark::State& state) {
  static const ph::Scene flat;
  run_engine(state, flat);
}

// A region with the method `none`: no field, C/D 1.
void BM_EngineFlatRegionNone(benchmark::State& state) {
  static const ph::Scene scene = flat_region(std::make_shared<ph::FlatMethod>(), {});
  run_engine(state, scene);
}

// A region of constant (zero) gradient with the curvature method: every texel step is still sampled.
void BM_EngineFlatRegionConstant(benchmark::State& state) {
  static const ph::Scene scene = [] {
    ph::RegionFields fields;
    fields.gradient = ph::GradientField(1920, 1080);
    return flat_region(std::make_shared<ph::CurvatureMethod>(ph::CurvatureParams{}), std::move(fields));
  }();
  run_engine(state, scene);
}

void BM_EngineTextured(benchmark::State& state) {
  static const ph::Scene scene = ph::default_scene();
  run_engine(state, scene);
}

// The default scene with the cursor model kept inside its Gaussian bump: every frame over a texture.
void BM_EngineInsideTextures(benchmark::State& state) {
  static const ph::Scene scene = ph::default_scene();
  run_engine(state, scene, kInsideTheBump);
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
BENCHMARK(BM_EngineFlatRegionNone)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EngineFlatRegionConstant)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EngineTextured)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EngineInsideTextures)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParseReplayWrite)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
