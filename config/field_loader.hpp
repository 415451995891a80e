// Builds a region's fields from its image files: read, decode, repair, resample, and keep only what the
// region's method needs (a method that needs normals and has only a depth map gets them from the depth).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "config/image_io.hpp"
#include "core/engine/decode.hpp"
#include "core/engine/field.hpp"

namespace ph {

struct FieldSources {
  std::optional<std::filesystem::path> normal_map;
  NormalDecodeOptions normal_options;
  std::optional<std::filesystem::path> depth_map;
  DepthDecodeOptions depth_options;
};

struct FieldLoadReport {
  DecodeReport normals;  // texels counted at the image's own size
  DecodeReport depth;
};

// Which of a region's maps load_region_fields opens for `needs`: the normal map for slopes; the depth map for its
// heights, or for slopes where there is no normal map. A map the region names but nothing reads is not opened.
struct MapsOpened {
  bool normal_map = false;
  bool depth_map = false;
};
MapsOpened maps_opened(const FieldSources& sources, FieldNeeds needs);

// Throws FieldError naming the file, or naming what is missing (e.g. the depth method with only a normal map).
RegionFields load_region_fields(const FieldSources& sources, std::int32_t width, std::int32_t height, FieldNeeds needs,
                                FieldLoadReport& report, const ImageLimits& limits = {});

// What `report` says about invalid texels, one line per map that had any (none when every texel was valid):
// "normal map PATH: N of M texels invalid (...), each given the nearest valid texel's value". For the log
// of whatever loaded the fields, after its own prefix (the scene file and region).
std::vector<std::string> invalid_texel_notes(const FieldSources& sources, const FieldLoadReport& report);

// What became of a map read for a region of width x height px (docs/METHODS.md, "Screen, regions and fields"):
// "500x500 px", or "1024x1024 px, resampled to the region's 500x500", and where the two sizes are not in
// proportion "; out of proportion: stretched by 1.6 across and 0.6 down". Empty for a map not read.
std::string map_size_description(const DecodeReport& map, std::int32_t width, std::int32_t height);

// What a region of width x height px should say at load of its maps: invalid_texel_notes, then one line per map whose
// size is out of proportion with the region's, so that its relief is stretched on the screen ("normal map PATH: " and
// map_size_description's text), then settings that flatten a map read (normal_encoding = "signed" on an image of
// unsigned codes, relief_px = 0). For the log, as invalid_texel_notes.
std::vector<std::string> map_notes(const FieldSources& sources, const FieldLoadReport& report, std::int32_t width,
                                   std::int32_t height);

}  // namespace ph
