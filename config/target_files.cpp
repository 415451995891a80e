#include "config/target_files.hpp"

#include <fmt/format.h>

#include <fstream>
#include <stdexcept>

#include "config/image_io.hpp"

namespace ph {
namespace {

// A double as a TOML float: shortest round-trip form, with ".0" added where it would read as an integer.
std::string toml_float(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // 'n': inf and nan need no suffix
  return text;
}

// Normalised depth h / relief_px in [-1, 1] mapped to v in [0, 1], the range a unorm image holds.
Grid<float> depth_image_values(const TargetSpec& spec) {
  Grid<float> values = target_depth_field(spec);
  for (float& v : values.values) v = static_cast<float>((v / spec.relief_px + 1.0) / 2.0);
  return values;
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": cannot write the file");
}

}  // namespace

TargetFilePaths target_file_paths(const std::filesystem::path& outdir, const TargetSpec& spec) {
  const std::string name = spec.name();
  return {outdir / (name + ".normal.png"), outdir / (name + ".depth.png"), outdir / (name + ".toml")};
}

std::string target_scene_text(const TargetSpec& spec) {
  const std::string name = spec.name();
  // v = (h / relief_px + 1) / 2, so h = (v - 0.5) * 2 * relief_px.
  return fmt::format(
      "# pseudohaptic scene: target {name} of Argelaguet et al. 2012, Fig. 3\n"
      "# Both maps are given, so the region works with either method (\"curvature\" or \"depth\").\n"
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
      "relief_px = {scene_relief}   # normalised depth 1 = {relief} px of relief: v in [0,1] holds (depth + 1) / 2\n",
      fmt::arg("name", name), fmt::arg("size", spec.size), fmt::arg("scene_relief", toml_float(2.0 * spec.relief_px)),
      fmt::arg("relief", spec.relief_px));
}

std::vector<std::filesystem::path> write_target_files(
    const std::filesystem::path& outdir, const std::vector<TargetSpec>& targets,
    const std::function<void(std::size_t done, std::size_t total, const TargetSpec&)>& progress) {
  std::filesystem::create_directories(outdir);
  std::vector<std::filesystem::path> scenes;
  scenes.reserve(targets.size());
  for (const TargetSpec& spec : targets) {
    const TargetFilePaths paths = target_file_paths(outdir, spec);
    write_normal_png16(paths.normal_map, target_normal_image(spec));
    write_gray_png16(paths.depth_map, depth_image_values(spec));
    // The scene goes last: an interrupted run leaves no scene file naming a map that was not written.
    write_text_file(paths.scene, target_scene_text(spec));
    scenes.push_back(paths.scene);
    if (progress) progress(scenes.size(), targets.size(), spec);
  }
  return scenes;
}

bool target_files_present(const std::filesystem::path& outdir, const std::vector<TargetSpec>& targets) {
  for (const TargetSpec& spec : targets) {
    const TargetFilePaths paths = target_file_paths(outdir, spec);
    for (const auto& path : {paths.normal_map, paths.depth_map, paths.scene}) {
      std::error_code error;  // an unreadable directory counts as absent rather than throwing
      if (!std::filesystem::exists(path, error)) return false;
    }
  }
  return true;
}

}  // namespace ph
