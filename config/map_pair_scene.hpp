// A square one-region scene whose normal map and depth map lie beside its file, as `pseudohaptic targets` and
// `pseudohaptic surfaces` write them: NAME.normal.png and NAME.depth.png (16-bit) and NAME.toml.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "core/engine/field.hpp"

namespace ph {

struct MapPairScene {
  std::string name;
  std::int32_t size = 0;       // the region's side, px (its rectangle starts at 0, 0)
  double relief_px = 0.0;      // heights lie within +-relief_px
  std::string header;          // the file's first comment lines, each "# ...\n"
  std::string relief_comment;  // said after the scene's relief_px
};

// The scene file's text. The depth map holds v = (h / relief_px + 1) / 2, so the scene says depth_zero = 0.5 and
// relief_px = 2 * relief_px; the map paths are relative to the scene file's folder.
std::string map_pair_scene_text(const MapPairScene& scene);

// Writes NAME.normal.png, NAME.depth.png and, last, NAME.toml into `outdir` (which must exist), overwriting old ones:
// an interrupted run leaves no scene file naming a map that was not written. Throws (FieldError for an image,
// std::runtime_error otherwise), naming the path, when a file cannot be written.
void write_map_pair_files(const std::filesystem::path& outdir, const MapPairScene& scene, const NormalImage& normals,
                          const Grid<float>& heights);

// A double as a TOML float: shortest round-trip form, with ".0" added where it would read as an integer.
std::string toml_float(double value);

// Writes `text` to `path`, replacing it; throws std::runtime_error naming the path when it cannot.
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace ph
