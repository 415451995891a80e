#include "daemon/configuration.hpp"

#include <fmt/format.h>

#include <optional>
#include <string>

#include "config/desktop_geometry.hpp"
#include "config/image_child.hpp"
#include "config/scene_file.hpp"
#include "core/engine/default_scene.hpp"

namespace ph {

namespace {

bool same_matchers(const std::vector<DeviceMatch>& a, const std::vector<DeviceMatch>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    // The same devices, however written (usb: and id: are one matcher).
    if (a[i].name_glob != b[i].name_glob || a[i].vendor != b[i].vendor || a[i].product != b[i].product) return false;
  }
  return true;
}

}  // namespace

Configuration load_configuration(const ConfigChoice& choice) {
  Configuration c;
  std::optional<std::filesystem::path> file = choice.file;
  if (!choice.default_scene && !file) {
    if (!scene_file_absent(choice.default_file)) {
      file = choice.default_file;
    } else {
      c.notes.push_back(
          fmt::format("no scene file at {}; using the embedded default scene (three targets of the "
                      "curvature paper in the middle of the desktop, see pseudohapticd(8))",
                      choice.default_file.string()));
    }
  }
  if (file && !choice.default_scene) {
    const SceneSpec spec = parse_scene_file(*file);
    SceneLoadReport report;
    // The images are read in a child process that ends with the load (config/image_child.hpp): the
    // daemon never maps the image library nor parses an image file.
    ImageChild images;
    c.scene = std::make_shared<const Scene>(load_scene(spec, &report, &images));
    // Invalid texels are counted, repaired and reported at load, as are maps stretched out of proportion
    // (docs/METHODS.md, "Screen, regions and fields").
    for (std::string& warning : load_warnings(spec, report, *c.scene)) c.warnings.push_back(std::move(warning));
    for (std::string& warning : desktop_warnings(spec)) c.warnings.push_back(std::move(warning));
    c.settings = spec.daemon;
    c.source = file->string();
  } else {
    c.source = "the embedded default scene";
    c.embedded = true;
  }
  c.pipeline = pipeline_config_of(c.settings, resolve_desktop(c.settings.desktop, choice.drm_dir, c.desktop_guessed));
  if (!c.desktop_guessed.empty()) c.warnings.push_back(c.desktop_guessed);
  // Laid out for the desktop found: its targets in the middle, as many as fit (Daemon::layout lays them out again
  // for the session helper's).
  if (c.embedded) {
    c.scene = std::make_shared<const Scene>(default_scene(c.pipeline.desktop));
    c.notes.push_back(fmt::format("the embedded default scene on the desktop {},{} {}x{} px: {}", c.pipeline.desktop.x,
                                  c.pipeline.desktop.y, c.pipeline.desktop.w, c.pipeline.desktop.h,
                                  default_scene_places(*c.scene)));
  }
  // With desktop = "auto" read from the connected displays, regions off it are said here (a configured desktop's
  // are, above, with their lines; the session helper's layout is checked again when it comes: Daemon::layout).
  if (!c.settings.desktop && c.desktop_guessed.empty()) {
    for (const std::string& note : off_desktop_notes(*c.scene, c.pipeline.desktop))
      c.warnings.push_back(
          fmt::format("{}: {} (desktop = \"auto\": the connected displays side by side)", c.source, note));
  }
  return c;
}

bool only_scene_differs(const Configuration& a, const Configuration& b) {
  return a.pipeline.desktop == b.pipeline.desktop && a.pipeline.outputs == b.pipeline.outputs &&
         a.pipeline.mode == b.pipeline.mode && a.pipeline.pointer_gain == b.pipeline.pointer_gain &&
         a.pipeline.acceleration.profile == b.pipeline.acceleration.profile &&
         a.pipeline.acceleration.speed == b.pipeline.acceleration.speed &&
         a.pipeline.acceleration.dpi == b.pipeline.acceleration.dpi &&
         same_matchers(a.settings.devices, b.settings.devices);
}

}  // namespace ph
