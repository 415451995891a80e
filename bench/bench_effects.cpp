// Cost of the frame effects (core/effect.hpp) of surface interrogation: per frame of ph::advance with an effect
// against the same region without, and the precompute (time, bytes per texel) for a full-HD region.
// docs/PERFORMANCE.md ("Surface interrogation: materials") gives the figures and the command.
//
// To add an effect: build its EffectPtr from relief() / relief_gradient(), then call advance_frames() with
// effect_scene({effect}) for the per-frame cost and report_precompute() for its load.
//
// Counters: time_per_texel (CPU seconds per texel of a precompute, printed with an SI prefix), bytes_per_texel
// (what the effect stores), slowed (share of frames whose C/D was above 1), steps_per_frame (texel boundaries the
// walk crossed: a slowed frame walks fewer).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "bench/relief.hpp"
#include "core/effect.hpp"
#include "core/effect_materials.hpp"
#include "core/field.hpp"
#include "core/method_flat.hpp"
#include "core/scene.hpp"
#include "core/traversal.hpp"

namespace {

constexpr std::int32_t kW = ph::bench::kReliefWidth;
constexpr std::int32_t kH = ph::bench::kReliefHeight;

const ph::DepthField& relief() { return ph::bench::relief_depth(); }

// The fields a loader would hold for the region: a normal map's gradient and a depth map.
const ph::RegionFields& relief_fields() {
  static const ph::RegionFields fields = [] {
    ph::RegionFields f;
    f.depth = relief();
    f.gradient = ph::gradient_from_depth(relief());
    return f;
  }();
  return fields;
}

// A full-HD region at the screen's origin with a flat method (C/D 1 per texel) and the given effects.
std::shared_ptr<const ph::Scene> effect_scene(std::vector<ph::EffectPtr> effects) {
  ph::Region region;
  region.name = "bench";
  region.rect = {0, 0, kW, kH};
  region.method = std::make_shared<ph::FlatMethod>();
  region.effects = std::move(effects);
  return std::make_shared<const ph::Scene>(std::vector<ph::Region>{region});
}

struct Motion {
  ph::Vec2 motor;
};

// 4096 motor displacements of 1-10 px in uniformly random directions (as bench_engine's typical stream).
const std::vector<Motion>& typical_stream() {
  static const std::vector<Motion> stream = [] {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> length(1.0, 10.0);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
    std::vector<Motion> s(4096);
    for (Motion& m : s) {
      const double a = angle(rng);
      const double l = length(rng);
      m.motor = {l * std::cos(a), l * std::sin(a)};
    }
    return s;
  }();
  return stream;
}

// One advance() per iteration, frames 8 ms apart (a 125 Hz mouse); a cursor that wanders out of the central
// 1000 x 600 box is put back at the centre (a few compares, kept in the timed loop).
void advance_frames(benchmark::State& state, const ph::Scene& scene) {
  const std::vector<Motion>& stream = typical_stream();
  const ph::Vec2 centre{kW / 2.0 + 0.5, kH / 2.0 + 0.5};
  ph::CursorState cursor = ph::cursor_at(centre);
  std::size_t frame = 0;
  std::int64_t slowed = 0, steps = 0;
  for (auto _ : state) {
    const ph::TimeUs time = static_cast<ph::TimeUs>(frame) * 8000;
    const ph::FrameResult result = ph::advance(scene, cursor, stream[frame & 4095].motor, time);
    benchmark::DoNotOptimize(result);
    slowed += result.cd_max > 1.0;
    steps += result.steps;
    ++frame;
    if (std::abs(cursor.position.x - centre.x) > 500.0 || std::abs(cursor.position.y - centre.y) > 300.0) {
      const ph::EffectStates kept = cursor.effects;
      cursor = ph::cursor_at(centre);
      cursor.effects = kept;
    }
  }
  const double frames = static_cast<double>(std::max<std::size_t>(frame, 1));
  state.counters["slowed"] = static_cast<double>(slowed) / frames;
  state.counters["steps_per_frame"] = static_cast<double>(steps) / frames;
}

void report_precompute(benchmark::State& state, std::size_t bytes) {
  state.counters["time_per_texel"] = benchmark::Counter(static_cast<double>(state.iterations()) * kW * kH,
                                                        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["bytes_per_texel"] = static_cast<double>(bytes) / (static_cast<double>(kW) * kH);
}

// ---- materials ----

ph::MaterialsParams materials_from(ph::ClassSource source) {
  ph::MaterialsParams p;
  p.source = source;
  return p;
}

void BM_AdvanceNoEffect(benchmark::State& state) {
  static const auto scene = effect_scene({});
  advance_frames(state, *scene);
}

void BM_AdvanceMaterials(benchmark::State& state) {
  static const auto effect =
      ph::make_materials_effect(relief_fields(), kW, kH, materials_from(ph::ClassSource::normals), 16);
  static const auto scene = effect_scene({effect});
  advance_frames(state, *scene);
  // Share of each class in the region (0 planar, 1 parabolic, 2 elliptic, 3 hyperbolic).
  const auto& classes = static_cast<const ph::MaterialsEffect&>(*effect).classes().values;
  for (int c = 0; c < 4; ++c) {
    const auto n = std::count(classes.begin(), classes.end(), static_cast<std::uint8_t>(c));
    state.counters[std::string("share_") + ph::class_name(static_cast<ph::CurvatureClass>(c))] =
        static_cast<double>(n) / static_cast<double>(classes.size());
  }
}

// The effect's cost alone: every class mapped to none, so the walk is the same as without the effect.
void BM_AdvanceMaterialsAllNone(benchmark::State& state) {
  ph::MaterialsParams params = materials_from(ph::ClassSource::normals);
  params.materials.fill(ph::Material::none);
  static const auto scene = effect_scene({ph::make_materials_effect(relief_fields(), kW, kH, params, 16)});
  advance_frames(state, *scene);
}

// The default filter and tolerances for a map of `bits` (state.range(0)): radius 3 (normals) or 8 (depth) at
// 16 bits, 16 at 8 bits.
void materials_precompute(benchmark::State& state, ph::ClassSource source) {
  const ph::MaterialsParams params = materials_from(source);
  const int bits = static_cast<int>(state.range(0));
  std::size_t bytes = 0;
  for (auto _ : state) {
    const ph::EffectPtr effect = ph::make_materials_effect(relief_fields(), kW, kH, params, bits);
    bytes = effect->bytes();
    benchmark::DoNotOptimize(effect.get());
  }
  report_precompute(state, bytes);
}

void BM_MaterialsPrecomputeNormals(benchmark::State& state) { materials_precompute(state, ph::ClassSource::normals); }
void BM_MaterialsPrecomputeDepth(benchmark::State& state) { materials_precompute(state, ph::ClassSource::depth); }

}  // namespace

BENCHMARK(BM_AdvanceNoEffect);
BENCHMARK(BM_AdvanceMaterials);
BENCHMARK(BM_AdvanceMaterialsAllNone);
BENCHMARK(BM_MaterialsPrecomputeNormals)->Arg(16)->Arg(8)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MaterialsPrecomputeDepth)->Arg(16)->Arg(8)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
