// PNG files read with libpng itself rather than through the image module (config/image_backend.hpp): loading
// OpenImageIO and its ~260 libraries costs about 0.35 s of dynamic linking per process (the daemon's image reader
// is a new process for every load), and under the test VM's emulation several seconds, while a PNG is what most
// maps are. The values are OpenImageIO's to the bit (tests/test_image_png.cpp compares every code): 1, 2 and
// 4-bit grey widened to 8 bits, a palette to RGB, a transparent colour to an alpha channel, colour as stored
// (never multiplied by alpha), integer codes scaled to [0, 1] as OpenImageIO scales them. The common PNG is read
// whole first (config/png_whole.hpp), libpng reading what that leaves. Internal to config/: callers use
// config/image_io.hpp, which sends files named .png here.
#pragma once

#include <filesystem>

#include "config/image_io.hpp"

namespace ph {

// As read_image_size and read_image (config/image_io.hpp), errors included, for a PNG file.
ImageSize read_png_size(const std::filesystem::path& path, const ImageLimits& limits);
RawImage read_png(const std::filesystem::path& path, const ImageLimits& limits);
// read_png without the whole-file reader: libpng alone (for the fuzzer's comparison of the two).
RawImage read_png_with_libpng(const std::filesystem::path& path, const ImageLimits& limits);

}  // namespace ph
