// What a load or reload costs, from the file to a region ready to walk: a 3840 x 2160 curvature region from a
// 16-bit normal PNG (load_scene, and its steps one by one), and a full-HD class map of the curvature materials
// (make_materials_effect from a normal map's gradient), and what the hybrid method derives at load for a full-HD
// region (prepare_hybrid_fields). docs/PERFORMANCE.md ("Load time") gives the figures and the command.
//
// The PNG is written once per run into a scratch folder (PH_BENCH_DIR, else the system's temporary folder).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include "bench/relief.hpp"
#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "core/effects/effect_materials.hpp"
#include "core/engine/decode.hpp"
#include "core/engine/field.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/lab/map_storage.hpp"

namespace {

namespace fs = std::filesystem;

constexpr std::int32_t kUhdW = 3840;
constexpr std::int32_t kUhdH = 2160;

// A 4K relief: the full-HD relief's bumps at twice the size, as normals.
ph::NormalImage uhd_normals() {
  ph::NormalImage normals(kUhdW, kUhdH);
  for (std::int32_t y = 0; y < kUhdH; ++y) {
    for (std::int32_t x = 0; x < kUhdW; ++x) {
      auto slope = [&](double cx, double cy, double s, double a) {
        const double dx = x - cx, dy = y - cy;
        const double e = a * std::exp(-(dx * dx + dy * dy) / (2.0 * s * s));
        return ph::Gradient{static_cast<float>(-dx / (s * s) * e), static_cast<float>(-dy / (s * s) * e)};
      };
      const ph::Gradient a = slope(960, 800, 300, 120), b = slope(2600, 1200, 440, 90), c = slope(1800, 500, 180, -70);
      normals.at(x, y) = ph::normal_from_gradient({a.x + b.x + c.x, a.y + b.y + c.y});
    }
  }
  return normals;
}

const fs::path& scratch() {
  static const fs::path dir = [] {
    const char* env = std::getenv("PH_BENCH_DIR");
    fs::path d = env != nullptr && *env != '\0' ? fs::path(env) : fs::temp_directory_path() / "ph-bench-load";
    fs::create_directories(d);
    ph::write_normal_png16(d / "uhd.normal.png", uhd_normals());
    const std::string scene = R"([[region]]
name = "uhd"
x = 0
y = 0
width = 3840
height = 2160
method = "curvature"
normal_map = "uhd.normal.png"
)";
    std::FILE* f = std::fopen((d / "uhd.toml").c_str(), "w");
    if (f == nullptr) std::abort();
    std::fputs(scene.c_str(), f);
    std::fclose(f);
    return d;
  }();
  return dir;
}

void report_texels(benchmark::State& state, std::int64_t texels) {
  state.counters["time_per_texel"] = benchmark::Counter(static_cast<double>(state.iterations()) * texels,
                                                        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The whole load, as the daemon's start and reload do it.
void BM_LoadCurvatureRegionUhd(benchmark::State& state) {
  const fs::path file = scratch() / "uhd.toml";
  ph::read_image(scratch() / "uhd.normal.png");  // the image module's first load is not a reload's cost
  for (auto _ : state) {
    const ph::Scene scene = ph::load_scene(ph::parse_scene_file(file));
    benchmark::DoNotOptimize(scene.regions().data());
  }
  report_texels(state, std::int64_t{kUhdW} * kUhdH);
}

// Its steps: the PNG read, the decoding (to normals, as a map of another size is, or straight to gradients).
void BM_ReadPngUhd(benchmark::State& state) {
  const fs::path png = scratch() / "uhd.normal.png";
  for (auto _ : state) {
    const ph::RawImage image = ph::read_image(png);
    benchmark::DoNotOptimize(image.pixels.data());
  }
  report_texels(state, std::int64_t{kUhdW} * kUhdH);
}

void BM_DecodeNormalsUhd(benchmark::State& state) {
  const ph::RawImage image = ph::read_image(scratch() / "uhd.normal.png");
  for (auto _ : state) {
    ph::DecodeReport report;
    const ph::NormalImage normals = ph::decode_normals(image, {}, report);
    benchmark::DoNotOptimize(normals.values.data());
  }
  report_texels(state, std::int64_t{kUhdW} * kUhdH);
}

// What a region of the map's own size does: straight to gradients.
void BM_DecodeNormalsToGradientUhd(benchmark::State& state) {
  const ph::RawImage image = ph::read_image(scratch() / "uhd.normal.png");
  for (auto _ : state) {
    ph::DecodeReport report;
    const ph::GradientField gradient = ph::decode_normals_to_gradient(image, {}, report);
    benchmark::DoNotOptimize(gradient.values.data());
  }
  report_texels(state, std::int64_t{kUhdW} * kUhdH);
}

// The class map of a full-HD region from a 16-bit normal map (radius 3) or depth map (radius 8).
void BM_ClassMapFullHd(benchmark::State& state) {
  ph::RegionFields fields;
  fields.gradient = ph::bench::relief_gradient();
  fields.depth = ph::bench::relief_depth();
  ph::MaterialsParams params;
  params.source = state.range(0) == 0 ? ph::ClassSource::normals : ph::ClassSource::depth;
  for (auto _ : state) {
    const ph::EffectPtr effect =
        ph::make_materials_effect(fields, ph::bench::kReliefWidth, ph::bench::kReliefHeight, params, 16);
    benchmark::DoNotOptimize(effect.get());
  }
  report_texels(state, std::int64_t{ph::bench::kReliefWidth} * ph::bench::kReliefHeight);
}

// A full-HD hybrid region's preparation (discontinuities, the normals' comparison with the heights, fusion,
// smoothing) from the shared relief's float heights and its normals as an 8-bit map (0), or as float normals with
// noise of sigma 0.02 (1: fused with the heights' slopes).
void BM_PrepareHybridFullHd(benchmark::State& state) {
  ph::RegionFields given;
  given.depth = ph::bench::relief_depth();
  ph::NormalImage normals(ph::bench::kReliefWidth, ph::bench::kReliefHeight);
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (std::size_t i = 0; i < normals.values.size(); ++i) {
    ph::Gradient g = ph::bench::relief_gradient().values[i];
    if (state.range(0) == 1) g = {static_cast<float>(g.x + noise(rng)), static_cast<float>(g.y + noise(rng))};
    normals.values[i] = ph::normal_from_gradient(g);
  }
  ph::DecodeReport report;
  given.gradient = ph::gradient_from_normals(ph::stored_normals(normals, state.range(0) == 0 ? 255 : 0, &report));
  given.gradient_rounding = ph::gradient_rounding_of_normals(report.value_step);
  for (auto _ : state) {
    state.PauseTiming();
    ph::RegionFields fields = given;
    state.ResumeTiming();
    ph::prepare_hybrid_fields(ph::HybridParams{}, fields);
    benchmark::DoNotOptimize(fields.gradient->values.data());
  }
  report_texels(state, std::int64_t{ph::bench::kReliefWidth} * ph::bench::kReliefHeight);
}

}  // namespace

BENCHMARK(BM_LoadCurvatureRegionUhd)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadPngUhd)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DecodeNormalsUhd)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeNormalsToGradientUhd)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClassMapFullHd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PrepareHybridFullHd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
