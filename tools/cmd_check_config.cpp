// `pseudohaptic check-config`: reads a scene file as the daemon would, images included, and summarises it.
#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/desktop_geometry.hpp"
#include "config/field_loader.hpp"
#include "config/image_child.hpp"
#include "config/scene_file.hpp"
#include "core/engine/decode.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/method_hybrid.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"

namespace ph::tools {

namespace {

struct CheckConfigOptions {
  std::string file{kDefaultSceneFile};
  bool quiet = false;
  const CLI::Option* file_option = nullptr;  // to tell FILE given from the default
};

// What the hybrid method found at load (docs/METHODS.md, "Hybrid"): the texels that take the depth C/D, which
// `discontinuity_px` tunes.
std::string steps_line(const RegionFields& fields) {
  if (!fields.depth) return "none can be found without a depth map";
  const std::vector<std::uint8_t>& marks = fields.discontinuity->values;
  const auto marked =
      static_cast<std::size_t>(std::count_if(marks.begin(), marks.end(), [](auto m) { return m != 0; }));
  const double share = marks.empty() ? 0.0 : 100.0 * static_cast<double>(marked) / static_cast<double>(marks.size());
  return fmt::format("{} texels ({:.2f} %) take the depth C/D at height steps the normals do not explain", marked,
                     share);
}

// Whether the hybrid method read a generator's normals again from the depth map's finer heights: their rounding is
// then below the normal map's own.
bool read_again_from_heights(const RegionFields& fields, const FieldLoadReport& report) {
  return report.normals.texels > 0 && fields.gradient_rounding > 0.0 &&
         fields.gradient_rounding < gradient_rounding_of_normals(report.normals.value_step);
}

// How the hybrid method smooths the normals: within the rounding the map's storage leaves, none for a float map; a
// rounding below the normal map's own says that it read a generator's normals again from finer heights.
std::string rounding_line(const RegionFields& fields, const FieldLoadReport& report, double noise_slope) {
  if (fields.gradient_rounding <= 0.0) return "none (a float map): the normals are used as given";
  if (noise_slope <= 0.0) {
    return fmt::format("slope sigma {:.2g} from the map's storage: noise_slope = 0 keeps the normals as given",
                       fields.gradient_rounding);
  }
  const std::size_t texels = fields.gradient ? fields.gradient->values.size() : 0;
  auto percent = [texels](std::size_t n) { return texels == 0 ? 0.0 : 100.0 * n / static_cast<double>(texels); };
  const std::string smoothed =
      fmt::format("smoothed within it ({:.1f} % of the texels; at {:.1f} % the smoothing's flattening taken off again)",
                  percent(fields.smoothed_texels), percent(fields.unflattened_texels));
  if (read_again_from_heights(fields, report)) {
    return fmt::format(
        "slope sigma {:.2g}: the normals are a generator's reading of the depth map's heights, which are stored "
        "finer, so they are read again from them (normal map's own: {:.2g}) and {}",
        fields.gradient_rounding, gradient_rounding_of_normals(report.normals.value_step), smoothed);
  }
  return fmt::format("slope sigma {:.2g} from the map's storage: the normals are {}", fields.gradient_rounding,
                     smoothed);
}

// Whether the hybrid method pulled the normals toward the depth map's slopes (docs/METHODS.md, "Hybrid"), which
// `noise_slope` bounds, and if not, why not. The disagreement it weighs is a robust sigma over the region: a
// disagreement of scale on a relief that is flat over most of the region does not count, and the scale line says it.
std::string fusion_line(const RegionFields& fields, const FieldLoadReport& report, double noise_slope) {
  if (!fields.depth) return "none without a depth map";
  if (noise_slope <= 0.0) return "none: noise_slope = 0 keeps the normals as given";
  if (read_again_from_heights(fields, report)) return "none: the normals were read again from the heights (above)";
  if (!fields.fused_normals_weight) {
    return "none: over most of the region the depth map's slopes explain the normals within their rounding and "
           "noise_slope";
  }
  return fmt::format(
      "the normals are pulled toward the depth map's slopes where they disagree by noise (their weight {:.2g})",
      *fields.fused_normals_weight);
}

// Whether the region's normal map and depth map hold the relief at one scale, as the hybrid method compares them.
std::string scale_line(const RegionSpec& region, const RegionFields& fields) {
  const std::optional<ReliefScale> scale = relief_scale(region, fields);
  if (!scale) return "too little resolved slope to compare the normal map's slopes with the depth map's";
  return scale->described();
}

// A map the region names: its own size and what became of it (resampled, stretched), or that the region's method and
// effects do not read it.
std::string map_line(const DecodeReport& map, const RegionSpec& region) {
  const std::string size = map_size_description(map, region.rect.w, region.rect.h);
  return size.empty() ? "not read: neither the method nor an effect uses it" : size;
}

// The [daemon] table's settings, as the daemon takes them.
void append_daemon(fmt::memory_buffer& out, const DaemonSettings& d) {
  const auto to = std::back_inserter(out);
  std::string devices;
  for (const DeviceMatch& m : d.devices) devices += (devices.empty() ? "" : ", ") + format_device_match(m);
  fmt::format_to(to, "daemon:\n");
  fmt::format_to(to, "  devices: {}\n", devices.empty() ? std::string("any pointer") : devices);
  fmt::format_to(to, "  output: {}\n", d.output == OutputMode::absolute ? "absolute" : "relative");
  if (d.desktop) {
    fmt::format_to(to, "  desktop: {},{} {}x{} px\n", d.desktop->x, d.desktop->y, d.desktop->w, d.desktop->h);
  } else {
    fmt::format_to(to, "  desktop: auto\n");
  }
  const AccelSettings accel = acceleration_of(d);
  // The resolution counts for the adaptive profile alone (the flat one scales the mice's own counts).
  fmt::format_to(to, "  acceleration: {} (speed {}{}){}\n", accel_profile_name(accel.profile), accel.speed,
                 accel.profile == AccelProfile::adaptive ? fmt::format(", {} dpi", accel.dpi) : std::string(),
                 d.acceleration ? "" : " by default for this output");
  fmt::format_to(to, "  pointer_speed: {}\n", d.pointer_speed);
  fmt::format_to(to, "  engine: {}\n", label_of(d.engine));
}

std::string summary(const SceneSpec& spec, const Scene& scene, const SceneLoadReport& report) {
  fmt::memory_buffer out;
  const auto to = std::back_inserter(out);
  fmt::format_to(to, "{}: ok\n", spec.file.string());
  append_daemon(out, spec.daemon);
  fmt::format_to(to, "regions: {}\n", spec.regions.size());
  for (std::size_t i = 0; i < spec.regions.size(); ++i) {
    const RegionSpec& r = spec.regions[i];
    const FieldLoadReport& fr = report.regions.at(i);
    const Region& region = scene.regions().at(i);
    std::string effects;
    std::size_t bytes = region.fields.bytes();
    for (const EffectPtr& effect : region.effects) {
      effects += fmt::format(" + {}", effect->name());
      bytes += effect->bytes();
    }
    fmt::format_to(to, "  [{}] '{}': {},{} {}x{} px, {}{}, {} bytes, {} invalid texels repaired\n", i, r.name, r.rect.x,
                   r.rect.y, r.rect.w, r.rect.h, r.method, effects, bytes,
                   fr.normals.invalid_texels + fr.depth.invalid_texels);
    if (r.sources.normal_map) fmt::format_to(to, "      normal map: {}\n", map_line(fr.normals, r));
    if (r.sources.depth_map) fmt::format_to(to, "      depth map: {}\n", map_line(fr.depth, r));
    if (i < report.variants.size()) fmt::format_to(to, "      traversal: {}\n", report.variants[i]);
    if (region.fields.discontinuity) {
      fmt::format_to(to, "      steps: {}\n", steps_line(region.fields));
      const double noise_slope = method_params<HybridMethod>(r).noise_slope;
      fmt::format_to(to, "      rounding: {}\n", rounding_line(region.fields, fr, noise_slope));
      fmt::format_to(to, "      fusion: {}\n", fusion_line(region.fields, fr, noise_slope));
      if (r.sources.normal_map && r.sources.depth_map)
        fmt::format_to(to, "      scale: {}\n", scale_line(r, region.fields));
    }
  }
  return fmt::to_string(out);
}

// Without a scene file at the default path the daemon runs its embedded default scene (daemon/configuration.cpp):
// not an error, so said as what the daemon will do.
std::string default_scene_summary(const std::string& file) {
  fmt::memory_buffer out;
  const auto to = std::back_inserter(out);
  // Laid out as the daemon would lay it out here at start: on the connected displays (the session helper's layout
  // lays it out again).
  std::string no_display;
  const Rect desktop = resolve_desktop(std::nullopt, kDrmDir, no_display);
  fmt::format_to(to,
                 "{}: no such file, so pseudohapticd runs its embedded default scene (three targets of the curvature "
                 "paper in the middle of the desktop; see pseudohapticd(8)) with the [daemon] table's defaults\n",
                 file);
  append_daemon(out, DaemonSettings{});
  fmt::format_to(to, "laid out for: {},{} {}x{} px ({}; the session helper's layout lays it out again)\n", desktop.x,
                 desktop.y, desktop.w, desktop.h,
                 no_display.empty() ? "the connected displays side by side" : "no connected display found here");
  const Scene scene = default_scene(desktop);
  fmt::format_to(to, "regions: {}\n", scene.regions().size());
  for (std::size_t i = 0; i < scene.regions().size(); ++i) {
    const Region& r = scene.regions()[i];
    fmt::format_to(to, "  [{}] '{}': {},{} {}x{} px, {}, {} bytes\n", i, r.name, r.rect.x, r.rect.y, r.rect.w, r.rect.h,
                   r.method->name(), r.fields.bytes());
  }
  return fmt::to_string(out);
}

void write_stdout(const std::string& text) {
  if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() || std::fflush(stdout) != 0)
    throw std::runtime_error("<stdout>: write failed");
}

int run_check_config(const CheckConfigOptions& o) {
  if (o.file_option->count() == 0 && scene_file_absent(o.file)) {
    if (!o.quiet) write_stdout(default_scene_summary(o.file));
    return 0;
  }
  const SceneSpec spec = parse_scene_file(o.file);
  SceneLoadReport report;
  // The images are read as the daemon reads them, in its image reader (config/image_child.hpp), under the same
  // limits: a region the reader has no memory or time for fails here as it would fail in the service.
  ImageChild images;
  const Scene scene = load_scene(spec, &report, &images);
  // What the daemon logs as warnings at load, before the summary; with --quiet too (a script that checks a file for
  // the service must hear that the service cannot read an image).
  std::vector<std::string> warnings = load_warnings(spec, report, scene);
  for (std::string& w : desktop_warnings(spec)) warnings.push_back(std::move(w));
  for (std::string& w : service_path_warnings(spec)) warnings.push_back(std::move(w));
  for (const std::string& w : warnings) fmt::print(stderr, "pseudohaptic: warning: {}\n", w);
  if (!o.quiet) write_stdout(summary(spec, scene, report));
  return 0;
}

}  // namespace

Run add_check_config_command(CLI::App& app) {
  auto o = std::make_shared<CheckConfigOptions>();
  app.description(
      "Read a scene file as the daemon would: the [daemon] table, every region and its images. Prints a\n"
      "summary and exits 0, or prints the first error (file, line, key) and exits 1.");
  o->file_option = app.add_option("FILE", o->file,
                                  "Scene file to check; without it, the daemon's default, and where that does not "
                                  "exist, what the daemon runs instead (its embedded default scene)")
                       ->check(non_empty_path())
                       ->capture_default_str();
  app.add_flag("-q,--quiet", o->quiet, "No summary: only the warnings (standard error), or the error");
  return [o] { return run_check_config(*o); };
}

}  // namespace ph::tools
