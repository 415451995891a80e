#include "config/field_loader.hpp"

#include <fmt/core.h>

#include <cmath>
#include <optional>
#include <string>
#include <utility>

namespace ph {
namespace {

// Runs a decoding step, prefixing the file's path to any FieldError that does not name it yet.
template <typename Step>
auto naming_file(const std::filesystem::path& path, Step step) {
  try {
    return step();
  } catch (const FieldError& error) {
    const std::string prefix = path.string() + ": ";
    const std::string message = error.what();
    if (message.rfind(prefix, 0) == 0) throw;
    throw FieldError(prefix + message);
  }
}

void require_sources(const FieldSources& sources, FieldNeeds needs) {
  if (needs.gradient && !sources.normal_map && !sources.depth_map) {
    throw FieldError("the method needs normals: give a normal map or a depth map");
  }
  if (needs.depth && !sources.depth_map) {
    throw FieldError("the depth method needs a depth map (a normal map alone is not enough)");
  }
}

DepthField load_depth(const std::filesystem::path& path, const DepthDecodeOptions& options, std::int32_t width,
                      std::int32_t height, DecodeReport& report, const ImageLimits& limits) {
  const RawImage image = read_image(path, limits);
  return naming_file(path, [&] {
    DepthField depth = decode_depth(image, options, report);
    if (depth.width == width && depth.height == height) return depth;  // the region's size already: no copy
    return resample_depth(depth, width, height);
  });
}

// A map of the region's size is decoded straight into gradients; any other is resampled as normals first.
GradientField load_gradient(const std::filesystem::path& path, const NormalDecodeOptions& options, std::int32_t width,
                            std::int32_t height, DecodeReport& report, const ImageLimits& limits) {
  const RawImage image = read_image(path, limits);
  return naming_file(path, [&] {
    if (image.width == width && image.height == height) return decode_normals_to_gradient(image, options, report);
    return gradient_from_normals(resample_normals(decode_normals(image, options, report), width, height));
  });
}

}  // namespace

MapsOpened maps_opened(const FieldSources& sources, FieldNeeds needs) {
  const bool gradient_from_depth_map = needs.gradient && !sources.normal_map;
  return {needs.gradient && sources.normal_map.has_value(),
          sources.depth_map.has_value() && (needs.reads_depth(true) || gradient_from_depth_map)};
}

RegionFields load_region_fields(const FieldSources& sources, std::int32_t width, std::int32_t height, FieldNeeds needs,
                                FieldLoadReport& report, const ImageLimits& limits) {
  report = {};
  require_sources(sources, needs);
  // Depth is read once, for the depth itself or for normals when there is no normal map; nothing else is read.
  const bool gradient_from_depth_map = needs.gradient && !sources.normal_map;
  std::optional<DepthField> depth;
  if (maps_opened(sources, needs).depth_map) {
    depth = load_depth(*sources.depth_map, sources.depth_options, width, height, report.depth, limits);
  }

  RegionFields fields;
  if (needs.gradient) {
    fields.gradient = gradient_from_depth_map ? gradient_from_depth(*depth)
                                              : load_gradient(*sources.normal_map, sources.normal_options, width,
                                                              height, report.normals, limits);
  }
  if (needs.gradient) {
    fields.gradient_rounding = gradient_from_depth_map ? gradient_rounding_of_depth(report.depth.value_step)
                                                       : gradient_rounding_of_normals(report.normals.value_step);
  }
  if (needs.reads_depth(sources.depth_map.has_value())) {  // kept: the heights are the method's or an effect's
    fields.depth = std::move(depth);
    fields.depth_rounding = height_rounding_of_depth(report.depth.value_step);
  }
  return fields;
}

std::vector<std::string> invalid_texel_notes(const FieldSources& sources, const FieldLoadReport& report) {
  std::vector<std::string> notes;
  auto note = [&](const char* what, const std::optional<std::filesystem::path>& path, const DecodeReport& r,
                  const char* why) {
    if (r.invalid_texels == 0) return;
    const std::string map = std::string(what) + " " + (path ? path->string() : std::string("(none)")) + ": ";
    if (r.invalid_texels >= r.texels) {  // nothing to take a value from (core/engine/decode.cpp)
      notes.push_back(map + "every texel invalid (" + why + "), so the map reads as flat");
      return;
    }
    notes.push_back(map + std::to_string(r.invalid_texels) + " of " + std::to_string(r.texels) + " texels invalid (" +
                    why + "), each given the nearest valid texel's value");
  };
  note("normal map", sources.normal_map, report.normals, "length < 0.5, n_z <= 0 or not finite");
  // A finite value can overflow a float's heights once scaled: (3e38 - depth_zero) * relief_px.
  note("depth map", sources.depth_map, report.depth, "not finite, or a height beyond a float once scaled by relief_px");
  return notes;
}

namespace {

// How much wider (sx) and taller (sy) the region shows the map than its own size.
struct MapScale {
  double sx = 1.0;
  double sy = 1.0;
  // A map within 1 % of the region's proportions is taken as in proportion (a region a pixel off a map's size).
  bool in_proportion() const { return std::abs(sx / sy - 1.0) <= 0.01; }
};

MapScale map_scale(const DecodeReport& map, std::int32_t width, std::int32_t height) {
  return {static_cast<double>(width) / map.width, static_cast<double>(height) / map.height};
}

bool was_read(const DecodeReport& map) { return map.width > 0 && map.height > 0; }

}  // namespace

std::string map_size_description(const DecodeReport& map, std::int32_t width, std::int32_t height) {
  if (!was_read(map)) return "";
  std::string text = fmt::format("{}x{} px", map.width, map.height);
  if (map.width == width && map.height == height) return text;
  text += fmt::format(", resampled to the region's {}x{}", width, height);
  const MapScale scale = map_scale(map, width, height);
  if (!scale.in_proportion()) {
    text += fmt::format("; out of proportion: stretched by {:.3g} across and {:.3g} down", scale.sx, scale.sy);
  }
  return text;
}

std::vector<std::string> map_notes(const FieldSources& sources, const FieldLoadReport& report, std::int32_t width,
                                   std::int32_t height) {
  std::vector<std::string> notes = invalid_texel_notes(sources, report);
  auto note = [&](const char* what, const std::optional<std::filesystem::path>& path, const DecodeReport& r) {
    if (!was_read(r) || map_scale(r, width, height).in_proportion()) return;
    notes.push_back(fmt::format("{} {}: {}", what, path ? path->string() : std::string("(none)"),
                                map_size_description(r, width, height)));
  };
  note("normal map", sources.normal_map, report.normals);
  note("depth map", sources.depth_map, report.depth);
  // Settings that silently flatten what a map holds. An image of unsigned codes has value_step > 0 (a signed
  // integer TIFF, whose codes the reader gives as values in [-1, 1], has none).
  const std::string none = "(none)";
  if (was_read(report.normals) && sources.normal_options.encoding == NormalEncoding::signed_values &&
      report.normals.value_step > 0.0) {
    notes.push_back(
        fmt::format("normal map {}: normal_encoding = \"signed\" reads this image's unsigned codes as "
                    "values from 0 to 1, so no normal leans left or up and most of the relief is lost; "
                    "\"auto\" (or \"unorm\") decodes them as 2c/cmax - 1",
                    sources.normal_map ? sources.normal_map->string() : none));
  }
  if (was_read(report.depth) && sources.depth_options.relief_px == 0.0) {
    notes.push_back(
        fmt::format("depth map {}: relief_px = 0 makes every height 0: what reads the heights feels the "
                    "region flat",
                    sources.depth_map ? sources.depth_map->string() : none));
  }
  return notes;
}

}  // namespace ph
