// `pseudohaptic surfaces`: the analytic test surfaces of the second paper as files (core/lab/surfaces.hpp).
#include <fmt/core.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "config/image_io.hpp"
#include "core/lab/surfaces.hpp"
#include "tools/commands.hpp"

namespace ph::tools {
namespace {

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": cannot write the file");
}

// A double as a TOML float: shortest round-trip form, with ".0" added where it would read as an integer.
std::string toml_float(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eE") == std::string::npos) text += ".0";
  return text;
}

// v = (h / relief + 1) / 2, so the scene reads h = (v - 0.5) * 2 relief.
std::string scene_text(const SurfaceSpec& spec) {
  return fmt::format(
      "# pseudohaptic scene: the {name} of the second paper's test surfaces ({cls}), {size} x {size} px\n"
      "[[region]]\n"
      "name = \"{name}\"\n"
      "x = 0\n"
      "y = 0\n"
      "width = {size}\n"
      "height = {size}\n"
      "method = \"curvature\"\n"
      "normal_map = \"{name}.normal.png\"\n"
      "normal_green = \"opengl\"\n"
      "depth_map = \"{name}.depth.png\"\n"
      "depth_zero = 0.5\n"
      "relief_px = {relief}   # heights within +-{half} px\n",
      fmt::arg("name", spec.name()), fmt::arg("cls", class_name(surface_class(spec.kind))), fmt::arg("size", spec.size),
      fmt::arg("relief", toml_float(2.0 * spec.relief_px())), fmt::arg("half", spec.relief_px()));
}

void write_surface(const std::filesystem::path& outdir, const SurfaceSpec& spec) {
  const std::string name = spec.name();
  write_normal_png16(outdir / (name + ".normal.png"), surface_normal_image(spec));
  DepthField depth = surface_depth_field(spec);
  for (float& v : depth.values) v = static_cast<float>((v / spec.relief_px() + 1.0) / 2.0);
  write_gray_png16(outdir / (name + ".depth.png"), depth);
  write_float_exr(outdir / (name + ".K.exr"), surface_curvature_fields(spec).gaussian);
  // The scene goes last: an interrupted run leaves no scene file naming a map that was not written.
  write_text_file(outdir / (name + ".toml"), scene_text(spec));
}

}  // namespace

Run add_surfaces_command(CLI::App& app) {
  auto outdir = std::make_shared<std::string>();
  auto size = std::make_shared<std::int32_t>(512);
  app.add_option("OUTDIR", *outdir, "Folder to write into (created if needed); existing files are overwritten")
      ->required();
  app.add_option("--size", *size, "Side of each square surface, px")->check(CLI::Range(8, 8192))->capture_default_str();
  app.footer(
      "For each surface NAME (plane, cylinder, cone, paraboloid, ellipsoid, sphere, hyperboloid, simple-saddle,\n"
      "monkey-saddle) writes NAME.normal.png (16-bit, exact analytic normals, OpenGL green), NAME.depth.png\n"
      "(16-bit, v = (h / relief + 1) / 2 with relief = size / 8 px), NAME.K.exr (exact Gaussian curvature,\n"
      "1/px^2, 32-bit float) and NAME.toml, a one-region scene that uses both maps. Lengths scale with the\n"
      "size; heights stay within +-size/8 px. See docs/INTERROGATION.md.");
  return [outdir, size] {
    std::filesystem::create_directories(*outdir);
    const auto surfaces = all_surfaces(*size);
    std::size_t done = 0;
    for (const SurfaceSpec& spec : surfaces) {
      write_surface(*outdir, spec);
      fmt::print(stderr, "\r[{}/{}] {:<16}", ++done, surfaces.size(), spec.name());
    }
    fmt::print(stderr, "\n");
    fmt::print("wrote {} surfaces to {}\n", surfaces.size(), *outdir);
    return 0;
  };
}

}  // namespace ph::tools
