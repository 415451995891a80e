// Why an image's header alone refuses it (empty, larger than the limits), as one reason the caller puts after the
// file's name, and that error: shared by config/image_io.cpp, the image module (config/image_oiio.cpp) and the PNG
// reader (config/image_png.cpp), so that a file is refused alike whichever reads it. Internal to config/.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "config/image_io.hpp"

namespace ph {

// The error for an image file: "PATH: reason".
inline FieldError image_file_error(const std::filesystem::path& path, const std::string& reason) {
  return FieldError(path.string() + ": " + reason);
}

// Empty when an image of that size and channel count is within the limits.
inline std::string image_size_refusal(std::int64_t width, std::int64_t height, std::int64_t channels,
                                      const ImageLimits& limits) {
  if (width <= 0 || height <= 0 || channels <= 0) return "image has zero size";
  const std::string size = std::to_string(width) + " x " + std::to_string(height) + " px";
  if (width > limits.max_side || height > limits.max_side)
    return "image is " + size + ", more than the limit of " + std::to_string(limits.max_side) + " px per side";
  if (width * height > limits.max_pixels)
    return "image is " + size + ", more than the limit of " + std::to_string(limits.max_pixels) + " pixels";
  if (channels > limits.max_channels) {
    return "image has " + std::to_string(channels) + " channels, more than the limit of " +
           std::to_string(limits.max_channels);
  }
  return {};
}

}  // namespace ph
