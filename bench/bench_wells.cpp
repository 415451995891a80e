// Gravity wells (core/effects/effect_wells.hpp) on a full-HD region: what they add to a frame of advance(), and
// what a reload costs (make_wells_effect: the mask and the nearest-pattern field). docs/PERFORMANCE.md
// ("Surface interrogation: gravity wells") gives the figures and the command.
//
// Counters: in_well (share of frames that start within R of the pattern, not on it), bytes_per_texel (of
// what the effect stores).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "bench/relief.hpp"
#include "core/effects/effect_wells.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_flat.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/traversal.hpp"

namespace {

constexpr std::int32_t kW = ph::bench::kReliefWidth;
constexpr std::int32_t kH = ph::bench::kReliefHeight;

// The shared relief's fields, as a loader would hold them.
const ph::RegionFields& relief() {
  static const ph::RegionFields f = [] {
    ph::RegionFields fields;
    fields.gradient = ph::bench::relief_gradient();
    fields.depth = ph::bench::relief_depth();
    return fields;
  }();
  return f;
}

ph::WellsParams params(ph::WellPattern pattern, double radius) {
  ph::WellsParams p;  // defaults: 8 evenly spaced contour levels; light (-1, -1, 2), cos alpha 0.95
  p.pattern = pattern;
  p.radius_px = radius;
  return p;
}

void BM_MakeWells(benchmark::State& state, ph::WellPattern pattern, double radius) {
  const ph::WellsParams p = params(pattern, radius);
  std::size_t bytes = 0;
  for (auto _ : state) {
    ph::EffectPtr e = ph::make_wells_effect(relief(), kW, kH, p);
    bytes = e->bytes();
    benchmark::DoNotOptimize(e.get());
  }
  state.counters["bytes_per_texel"] = static_cast<double>(bytes) / (static_cast<double>(kW) * kH);
}

BENCHMARK_CAPTURE(BM_MakeWells, isophotes_R32, ph::WellPattern::isophotes, 32.0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MakeWells, isophotes_R64, ph::WellPattern::isophotes, 64.0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MakeWells, contours8_R32, ph::WellPattern::contours, 32.0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MakeWells, contours8_R64, ph::WellPattern::contours, 64.0)->Unit(benchmark::kMillisecond);

// 4096 motor displacements of 1-10 px in random directions (as bench_engine's typical stream).
const std::vector<ph::Vec2>& stream() {
  static const std::vector<ph::Vec2> s = [] {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
    std::uniform_real_distribution<double> len(1.0, 10.0);
    std::vector<ph::Vec2> v(4096);
    for (ph::Vec2& m : v) {
      const double a = angle(rng);
      m = ph::Vec2{std::cos(a), std::sin(a)} * len(rng);
    }
    return v;
  }();
  return s;
}

// The typical stream over the whole region, with or without contour wells (8 levels, R = 32) on top of
// the flat or the curvature method.
void BM_Frame(benchmark::State& state, bool curvature, bool wells) {
  ph::Region region;
  region.name = "relief";
  region.rect = {0, 0, kW, kH};
  region.fields = relief();
  region.method = curvature ? ph::MethodPtr(std::make_shared<ph::CurvatureMethod>(ph::CurvatureParams{}))
                            : ph::MethodPtr(std::make_shared<ph::FlatMethod>());
  ph::EffectPtr effect;
  if (wells) {
    effect = ph::make_wells_effect(region.fields, kW, kH, params(ph::WellPattern::contours, 32.0));
    region.effects.push_back(effect);
  }
  const ph::Scene scene({region});
  const ph::Vec2 centre{kW / 2.0 + 0.5, kH / 2.0 + 0.5};
  const std::vector<ph::Vec2>& s = stream();
  // The stream frame after frame; a cursor that leaves the region goes back to the centre.
  ph::CursorState cursor = ph::cursor_at(centre);
  std::size_t i = 0;
  auto frame = [&] {
    benchmark::DoNotOptimize(ph::advance(scene, cursor, s[i]));
    if (++i == s.size()) i = 0;
    if (!scene.owner(cursor.texel)) cursor = ph::cursor_at(centre);
  };
  if (effect) {
    // Untimed: the share of frames that start where the wells act.
    constexpr int kFrames = 100000;
    int in_well = 0;
    for (int n = 0; n < kFrames; ++n) {
      ph::EffectState unused;
      in_well += !(effect->apply({s[i], ph::kNoTime, cursor.position, cursor.texel}, unused) == s[i]);
      frame();
    }
    state.counters["in_well"] = static_cast<double>(in_well) / kFrames;
    cursor = ph::cursor_at(centre);
    i = 0;
  }
  for (auto _ : state) frame();
}

// apply() alone, at 4096 random cursor positions over the region (the effect's own per-frame cost).
void BM_Apply(benchmark::State& state) {
  const ph::EffectPtr e = ph::make_wells_effect(relief(), kW, kH, params(ph::WellPattern::contours, 32.0));
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> x(0.0, kW), y(0.0, kH);
  std::vector<ph::EffectInput> in(4096);
  const std::vector<ph::Vec2>& s = stream();
  for (std::size_t k = 0; k < in.size(); ++k) {
    const ph::Vec2 p{x(rng), y(rng)};
    in[k] = {s[k], ph::kNoTime, p, ph::texel_at(p)};
  }
  ph::EffectState unused;
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(e->apply(in[i], unused));
    if (++i == in.size()) i = 0;
  }
}
BENCHMARK(BM_Apply);

BENCHMARK_CAPTURE(BM_Frame, flat_none, false, false);
BENCHMARK_CAPTURE(BM_Frame, flat_wells, false, true);
BENCHMARK_CAPTURE(BM_Frame, curvature_none, true, false);
BENCHMARK_CAPTURE(BM_Frame, curvature_wells, true, true);

}  // namespace

BENCHMARK_MAIN();
