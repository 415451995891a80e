// Cost of recomputing a region's gravity-well data when the light, the levels or a tolerance change on
// reload (core/effects/patterns.hpp, core/effects/distance_transform.hpp), for a full-HD region. docs/PERFORMANCE.md
// ("Surface interrogation: pattern fields") gives the figures and the command.
//
// Counters: time_per_texel (CPU seconds per texel, printed with an SI prefix), pattern_fraction (share of
// texels in the mask), bytes_per_texel (of the stored nearest-pattern field).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

#include "bench/relief.hpp"
#include "core/effects/distance_transform.hpp"
#include "core/effects/patterns.hpp"
#include "core/engine/field.hpp"

namespace {

constexpr std::int32_t kW = ph::bench::kReliefWidth;
constexpr std::int32_t kH = ph::bench::kReliefHeight;
constexpr float kRadius = 64.0f;  // a generous radius of influence, px

const ph::DepthField& relief() { return ph::bench::relief_depth(); }
const ph::GradientField& relief_gradient() { return ph::bench::relief_gradient(); }

ph::Grid<std::uint8_t> random_mask(double density) {
  std::mt19937 rng(42);
  std::bernoulli_distribution set(density);
  ph::Grid<std::uint8_t> m(kW, kH, 0);
  for (auto& v : m.values) v = set(rng) ? 1 : 0;
  return m;
}

const ph::Grid<std::uint8_t>& sparse_mask() {
  static const auto m = random_mask(0.001);
  return m;
}
const ph::Grid<std::uint8_t>& dense_mask() {
  static const auto m = random_mask(0.5);
  return m;
}
const ph::Grid<std::uint8_t>& contour_mask() {
  static const auto m = ph::contour_mask(relief(), ph::ContourParams{});
  return m;
}

double fraction(const ph::Grid<std::uint8_t>& m) {
  std::size_t n = 0;
  for (auto v : m.values) n += v != 0;
  return static_cast<double>(n) / static_cast<double>(m.values.size());
}

void report(benchmark::State& state, double pattern_fraction, bool stores_field) {
  state.counters["time_per_texel"] = benchmark::Counter(static_cast<double>(state.iterations()) * kW * kH,
                                                        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["pattern_fraction"] = pattern_fraction;
  state.counters["bytes_per_texel"] = stores_field ? static_cast<double>(sizeof(ph::PatternOffset)) : 1.0;
}

void edt(benchmark::State& state, const ph::Grid<std::uint8_t>& mask, float radius) {
  for (auto _ : state) {
    ph::PatternField f = ph::make_pattern_field(mask, radius);
    benchmark::DoNotOptimize(f.offsets.values.data());
  }
  report(state, fraction(mask), true);
}

void BM_EdtSparse(benchmark::State& state) { edt(state, sparse_mask(), ph::kMaxPatternRadius); }
void BM_EdtSparseR64(benchmark::State& state) { edt(state, sparse_mask(), kRadius); }
void BM_EdtDense(benchmark::State& state) { edt(state, dense_mask(), ph::kMaxPatternRadius); }
void BM_EdtContourMask(benchmark::State& state) { edt(state, contour_mask(), ph::kMaxPatternRadius); }
void BM_EdtContourMaskR64(benchmark::State& state) { edt(state, contour_mask(), kRadius); }

void BM_IsophoteMask(benchmark::State& state) {
  const ph::IsophoteParams params;
  for (auto _ : state) {
    ph::Grid<std::uint8_t> m = ph::isophote_mask(relief_gradient(), params);
    benchmark::DoNotOptimize(m.values.data());
  }
  // Counted outside the timed loop, as BM_ContourMask does (a count of the 2 M texels is about 4 % of the mask).
  report(state, fraction(ph::isophote_mask(relief_gradient(), params)), false);
}

void BM_ContourMask(benchmark::State& state) {
  const ph::ContourParams params;  // 8 evenly spaced levels, crossing rule
  for (auto _ : state) {
    ph::Grid<std::uint8_t> m = ph::contour_mask(relief(), params);
    benchmark::DoNotOptimize(m.values.data());
  }
  report(state, fraction(contour_mask()), false);
}

// Everything a reload redoes for one region: the mask from the stored field, then its EDT.
void BM_RecomputeIsophote(benchmark::State& state) {
  const ph::IsophoteParams params;
  for (auto _ : state) {
    ph::PatternField f = ph::isophote_field(relief_gradient(), params, kRadius);
    benchmark::DoNotOptimize(f.offsets.values.data());
  }
  report(state, fraction(ph::isophote_mask(relief_gradient(), params)), true);
}

void BM_RecomputeContour(benchmark::State& state) {
  const ph::ContourParams params;
  for (auto _ : state) {
    ph::PatternField f = ph::contour_field(relief(), params, kRadius);
    benchmark::DoNotOptimize(f.offsets.values.data());
  }
  report(state, fraction(contour_mask()), true);
}

}  // namespace

BENCHMARK(BM_EdtSparse)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EdtSparseR64)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EdtDense)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EdtContourMask)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EdtContourMaskR64)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IsophoteMask)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ContourMask)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RecomputeIsophote)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RecomputeContour)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
