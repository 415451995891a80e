#include "config/image_io.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ph {
namespace {

// OpenImageIO messages sometimes end in a newline; ours are one line.
std::string one_line(std::string message) {
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  std::replace(message.begin(), message.end(), '\n', ' ');
  return message.empty() ? "unknown error" : message;
}

FieldError file_error(const std::filesystem::path& path, const std::string& reason) {
  return FieldError(path.string() + ": " + reason);
}

// Keeps colour values as stored: without this hint OpenImageIO premultiplies RGB by alpha on reading PNG,
// which would corrupt an RGBA normal map whose alpha is not 1.
OIIO::ImageSpec as_stored_config() {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  return config;
}

bool is_float_type(OIIO::TypeDesc format) {
  return format.basetype == OIIO::TypeDesc::HALF || format.basetype == OIIO::TypeDesc::FLOAT ||
         format.basetype == OIIO::TypeDesc::DOUBLE;
}

// Refuses, from the header alone, an image that is empty, not a plain 2D image, or larger than the limits.
void check_spec(const std::filesystem::path& path, const OIIO::ImageSpec& spec, const ImageLimits& limits) {
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) throw file_error(path, "image has zero size");
  if (spec.depth > 1)
    throw file_error(path, "volume images (depth " + std::to_string(spec.depth) + ") are not supported");
  if (spec.deep) throw file_error(path, "deep images are not supported");
  const std::string size = std::to_string(spec.width) + " x " + std::to_string(spec.height) + " px";
  if (spec.width > limits.max_side || spec.height > limits.max_side) {
    throw file_error(
        path, "image is " + size + ", more than the limit of " + std::to_string(limits.max_side) + " px per side");
  }
  const std::int64_t pixels = std::int64_t{spec.width} * spec.height;
  if (pixels > limits.max_pixels) {
    throw file_error(path,
                     "image is " + size + ", more than the limit of " + std::to_string(limits.max_pixels) + " pixels");
  }
  if (spec.nchannels > limits.max_channels) {
    throw file_error(path, "image has " + std::to_string(spec.nchannels) + " channels, more than the limit of " +
                               std::to_string(limits.max_channels));
  }
}

// 16-bit code of a value in [0, 1]; a non-finite value writes 0.
std::uint16_t unorm16(double v) {
  if (!std::isfinite(v)) v = 0.0;
  return static_cast<std::uint16_t>(std::lround(std::clamp(v, 0.0, 1.0) * 65535.0));
}

// Writes pixels of the given type in the given format, whatever the file name says.
void write_pixels(const std::filesystem::path& path, const char* format, std::int32_t width, std::int32_t height,
                  int channels, OIIO::TypeDesc type, const void* pixels) {
  if (width <= 0 || height <= 0) throw file_error(path, "cannot write an image of zero size");
  auto out = OIIO::ImageOutput::create(format);
  if (!out) throw file_error(path, "cannot write: " + one_line(OIIO::geterror()));
  const OIIO::ImageSpec spec(width, height, channels, type);
  if (!out->open(path.string(), spec)) throw file_error(path, "cannot write: " + one_line(out->geterror()));
  const bool written = out->write_image(type, pixels);
  const bool closed = out->close();
  if (!written || !closed) throw file_error(path, "cannot write: " + one_line(out->geterror()));
}

void write_png16(const std::filesystem::path& path, std::int32_t width, std::int32_t height, int channels,
                 const std::vector<std::uint16_t>& codes) {
  write_pixels(path, "png", width, height, channels, OIIO::TypeDesc::UINT16, codes.data());
}

}  // namespace

ImageSize read_image_size(const std::filesystem::path& path, const ImageLimits& limits) {
  const OIIO::ImageSpec config = as_stored_config();
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) throw file_error(path, "cannot open: " + one_line(OIIO::geterror()));
  check_spec(path, in->spec(), limits);
  const OIIO::TypeDesc format = in->spec().format;
  const std::uint32_t code_max = format == OIIO::TypeDesc::UINT8 ? 255 : format == OIIO::TypeDesc::UINT16 ? 65535 : 0;
  return {in->spec().width, in->spec().height, code_max};
}

RawImage read_image(const std::filesystem::path& path, const ImageLimits& limits) {
  const OIIO::ImageSpec config = as_stored_config();
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) throw file_error(path, "cannot open: " + one_line(OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  check_spec(path, spec, limits);

  RawImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  image.is_float = is_float_type(spec.format);
  if (spec.format == OIIO::TypeDesc::UINT8) image.code_max = 255;
  if (spec.format == OIIO::TypeDesc::UINT16) image.code_max = 65535;
  image.pixels.resize(static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height) *
                      static_cast<std::size_t>(spec.nchannels));
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
    throw file_error(path, "truncated or corrupt: " + one_line(in->geterror()));
  }
  in->close();
  return image;
}

void write_normal_png16(const std::filesystem::path& path, const NormalImage& normals) {
  std::vector<std::uint16_t> codes;
  codes.reserve(normals.values.size() * 3);
  for (const Normal& n : normals.values) {
    // Tangent space, OpenGL convention: +green points to the top of the image, screen -y.
    codes.push_back(unorm16((n.x + 1.0) / 2.0));
    codes.push_back(unorm16((-n.y + 1.0) / 2.0));
    codes.push_back(unorm16((n.z + 1.0) / 2.0));
  }
  write_png16(path, normals.width, normals.height, 3, codes);
}

void write_gray_png16(const std::filesystem::path& path, const Grid<float>& values) {
  std::vector<std::uint16_t> codes;
  codes.reserve(values.values.size());
  for (const float v : values.values) codes.push_back(unorm16(v));
  write_png16(path, values.width, values.height, 1, codes);
}

void write_float_exr(const std::filesystem::path& path, const Grid<float>& values) {
  write_pixels(path, "openexr", values.width, values.height, 1, OIIO::TypeDesc::FLOAT, values.values.data());
}

void write_rgb_png8(const std::filesystem::path& path, std::int32_t width, std::int32_t height,
                    const std::vector<std::uint8_t>& rgb) {
  if (rgb.size() != static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0)) * 3)
    throw file_error(path, "cannot write: pixel count does not match the size");
  write_pixels(path, "png", width, height, 3, OIIO::TypeDesc::UINT8, rgb.data());
}

}  // namespace ph
