// Cost of ph::advance, the exact per-texel traversal (docs/METHODS.md, "The traversal"), for the curvature, the
// depth and the hybrid method (given both maps) on the paper's targets: typical frames, frames that stay in their texel
// (still/: a frame's own cost), fast flicks, a pointer outside every region and a flat region, and a texel's reading
// and C/D without the walk (texel/: time_per_texel). docs/PERFORMANCE.md explains the figures and how to reproduce
// them.
//
// Every benchmark reports, besides the time per iteration (= per frame, one advance call):
//   steps_per_frame  texel boundaries crossed inside regions per frame (FrameResult::steps, averaged);
//   time_per_step    the benchmark's CPU time divided by the number of those steps. It is a Counter on the
//                    summed step count with kIsRate | kInvert: kIsRate divides the count by the run's CPU
//                    seconds (the library always uses CPU time for rates), kInvert turns steps per second
//                    into seconds per step. The value is in seconds; the console prints it with an SI
//                    prefix ("12.3ns"). It includes the per-frame overhead spread over the frame's steps.
// latency/typical/... times each frame of the typical stream on its own and reports the median and 99th percentile
// of those times (median_ns, p99_ns) and the cost of an empty timed interval (clock_ns), which both include, and the
// same quantiles of the texel steps a frame takes (median_steps, p99_steps): whether a slow frame did more work.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/engine/direction_lut.hpp"
#include "core/engine/engine_options.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"

