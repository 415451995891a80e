// `pseudohaptic surfaces`: the analytic test surfaces of the second paper as files (core/lab/surfaces.hpp).
#include <fmt/core.h>

#include <filesystem>
#include <memory>

#include "config/image_io.hpp"
#include "config/map_pair_scene.hpp"
#include "config/staged_write.hpp"
#include "core/lab/surfaces.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/progress_line.hpp"

namespace ph::tools {
namespace {

void write_surface(const std::filesystem::path& outdir, const SurfaceSpec& spec) {
  const std::string name = spec.name();
  write_staged(outdir / (name + ".K.exr"),
               [&](const auto& path) { write_float_exr(path, surface_curvature_fields(spec).gaussian); });
  const MapPairScene scene{
      name, spec.size, spec.relief_px(),
      fmt::format("# pseudohaptic scene: the {} of the second paper's test surfaces ({}), {} x {} px\n", name,
                  class_name(surface_class(spec.kind)), spec.size, spec.size),
      fmt::format("heights within +-{} px", spec.relief_px())};
  write_map_pair_files(outdir, scene, surface_normal_image(spec), surface_depth_field(spec));
}

}  // namespace

Run add_surfaces_command(CLI::App& app) {
  auto outdir = std::make_shared<std::string>();
  auto size = std::make_shared<std::int32_t>(512);
  app.add_option("OUTDIR", *outdir, "Folder to write into (created if needed); existing files are overwritten")
      ->required()
      ->check(non_empty_path());
  app.add_option("--size", *size, "Side of each square surface, px")
      ->transform(whole_number(8, 8192))
      ->capture_default_str();
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
    ProgressLine progress;
    for (const SurfaceSpec& spec : surfaces) {
      write_surface(*outdir, spec);
      progress.show(fmt::format("[{}/{}] {}", ++done, surfaces.size(), spec.name()));
    }
    progress.finish();
    fmt::print("wrote {} surfaces to {}\n", surfaces.size(), *outdir);
    return 0;
  };
}

}  // namespace ph::tools
