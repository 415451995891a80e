// The common PNG read in one inflate call: 8- or 16-bit grey, grey and alpha, RGB or RGBA, not interlaced, no
// transparent colour (every map the project's tools write, and most that users bring). libpng streams the image
// data through zlib a row at a time; libdeflate inflates the whole of it in one call about three times as fast
// (a 3840 x 2160 16-bit normal map: 46 ms against 150 ms), which is most of what a large map's load waits for.
// What it cannot read as libpng would (any other layout, a transparent colour, and any file in which it finds
// anything wrong) it leaves to libpng, which reads it, or says what is wrong with it, as before. Internal to
// config/: config/image_png.cpp tries it first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>

#include "config/image_io.hpp"

namespace ph {

// The image as read_png (config/image_png.hpp) gives it, to the bit; nullopt where libpng is to read the file.
std::optional<RawImage> read_png_whole(const std::filesystem::path& path, const ImageLimits& limits);

// What both PNG readers make of the samples: an image of that size for 8- or 16-bit codes (its pixels sized, to be
// filled), and one row's `count` samples as a PNG stores them (bytes, or 16-bit big-endian) converted to float as
// OpenImageIO converts integer codes: times the reciprocal of the largest code, in float.
RawImage png_raw_image(std::uint32_t width, std::uint32_t height, int channels, int bit_depth);
void png_row_to_float(const unsigned char* row, int bit_depth, std::size_t count, float* out);

}  // namespace ph