namespace {

enum class MethodKind { curvature, depth, hybrid };

const char* method_name(MethodKind kind) {
  return kind == MethodKind::curvature ? "curvature" : kind == MethodKind::depth ? "depth" : "hybrid";
}

constexpr std::int32_t kTargetSize = 500;  // TargetSpec's default: the region is 500 x 500 px at (0, 0)
constexpr ph::Vec2 kTargetCentre{kTargetSize / 2.0, kTargetSize / 2.0};             // a texel corner
constexpr ph::Vec2 kTexelCentre{kTargetSize / 2.0 + 0.5, kTargetSize / 2.0 + 0.5};  // the centre of the texel past it
constexpr ph::Rect kTargetRect{0, 0, kTargetSize, kTargetSize};

// ---------------------------------------------------------------------------------------------------
// Scenes, built in memory once and kept: the benchmark runner calls each function several times.

// One target as one region at (0, 0) with the method's default parameters (as tests/test_traversal.cpp).
ph::Region target_region(const ph::TargetSpec& spec, MethodKind kind) {
  ph::Region region;
  region.name = spec.name();
  region.rect = kTargetRect;
  if (kind == MethodKind::depth) {
    region.fields.depth = ph::target_depth_field(spec);
    region.method = std::make_shared<ph::DepthMethod>(ph::DepthParams{});
  } else if (kind == MethodKind::hybrid) {  // both maps, as a hybrid region is given them
    region.fields.gradient = ph::target_gradient_field(spec);
    region.fields.depth = ph::target_depth_field(spec);
    region.method = std::make_shared<ph::HybridMethod>(ph::HybridParams{});
  } else {
    region.fields.gradient = ph::target_gradient_field(spec);
    region.method = std::make_shared<ph::CurvatureMethod>(ph::CurvatureParams{});
  }
  return region;
}

// A region of the same size whose surface is flat (zero gradient, constant depth): every step still
// samples and computes a C/D, which comes out as 1.
ph::Region flat_region(ph::Rect rect, MethodKind kind) {
  ph::Region region;
  region.name = "flat";
  region.rect = rect;
  if (kind == MethodKind::depth) {
    region.fields.depth = ph::DepthField(rect.w, rect.h, 0.0f);
    region.method = std::make_shared<ph::DepthMethod>(ph::DepthParams{});
  } else if (kind == MethodKind::hybrid) {
    region.fields.gradient = ph::GradientField(rect.w, rect.h, ph::Gradient{});
    region.fields.depth = ph::DepthField(rect.w, rect.h, 0.0f);
    region.method = std::make_shared<ph::HybridMethod>(ph::HybridParams{});
  } else {
    region.fields.gradient = ph::GradientField(rect.w, rect.h, ph::Gradient{});
    region.method = std::make_shared<ph::CurvatureMethod>(ph::CurvatureParams{});
  }
  return region;
}

ph::Scene scene_of(ph::Region region) {
  std::vector<ph::Region> regions;
  regions.push_back(std::move(region));
  return ph::Scene(std::move(regions));
}

const ph::Scene& target_scene(const ph::TargetSpec& spec, MethodKind kind) {
  static std::map<std::pair<std::string, MethodKind>, ph::Scene> cache;
  auto key = std::make_pair(spec.name(), kind);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(std::move(key), scene_of(target_region(spec, kind))).first;
  return it->second;
}

std::vector<const ph::Scene*> all_target_scenes(MethodKind kind) {
  std::vector<const ph::Scene*> scenes;
  for (const ph::TargetSpec& spec : ph::all_targets()) scenes.push_back(&target_scene(spec, kind));
  return scenes;
}

// The 24 target scenes with engine options (the traversal variants); direction tables are built here, once.
std::vector<const ph::Scene*> all_target_scenes(MethodKind kind, const ph::EngineOptions& options) {
  static std::map<std::pair<std::string, MethodKind>, std::vector<ph::Scene>> cache;
  auto key = std::make_pair(ph::label_of(options), kind);
  auto it = cache.find(key);
  if (it == cache.end()) {
    std::vector<ph::Scene> scenes;
    for (const ph::TargetSpec& spec : ph::all_targets()) {
      scenes.push_back(scene_of(target_region(spec, kind)));
      scenes.back().set_options(options);
    }
    it = cache.emplace(std::move(key), std::move(scenes)).first;
  }
  std::vector<const ph::Scene*> out;
  for (const ph::Scene& scene : it->second) out.push_back(&scene);
  return out;
}

const ph::Scene& flat_scene(MethodKind kind) {
  static const ph::Scene curvature = scene_of(flat_region(kTargetRect, MethodKind::curvature));
  static const ph::Scene depth = scene_of(flat_region(kTargetRect, MethodKind::depth));
  static const ph::Scene hybrid = scene_of(flat_region(kTargetRect, MethodKind::hybrid));
  return kind == MethodKind::curvature ? curvature : kind == MethodKind::depth ? depth : hybrid;
}

// A 1920 x 1080 screen with a 300 x 300 region in each corner: the cursor in the middle never reaches
// them, so what they contain does not matter (flat ones are cheapest to build).
const ph::Scene& far_regions_scene() {
  static const ph::Scene scene = [] {
    std::vector<ph::Region> regions;
    for (ph::Rect rect : {ph::Rect{0, 0, 300, 300}, ph::Rect{1620, 0, 300, 300}, ph::Rect{0, 780, 300, 300},
                          ph::Rect{1620, 780, 300, 300}}) {
      regions.push_back(flat_region(rect, MethodKind::curvature));
    }
    return ph::Scene(std::move(regions));
  }();
  return scene;
}

// ---------------------------------------------------------------------------------------------------
// Inputs, precomputed so that the timed loop only reads them.

constexpr std::size_t kStreamLength = 4096;  // a power of two: the stream index wraps with a mask
constexpr std::size_t kStreamMask = kStreamLength - 1;

ph::Vec2 polar(double length, double angle) { return {length * std::cos(angle), length * std::sin(angle)}; }

// Typical mouse frames: 1-10 px of motor travel in uniformly random directions.
const std::vector<ph::Vec2>& typical_motions() {
  static const std::vector<ph::Vec2> motions = [] {
    std::mt19937_64 rng(20240601);
    std::uniform_real_distribution<double> size(1.0, 10.0);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
    std::vector<ph::Vec2> out(kStreamLength);
    for (ph::Vec2& m : out) m = polar(size(rng), angle(rng));
    return out;
  }();
  return motions;
}

// The same directions, each 1000 times shorter (1-10 thousandths of a px): each frame run from the centre of a texel
// (kTexelCentre, run_typical_frames' every_frame_from_start) stays inside it, so that it costs the frame's own work
// and the one C/D of that texel, and no texel step. (Run one after another, as before 2026-11-29, the millions of
// frames of a run drifted the cursor downhill, a frame down a slope going further than one up it, and from a texel
// corner: 0.7-5 % of them stepped.)
const std::vector<ph::Vec2>& still_motions() {
  static const std::vector<ph::Vec2> motions = [] {
    std::vector<ph::Vec2> out = typical_motions();
    for (ph::Vec2& m : out) m = m * 1e-3;
    return out;
  }();
  return motions;
}

struct Flick {
  ph::CursorState start;
  ph::Vec2 motor;
};

// 500 px of motor travel in one frame, starting near the target's edge (240 px from its centre) and aimed
// across it, within 30 degrees of the centre, so that it crosses most of the relief.
const std::vector<Flick>& flicks() {
  static const std::vector<Flick> out = [] {
    std::mt19937_64 rng(20240602);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
    std::uniform_real_distribution<double> jitter(-std::numbers::pi / 6.0, std::numbers::pi / 6.0);
    std::vector<Flick> flicks(kStreamLength);
    for (Flick& flick : flicks) {
      const double around = angle(rng);
      const ph::Vec2 start = kTargetCentre + polar(240.0, around);
      flick = {ph::cursor_at(start), polar(500.0, around + std::numbers::pi + jitter(rng))};
    }
    return flicks;
  }();
  return out;
}

// ---------------------------------------------------------------------------------------------------
// Timed loops.

bool inside(const ph::Rect& box, ph::Vec2 p) {
  return p.x >= box.x && p.x < box.x + box.w && p.y >= box.y && p.y < box.y + box.h;
}

void report_steps(benchmark::State& state, std::uint64_t steps) {
  const auto count = static_cast<double>(steps);
  state.counters["steps_per_frame"] = benchmark::Counter(count, benchmark::Counter::kAvgIterations);
  if (steps > 0) {
    state.counters["time_per_step"] =
        benchmark::Counter(count, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
}

// Feeds the typical stream (or `motions`) frame after frame, as the daemon would (each frame depends on the last). A
// cursor that leaves `keep_in` goes back to `start`; that check is two compares per frame, under 1 ns, and
// is left in the timing rather than pausing the timer (PauseTiming costs far more than a frame). With
// several scenes, the next one takes over from `start` after each pass over the stream.
// `every_frame_from_start`: each frame starts at `start` (the still stream; the copy of the cursor's state, a few
// words, is timed with the frame).
void run_typical_frames(benchmark::State& state, std::span<const ph::Scene* const> scenes, ph::Vec2 start,
                        ph::Rect keep_in, const std::vector<ph::Vec2>& motions = typical_motions(),
                        bool every_frame_from_start = false) {
  const ph::CursorState start_cursor = ph::cursor_at(start);
  ph::CursorState cursor = start_cursor;
  std::size_t scene_index = 0;
  std::size_t frame = 0;
  std::uint64_t steps = 0;
  for (auto _ : state) {
    if (every_frame_from_start) cursor = start_cursor;
    const ph::FrameResult result = ph::advance(*scenes[scene_index], cursor, motions[frame & kStreamMask]);
    benchmark::DoNotOptimize(result);
    steps += result.steps;
    if (!inside(keep_in, cursor.position)) cursor = start_cursor;
    if ((++frame & kStreamMask) == 0 && scenes.size() > 1) {
      scene_index = (scene_index + 1) % scenes.size();
      cursor = start_cursor;
    }
  }
  report_steps(state, steps);
}

// The spread of single frames: the typical stream as run_typical_frames, each frame timed on its own with
// steady_clock. Counters: the median and 99th percentile of those times (ns) and the median of an empty timed
// interval (clock_ns), which both include; the benchmark's own time per iteration includes two clock reads.
void run_frame_latency(benchmark::State& state, std::span<const ph::Scene* const> scenes, ph::Vec2 start,
                       ph::Rect keep_in) {
  using Clock = std::chrono::steady_clock;
  const std::vector<ph::Vec2>& motions = typical_motions();
  const ph::CursorState start_cursor = ph::cursor_at(start);
  ph::CursorState cursor = start_cursor;
  std::size_t scene_index = 0;
  std::size_t frame = 0;
  std::vector<double> frame_ns, clock_ns, frame_steps;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const ph::FrameResult result = ph::advance(*scenes[scene_index], cursor, motions[frame & kStreamMask]);
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(result);
    frame_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
    frame_steps.push_back(static_cast<double>(result.steps));
    if ((frame & 15) == 0) {
      const auto c0 = Clock::now();
      const auto c1 = Clock::now();
      clock_ns.push_back(std::chrono::duration<double, std::nano>(c1 - c0).count());
    }
    if (!inside(keep_in, cursor.position)) cursor = start_cursor;
    if ((++frame & kStreamMask) == 0 && scenes.size() > 1) {
      scene_index = (scene_index + 1) % scenes.size();
      cursor = start_cursor;
    }
  }
  auto quantile = [](std::vector<double>& v, double q) {
    if (v.empty()) return 0.0;
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[static_cast<std::size_t>(k)];
  };
  state.counters["median_ns"] = quantile(frame_ns, 0.5);
  state.counters["p99_ns"] = quantile(frame_ns, 0.99);
  state.counters["clock_ns"] = quantile(clock_ns, 0.5);
  state.counters["median_steps"] = quantile(frame_steps, 0.5);
  state.counters["p99_steps"] = quantile(frame_steps, 0.99);
}

// With several scenes, the next takes over after this many flicks: a 0.5 s run then covers all 24 targets
// several times, and each field stays in cache for a while as it would during a session.
constexpr std::size_t kFlicksPerScene = 64;

// Each frame is one flick from its own precomputed start; frames do not depend on each other.
void run_flicks(benchmark::State& state, std::span<const ph::Scene* const> scenes) {
  const std::vector<Flick>& all = flicks();
  std::size_t scene_index = 0;
  std::size_t frame = 0;
  std::uint64_t steps = 0;
  for (auto _ : state) {
    const Flick& flick = all[frame & kStreamMask];
    ph::CursorState cursor = flick.start;
    const ph::FrameResult result = ph::advance(*scenes[scene_index], cursor, flick.motor);
    benchmark::DoNotOptimize(result);
    benchmark::DoNotOptimize(cursor);
    steps += result.steps;
    if (++frame % kFlicksPerScene == 0 && scenes.size() > 1) scene_index = (scene_index + 1) % scenes.size();
  }
  report_steps(state, steps);
}

// ---------------------------------------------------------------------------------------------------
// Registration.

// Representative targets: the steepest smooth bump, a linear bump with its kink and rim, a shallow hole.
const char* const kRepresentativeTargets[] = {"bump-gaussian-h1-r200", "bump-linear-h1-r100",
                                              "hole-polynomial-h0.25-r200"};

ph::TargetSpec target_named(const std::string& name) {
  for (const ph::TargetSpec& spec : ph::all_targets()) {
    if (spec.name() == name) return spec;
  }
  throw std::invalid_argument("no target named " + name);
}

// Scenes are built lazily, on the first run of a benchmark, so that a filtered run builds only what it uses.
using SceneListFn = std::vector<const ph::Scene*> (*)(MethodKind, const std::string&);

void register_pair(const std::string& label, MethodKind kind, SceneListFn make_scenes) {
  const std::string suffix = std::string(method_name(kind)) + "/" + label;
  // Shared by the two benchmarks, which the library keeps (and so this list) until the program ends.
  auto scenes = std::make_shared<std::vector<const ph::Scene*>>();
  auto scenes_for = [=] {
    if (scenes->empty()) *scenes = make_scenes(kind, label);
    return std::span<const ph::Scene* const>(*scenes);
  };
  benchmark::RegisterBenchmark(("typical/" + suffix).c_str(), [=](benchmark::State& state) {
    run_typical_frames(state, scenes_for(), kTargetCentre, kTargetRect);
  });
  benchmark::RegisterBenchmark(("still/" + suffix).c_str(), [=](benchmark::State& state) {
    run_typical_frames(state, scenes_for(), kTexelCentre, kTargetRect, still_motions(), true);
  });
  benchmark::RegisterBenchmark(("flick/" + suffix).c_str(),
                               [=](benchmark::State& state) { run_flicks(state, scenes_for()); });
  benchmark::RegisterBenchmark(("latency/typical/" + suffix).c_str(), [=](benchmark::State& state) {
    run_frame_latency(state, scenes_for(), kTargetCentre, kTargetRect);
  });
}

std::vector<const ph::Scene*> one_target(MethodKind kind, const std::string& name) {
  return {&target_scene(target_named(name), kind)};
}
std::vector<const ph::Scene*> every_target(MethodKind kind, const std::string&) { return all_target_scenes(kind); }
std::vector<const ph::Scene*> flat_only(MethodKind kind, const std::string&) { return {&flat_scene(kind)}; }

// The cursor wanders in the middle of a 1920 x 1080 screen, at least 300 px from the far regions.
constexpr ph::Vec2 kMiddle{960.0, 540.0};
constexpr ph::Rect kMiddleBox{660, 340, 600, 400};

void register_outside() {
  static const ph::Scene empty;
  static const ph::Scene* const empty_list[] = {&empty};
  static const ph::Scene* const far_list[] = {&far_regions_scene()};
  benchmark::RegisterBenchmark("typical/outside/empty-scene", [](benchmark::State& state) {
    run_typical_frames(state, empty_list, kMiddle, kMiddleBox);
  });
  benchmark::RegisterBenchmark("typical/outside/4-far-regions", [](benchmark::State& state) {
    run_typical_frames(state, far_list, kMiddle, kMiddleBox);
  });
}

// Every variant of core/engine/engine_options.hpp on all 24 targets, as typical frames and flicks. For
// unit_steps and frame_midpoint, steps_per_frame counts C/D evaluations inside regions, not texel steps.
void register_variants() {
  for (const ph::EngineOptions& options : ph::all_engine_variants()) {
    for (MethodKind kind : {MethodKind::curvature, MethodKind::depth}) {
      const std::string suffix = ph::label_of(options) + "/" + method_name(kind) + "/all-24";
      auto scenes = std::make_shared<std::vector<const ph::Scene*>>();
      auto scenes_for = [=] {
        if (scenes->empty()) *scenes = all_target_scenes(kind, options);
        return std::span<const ph::Scene* const>(*scenes);
      };
      benchmark::RegisterBenchmark(("variant/typical/" + suffix).c_str(), [=](benchmark::State& state) {
        run_typical_frames(state, scenes_for(), kTargetCentre, kTargetRect);
      });
      benchmark::RegisterBenchmark(("variant/flick/" + suffix).c_str(),
                                   [=](benchmark::State& state) { run_flicks(state, scenes_for()); });
    }
  }
}

// A 1920 x 1080 region of smooth relief (gradient of sin x sin y, 60 px of height): what a full-screen
// texture costs to tabulate.
ph::Region screen_region(MethodKind kind) {
  ph::Region region;
  region.name = "screen";
  region.rect = {0, 0, 1920, 1080};
  const double f = 2.0 * std::numbers::pi / 240.0, a = 60.0;
  if (kind == MethodKind::depth) {
    region.fields.depth = ph::DepthField(1920, 1080);
    for (int y = 0; y < 1080; ++y) {
      for (int x = 0; x < 1920; ++x) {
        region.fields.depth->at(x, y) = static_cast<float>(a * std::sin(f * x) * std::sin(f * y));
      }
    }
    region.method = std::make_shared<ph::DepthMethod>(ph::DepthParams{});
  } else {
    region.fields.gradient = ph::GradientField(1920, 1080);
    for (int y = 0; y < 1080; ++y) {
      for (int x = 0; x < 1920; ++x) {
        region.fields.gradient->at(x, y) = {static_cast<float>(a * f * std::cos(f * x) * std::sin(f * y)),
                                            static_cast<float>(a * f * std::sin(f * x) * std::cos(f * y))};
      }
    }
    region.method = std::make_shared<ph::CurvatureMethod>(ph::CurvatureParams{});
  }
  return region;
}

// Time of Scene::set_options(direction_lut) (building the tables; the region's fields already exist)
// and the table's bytes per texel. Manual time: each iteration starts from a scene without tables.
void register_lut_builds() {
  for (int directions : {8, 16}) {
    for (MethodKind kind : {MethodKind::curvature, MethodKind::depth}) {
      for (bool screen : {false, true}) {
        const std::string name = "lut_build/" + std::string(method_name(kind)) + "/" +
                                 (screen ? "1920x1080" : "500x500") + "/" + std::to_string(directions);
        benchmark::RegisterBenchmark(
            name.c_str(),
            [=](benchmark::State& state) {
              ph::Scene scene =
                  scene_of(screen ? screen_region(kind) : target_region(target_named("bump-gaussian-h1-r200"), kind));
              const auto texels = static_cast<double>(scene.regions()[0].rect.area());
              double seconds = 0.0;
              for (auto _ : state) {
                scene.set_options({});
                const auto t0 = std::chrono::steady_clock::now();
                scene.set_options({ph::Traversal::direction_lut, ph::Sampling::nearest, directions});
                const auto t1 = std::chrono::steady_clock::now();
                const double elapsed = std::chrono::duration<double>(t1 - t0).count();
                seconds += elapsed;
                state.SetIterationTime(elapsed);
              }
              state.counters["bytes_per_texel"] = static_cast<double>(scene.lut_bytes()) / texels;
              // Build time per texel (ns), from the manual times alone.
              state.counters["ns_per_texel"] = seconds * 1e9 / (texels * static_cast<double>(state.iterations()));
            })
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond)
            ->Iterations(screen ? 2 : 5);
      }
    }
  }
}

// A texel's reading and C/D alone, without the walk: the method's leg for one direction (30 degrees) reads 4096
// texels of a 64 x 64 window on the target's slope (in cache), in a random order, each C/D independent of the last.
// What a step costs beyond this is the walk's (docs/PERFORMANCE.md, "The chain shorter with other last bits").
template <typename M>
void run_texels(benchmark::State& state, const ph::Region& region, const M& method) {
  const ph::Vec2 m{std::cos(std::numbers::pi / 6.0), std::sin(std::numbers::pi / 6.0)};
  const auto leg = method.leg(&region.fields, m);
  std::mt19937_64 rng(20241126);
  std::uniform_int_distribution<std::int32_t> cell(0, 63);
  std::vector<ph::FieldTexel> texels(4096);
  // From 80 px right of the centre: the Gaussian bump's flank, where the C/D changes from texel to texel.
  for (ph::FieldTexel& texel : texels) texel = leg.at({kTargetSize / 2 + 80 + cell(rng), kTargetSize / 2 + cell(rng)});
  const ph::TexelSample from{};
  double sum = 0.0;
  for (auto _ : state) {
    for (const ph::FieldTexel& texel : texels) sum += method.cd(from, leg.sample(texel), 1.0, nullptr);
  }
  benchmark::DoNotOptimize(sum);
  state.counters["time_per_texel"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(texels.size()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void register_texels() {
  for (MethodKind kind : {MethodKind::curvature, MethodKind::depth, MethodKind::hybrid}) {
    const std::string name = std::string("texel/") + method_name(kind) + "/bump-gaussian-h1-r200";
    benchmark::RegisterBenchmark(name.c_str(), [kind](benchmark::State& state) {
      const ph::Region& region = target_scene(target_named("bump-gaussian-h1-r200"), kind).regions()[0];
      // As the traversal does: the method as its concrete class, so that its reading and C/D inline.
      ph::visit_method(*region.method, [&](const auto& method) {
        if constexpr (requires { method.leg(&region.fields, ph::Vec2{}); }) {
          run_texels(state, region, method);
        } else {
          state.SkipWithError("the method has no per-leg reading");
        }
      });
    });
  }
}

void register_all() {
  for (MethodKind kind : {MethodKind::curvature, MethodKind::depth, MethodKind::hybrid}) {
    for (const char* name : kRepresentativeTargets) register_pair(name, kind, one_target);
    register_pair("all-24", kind, every_target);
    register_pair("flat", kind, flat_only);
  }
  register_outside();
  register_texels();
  register_variants();
  register_lut_builds();
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
