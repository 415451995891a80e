// How a user's maps reach the engine, built in memory: the integer codes an 8- or 16-bit image file holds,
// decoded through the loader's own path (core/engine/decode.hpp), and the normal map a normal-map generator makes
// from a height image (Sobel). What the accuracy and stability commands measure storage with.
#pragma once

#include <cstdint>
#include <vector>

#include "core/engine/decode.hpp"
#include "core/engine/field.hpp"

namespace ph {

// A w x h x channels image of unorm values in [0, 1] (clamped) rounded to integer codes of 0..code_max, as an
// 8-bit (255) or 16-bit (65535) file would give it to the loader.
RawImage quantised_image(std::int32_t width, std::int32_t height, int channels, const std::vector<double>& values,
                         std::uint32_t code_max);

// A normal map's file: codes of (n + 1) / 2, green in the OpenGL convention (+green = screen -y), the loader's
// default.
RawImage encode_normal_map(const NormalImage& normals, std::uint32_t code_max);

// A depth map's file whose codes span the heights [lo, hi] px (a generator's normalised range); its
// DepthDecodeOptions give the heights back.
RawImage encode_depth_map(const DepthField& depth, double lo, double hi, std::uint32_t code_max);
DepthDecodeOptions depth_options_for(double lo, double hi);

// The normals decoded from a normal map stored with code_max (0: float, returned as given); what decoding found goes
// to `report` where one is given (its value_step: 0 for float).
NormalImage stored_normals(const NormalImage& normals, std::uint32_t code_max, DecodeReport* report = nullptr);
// The heights decoded from a depth map stored with code_max over the field's own range (0: float, as given); what
// decoding found goes to `report` where one is given (its value_step: 0 for float).
DepthField stored_depth(const DepthField& depth, std::uint32_t code_max, DecodeReport* report = nullptr);

// The normal map a generator makes from a height image: the Sobel derivatives (divided by 8, so a plane's slope
// comes out exact), edges clamped, n = (-g_x, -g_y, 1) / |.| times `strength` on the slope.
NormalImage sobel_normals(const DepthField& depth, double strength = 1.0);

}  // namespace ph
