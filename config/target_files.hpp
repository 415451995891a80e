// Writes the 24 targets of the curvature paper (core/engine/targets.hpp) as files the daemon loads: for each target a
// 16-bit normal map, a 16-bit depth map and a one-region scene file that names both.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "config/map_pair_scene.hpp"
#include "core/engine/targets.hpp"

namespace ph {

// The three files of one target in outdir: NAME.normal.png, NAME.depth.png and NAME.toml.
struct TargetFilePaths {
  std::filesystem::path normal_map;
  std::filesystem::path depth_map;
  std::filesystem::path scene;
};

TargetFilePaths target_file_paths(const std::filesystem::path& outdir, const TargetSpec& spec);

// The scene of one target, and its file's text (config/map_pair_scene.hpp: its map paths are relative to the scene
// file's directory; the scene says depth_zero = 0.5, relief_px = 2 * the target's relief_px).
MapPairScene target_scene(const TargetSpec& spec);
std::string target_scene_text(const TargetSpec& spec);

// Creates outdir if needed and writes the three files of every target, overwriting old ones. Calls progress
// after each target with the number written so far. Returns the scene file paths, in the order of targets.
// Throws (FieldError for an image, std::runtime_error or std::filesystem::filesystem_error otherwise),
// naming the path, when a file cannot be written.
std::vector<std::filesystem::path> write_target_files(
    const std::filesystem::path& outdir, const std::vector<TargetSpec>& targets,
    const std::function<void(std::size_t done, std::size_t total, const TargetSpec&)>& progress = {});

// True when all three files of every target exist in outdir (their content is not checked).
bool target_files_present(const std::filesystem::path& outdir, const std::vector<TargetSpec>& targets);

}  // namespace ph
