// `pseudohaptic inspect`: what the surface-interrogation methods see in a normal or depth map, as false-colour
// pictures (docs/INTERROGATION.md).
#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config/field_loader.hpp"
#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "core/effects/curvature_class.hpp"
#include "core/effects/curvature_field.hpp"
#include "core/effects/patterns.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/finite_check.hpp"
#include "tools/map_flags.hpp"
#include "tools/number_tuple.hpp"
#include "tools/output_folder.hpp"
#include "tools/progress_line.hpp"

namespace ph::tools {
namespace {

using Rgb = std::array<std::uint8_t, 3>;

struct InspectOptions {
  std::string outdir, normal_map, depth_map;
  std::string from;
  MapFlags maps;  // how to decode the maps
  std::vector<std::int32_t> size;
  std::optional<std::int32_t> radius;
  std::optional<double> planar_curvedness, parabolic_ratio;
  std::vector<double> light;
  std::optional<double> cos_alpha;
  std::optional<std::int32_t> contours;
};

// Fixed class colours, indexed by CurvatureClass.
constexpr std::array<Rgb, 4> kClassColours = {{{200, 200, 200}, {240, 190, 40}, {215, 48, 39}, {69, 117, 180}}};

// Blue (negative), white (0), red (positive); t in [-1, 1].
Rgb diverging(double t) {
  const Rgb end = t < 0 ? Rgb{59, 76, 192} : Rgb{180, 4, 38};
  const double a = std::min(std::abs(t), 1.0);
  Rgb out;
  for (int i = 0; i < 3; ++i) out[i] = static_cast<std::uint8_t>(std::lround(255.0 + a * (end[i] - 255.0)));
  return out;
}

// The 99th percentile of |v|: a robust scale that a few spikes (steps, walls) cannot flatten into white. 0 where
// (nearly) every value is 0: the floor the caller gives then sets the scale.
double robust_scale(const Grid<float>& values) {
  std::vector<float> magnitudes;
  magnitudes.reserve(values.values.size());
  for (float v : values.values) magnitudes.push_back(std::abs(v));
  if (magnitudes.empty()) return 0.0;
  const std::size_t k = std::min(magnitudes.size() - 1, magnitudes.size() * 99 / 100);
  std::nth_element(magnitudes.begin(), magnitudes.begin() + k, magnitudes.end());
  return magnitudes[k];
}

template <typename T, typename F>
void write_picture(const std::filesystem::path& path, const Grid<T>& grid, F colour) {
  std::vector<std::uint8_t> rgb;
  rgb.reserve(grid.values.size() * 3);
  for (const T& v : grid.values) {
    const Rgb c = colour(v);
    rgb.insert(rgb.end(), c.begin(), c.end());
  }
  write_rgb_png8(path, grid.width, grid.height, rgb);
}

// `floor`: the scale at least, so that a surface whose values are rounding noise (a plane's H, a cylinder's K) comes
// out white, not painted in full colour as if it were curved. With a floor of 0 (--planar-curvedness 0) over values
// nearly all 0, the largest |value| is the scale, so that the few others show; 0 where every value is 0 (all white).
double write_diverging(const std::filesystem::path& path, const Grid<float>& values, double floor) {
  double scale = std::max(robust_scale(values), floor);
  if (scale <= 0.0) {
    for (float v : values.values) scale = std::max(scale, static_cast<double>(std::abs(v)));
  }
  const double divisor = scale > 0.0 ? scale : 1.0;
  write_picture(path, values, [&](float v) { return diverging(v / divisor); });
  return scale;
}

// The legend's words for a diverging picture whose values were all 0: no colour at all.
constexpr std::string_view kAllZero = "0 everywhere (all white)";

void write_mask(const std::filesystem::path& path, const Grid<std::uint8_t>& mask) {
  write_picture(path, mask, [](std::uint8_t m) { return m ? Rgb{0, 0, 0} : Rgb{255, 255, 255}; });
}

// Everything inspect writes, computed before any of it is: an option that the computation refuses (a light of no
// length) must not leave a folder of some of the pictures, from this run, beside older ones.
struct InspectPictures {
  std::int32_t width = 0, height = 0;
  int bits = 8;
  DerivativeFilter filter;
  ClassTolerances tolerances;
  CurvatureFields curvature;
  Grid<std::uint8_t> classes, isophotes;
  std::optional<Grid<std::uint8_t>> contours;  // with a depth map
};

// `stage` is told what each step does, for a progress line: a large texture takes seconds a step.
InspectPictures compute_pictures(const InspectOptions& o, const FieldSources& sources, const ImageSize& image,
                                 bool from_depth, FieldLoadReport& report,
                                 const std::function<void(const std::string&)>& stage) {
  InspectPictures p;
  p.width = o.size.size() == 2 ? o.size[0] : image.width;
  p.height = o.size.size() == 2 ? o.size[1] : image.height;
  stage(fmt::format("reading the maps ({}x{} texels)", p.width, p.height));
  const RegionFields fields = load_region_fields(sources, p.width, p.height, {true, !o.depth_map.empty()}, report);

  p.bits = image.code_max == 255 ? 8 : 16;
  p.filter = o.radius ? DerivativeFilter{*o.radius} : DerivativeFilter::recommended(from_depth, p.bits);
  p.tolerances = ClassTolerances::recommended(p.bits);
  if (o.planar_curvedness) p.tolerances.planar_curvedness = *o.planar_curvedness;
  if (o.parabolic_ratio) p.tolerances.parabolic_ratio = *o.parabolic_ratio;
  stage(fmt::format("curvature (filter radius {})", p.filter.radius));
  p.curvature =
      from_depth ? curvature_from_depth(*fields.depth, p.filter) : curvature_from_gradient(*fields.gradient, p.filter);
  stage("classes and isophotes");
  p.classes = class_map(p.curvature, p.tolerances);
  IsophoteParams isophotes;
  if (o.light.size() == 3) isophotes.light = {o.light[0], o.light[1], o.light[2]};
  if (o.cos_alpha) isophotes.cos_alpha = *o.cos_alpha;
  p.isophotes = isophote_mask(*fields.gradient, isophotes);
  if (fields.depth) {
    stage("contours");
    ContourParams contours;
    if (o.contours) contours.count = *o.contours;
    p.contours = contour_mask(*fields.depth, contours);
  }
  return p;
}

int run_inspect(const InspectOptions& o) {
  if (o.normal_map.empty() && o.depth_map.empty()) throw std::invalid_argument("give --normal-map or --depth-map");
  const bool from_depth = o.from.empty() ? o.normal_map.empty() : o.from == "depth";
  if (from_depth && o.depth_map.empty()) throw std::invalid_argument("--from depth needs --depth-map");
  if (!from_depth && o.normal_map.empty()) throw std::invalid_argument("--from normal needs --normal-map");
  check_map_flags_have_their_map(o.maps, !o.normal_map.empty(), !o.depth_map.empty());
  if (o.contours && o.depth_map.empty())
    throw std::invalid_argument("--contours sets the contours of a depth map: give --depth-map, or leave it out");
  if (o.light.size() == 3 && !(light_length({o.light[0], o.light[1], o.light[2]}) > 0.0))
    throw CLI::ValidationError("--light", "must not be 0,0,0: give the direction toward the light");

  // Decoded as `trace` and the daemon decode them (config/field_loader).
  FieldSources sources;
  if (!o.normal_map.empty()) sources.normal_map = o.normal_map;
  if (!o.depth_map.empty()) sources.depth_map = o.depth_map;
  apply_map_flags(o.maps, sources);
  const ImageSize image = read_image_size(from_depth ? o.depth_map : o.normal_map);
  const std::int64_t texels =
      o.size.size() == 2 ? std::int64_t{o.size[0]} * o.size[1] : std::int64_t{image.width} * image.height;
  if (texels > kMaxRegionTexels) {
    throw std::invalid_argument(
        fmt::format("{} px are more than the {} (8192 x 8192) a region may have: give a "
                    "smaller --size",
                    texels, kMaxRegionTexels));
  }
  // Before the pictures are computed (a minute for a large texture): a folder that cannot take them fails now.
  prepare_output_folder(o.outdir, {"K.png", "H.png", "class.png", "isophotes.png", "contours.png"});
  FieldLoadReport report;
  // On a terminal only: where standard error is a file the legend and the warnings say what was done.
  ProgressLine progress;
  const auto stage = [&progress](const std::string& what) {
    if (progress.in_place()) progress.show("inspect: " + what);
  };
  // Erased before anything else is said, an error included.
  const std::unique_ptr<ProgressLine, void (*)(ProgressLine*)> erase_progress(
      &progress, [](ProgressLine* line) { line->finish(true); });
  const InspectPictures p = compute_pictures(o, sources, image, from_depth, report, stage);
  stage("writing the pictures");

  const std::filesystem::path out = o.outdir;
  std::filesystem::create_directories(out);
  // Replaced together once all are written (seconds for a large texture): an interrupted run leaves the last run's
  // pictures, not some of this one's beside them (tools/output_folder.hpp).
  OutputSet files(out);
  // What the classes call planar sets the floors: a curvedness of planar_curvedness, and its square for K.
  const double planar = p.tolerances.planar_curvedness;
  const double k_scale = write_diverging(files.stage("K.png"), p.curvature.gaussian, planar * planar);
  const double h_scale = write_diverging(files.stage("H.png"), p.curvature.mean, planar);
  write_picture(files.stage("class.png"), p.classes, [](std::uint8_t c) { return kClassColours[c & 3]; });
  write_mask(files.stage("isophotes.png"), p.isophotes);
  if (p.contours) write_mask(files.stage("contours.png"), *p.contours);
  files.commit();
  // Not one of this run's pictures: an older run's, with a depth map, would read as this texture's contours.
  if (!p.contours) std::filesystem::remove(out / "contours.png");
  progress.finish(true);

  fmt::print("{} x {} texels, curvature from the {} map ({}-bit), filter radius {}\n", p.width, p.height,
             from_depth ? "depth" : "normal", image.code_max == 0 ? 32 : p.bits, p.filter.radius);
  fmt::print("K.png: K in 1/px^2, {}\n",
             k_scale > 0.0 ? fmt::format("blue < 0 < red, full colour at +-{:.4g} (99th percentile of |K|, at least "
                                         "the planar curvedness squared)",
                                         k_scale)
                           : std::string(kAllZero));
  fmt::print("H.png: H in 1/px, {}\n",
             h_scale > 0.0 ? fmt::format("blue < 0 < red (a bump is blue), full colour at +-{:.4g}", h_scale)
                           : std::string(kAllZero));
  fmt::print("class.png: planar below curvedness {:g} /px, parabolic below |k_small|/|k_large| {:g}\n",
             p.tolerances.planar_curvedness, p.tolerances.parabolic_ratio);
  std::array<std::size_t, 4> counts{};
  for (std::uint8_t c : p.classes.values) ++counts[c & 3];
  for (std::uint8_t c = 0; c < 4; ++c) {
    const Rgb rgb = kClassColours[c];
    fmt::print("  {:<10} #{:02x}{:02x}{:02x} {:6.2f}%\n", class_name(static_cast<CurvatureClass>(c)), rgb[0], rgb[1],
               rgb[2], 100.0 * counts[c] / std::max<std::size_t>(p.classes.values.size(), 1));
  }
  fmt::print("isophotes.png{}: pattern texels black\n", p.contours ? ", contours.png" : "");
  // As `trace` and the daemon warn: invalid texels (repaired), and a --size out of the maps' proportion.
  for (const std::string& note : map_notes(sources, report, p.width, p.height))
    fmt::print(stderr, "pseudohaptic: warning: {}\n", note);
  return 0;
}

}  // namespace

Run add_inspect_command(CLI::App& app) {
  auto o = std::make_shared<InspectOptions>();
  app.description(
      "Write what the surface-interrogation methods see in a texture as false-colour PNGs into OUTDIR:\n"
      "K.png (Gaussian curvature), H.png (mean curvature), class.png (planar / parabolic / elliptic /\n"
      "hyperbolic; the legend goes to standard output), isophotes.png and, with a depth map, contours.png.");
  app.add_option("OUTDIR", o->outdir,
                 "Folder to write into (created if needed); the pictures of these names there are replaced, and "
                 "a contours.png an earlier run left is removed when this run has no depth map")
      ->required()
      ->check(non_empty_path());
  app.add_option("--normal-map", o->normal_map, "Normal map image (PNG, TIFF, EXR)")->check(non_empty_path());
  app.add_option("--depth-map", o->depth_map, "Depth map image (one channel)")->check(non_empty_path());
  app.add_option("--from", o->from, "Curvature from the normal or the depth map (default: normal when given)")
      ->check(CLI::IsMember({"normal", "depth"}));
  add_map_flags(app, o->maps);
  add_number_tuple(app, "--size", o->size, "W,H",
                   "Region size in px the maps are resampled to (default: the image's size)",
                   {CLI::Range(1, kMaxRegionSide)});  // a region's largest
  app.add_option("--radius", o->radius,
                 "Derivative filter radius r, a (2r+1)^2 least-squares window (default: 3 for 16-bit normal maps, "
                 "8 for 16-bit depth maps, 16 for 8-bit maps)")
      ->transform(whole_number(1, 256));
  app.add_option("--planar-curvedness", o->planar_curvedness,
                 "Planar below this curvedness, 1/px (default 5e-5; 1e-4 for 8-bit maps)")
      ->check(finite_number())
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--parabolic-ratio", o->parabolic_ratio,
                 "Parabolic below this |k_small|/|k_large| (default 0.1; 0.25 for 8-bit maps)")
      ->check(finite_number())
      ->check(CLI::Range(0.0, 1.0));
  add_number_tuple(app, "--light", o->light, "X,Y,Z", "Light direction for isophotes (default -1,-1,2: top left)",
                   {finite_number()});
  app.add_option("--cos-alpha", o->cos_alpha, "Isophote value n.l (default 0.95)")
      ->check(finite_number())
      ->check(CLI::Range(-1.0, 1.0));
  app.add_option("--contours", o->contours, "Number of evenly spaced contour levels (default 8)")
      ->transform(whole_number(0, 4096));
  return [o] { return run_inspect(*o); };
}

}  // namespace ph::tools
