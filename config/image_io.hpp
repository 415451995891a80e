// Reading and writing images through OpenImageIO, and PNG files read with libpng. Every error names the file.
// OpenImageIO lives in a module (ph_image_oiio.so, config/image_backend.hpp) loaded on the first call of
// any function here that needs it, so a program that never touches an image never maps it; a file named .png is
// read without it (config/image_png.hpp: the same values), and one that only reads PNG maps never loads it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/engine/decode.hpp"
#include "core/engine/field.hpp"

namespace ph {

// Images larger than this are refused before any pixel is read.
struct ImageLimits {
  std::int64_t max_pixels = std::int64_t{1} << 26;  // 67 M pixels (8192 x 8192)
  std::int32_t max_side = 32768;
  std::int32_t max_channels = 16;  // normal and depth maps use at most 4
};

struct ImageSize {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::uint32_t code_max = 0;  // 255 or 65535 for 8- and 16-bit images, 0 for float or other formats
};

// The size from the file's header alone, with the same checks and errors as read_image.
ImageSize read_image_size(const std::filesystem::path& path, const ImageLimits& limits = {});

// Reads every channel as float (integer formats scaled to [0, 1] as OpenImageIO scales them).
// Throws FieldError("PATH: reason") for a missing, unreadable, truncated, zero-sized or too large image.
RawImage read_image(const std::filesystem::path& path, const ImageLimits& limits = {});
// The same through the image module whatever the file's name (read_image reads a .png without it; the tests
// compare the two).
RawImage read_image_with_openimageio(const std::filesystem::path& path, const ImageLimits& limits = {});

// How an integer image is written: its file format (whatever the file name says) and 8 or 16 bits per channel.
enum class ImageFormat { png, tiff };
struct ImageEncoding {
  ImageFormat format = ImageFormat::png;
  int bits = 16;  // 8 or 16; anything else is refused (FieldError)
};

// RGB image of unit normals, tangent-space OpenGL convention (+green = screen -y), c = round((n+1)/2 * cmax)
// with cmax = 2^bits - 1.
void write_normal_image(const std::filesystem::path& path, const NormalImage& normals, ImageEncoding encoding);
// The same as a 16-bit PNG.
void write_normal_png16(const std::filesystem::path& path, const NormalImage& normals);

// Grey image of values in [0, 1] (clamped), c = round(v * cmax).
void write_gray_image(const std::filesystem::path& path, const Grid<float>& values, ImageEncoding encoding);
// The same as a 16-bit PNG.
void write_gray_png16(const std::filesystem::path& path, const Grid<float>& values);

// One-channel 32-bit float OpenEXR image of the values as they are (e.g. Gaussian curvature in 1/px^2).
void write_float_exr(const std::filesystem::path& path, const Grid<float>& values);

// 8-bit RGB PNG; rgb holds width * height * 3 bytes, row-major (false-colour pictures).
void write_rgb_png8(const std::filesystem::path& path, std::int32_t width, std::int32_t height,
                    const std::vector<std::uint8_t>& rgb);

}  // namespace ph
