#include "config/target_files.hpp"

#include <fmt/format.h>

namespace ph {

TargetFilePaths target_file_paths(const std::filesystem::path& outdir, const TargetSpec& spec) {
  const std::string name = spec.name();
  return {outdir / (name + ".normal.png"), outdir / (name + ".depth.png"), outdir / (name + ".toml")};
}

MapPairScene target_scene(const TargetSpec& spec) {
  const std::string name = spec.name();
  return {name, spec.size, spec.relief_px,
          fmt::format("# pseudohaptic scene: target {} of Argelaguet et al. 2012, Fig. 3\n"
                      "# Both maps are given, so the region works with either method (\"curvature\" or \"depth\").\n",
                      name),
          fmt::format("normalised depth 1 = {} px of relief: v in [0,1] holds (depth + 1) / 2", spec.relief_px)};
}

std::string target_scene_text(const TargetSpec& spec) { return map_pair_scene_text(target_scene(spec)); }

std::vector<std::filesystem::path> write_target_files(
    const std::filesystem::path& outdir, const std::vector<TargetSpec>& targets,
    const std::function<void(std::size_t done, std::size_t total, const TargetSpec&)>& progress) {
  std::filesystem::create_directories(outdir);
  std::vector<std::filesystem::path> scenes;
  scenes.reserve(targets.size());
  for (const TargetSpec& spec : targets) {
    write_map_pair_files(outdir, target_scene(spec), target_normal_image(spec), target_depth_field(spec));
    scenes.push_back(target_file_paths(outdir, spec).scene);
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
