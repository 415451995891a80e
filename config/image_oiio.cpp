// The image module ph_image_oiio.so: every use of OpenImageIO, behind the table of config/image_backend.hpp.
// Loaded by config/image_io.cpp on the first image read or written; built with hidden visibility and a
// version script, so the entry point below is its only exported symbol.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "config/image_backend.hpp"
#include "config/image_header_check.hpp"

namespace ph {
namespace {

// OpenImageIO messages sometimes end in a newline; ours are one line.
std::string one_line(std::string message) {
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  std::replace(message.begin(), message.end(), '\n', ' ');
  return message.empty() ? "unknown error" : message;
}

// OpenImageIO 2.4 decompresses a deflate TIFF's strips on its thread pool and, where a scanline after them fails
// to read, returns before those tasks end, which then write to its stack and freed buffers (a use after scope,
// mended in later OpenImageIO releases). The image fuzzer found it as heap corruption that no input reproduced alone.
// Decoded in one thread, the strips are done before it returns.
void decode_tiff_strips_in_one_thread() {
  static const bool set = OIIO::attribute("tiff:multithread", 0);
  static_cast<void>(set);
}

// Keeps colour values as stored: without this hint OpenImageIO premultiplies RGB by alpha on reading PNG,
// which would corrupt an RGBA normal map whose alpha is not 1. (Every read opens its image with it, so the TIFF
// setting above is made here too.)
OIIO::ImageSpec as_stored_config() {
  decode_tiff_strips_in_one_thread();
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
  if (spec.depth > 1)
    throw image_file_error(path, "volume images (depth " + std::to_string(spec.depth) + ") are not supported");
  if (spec.deep) throw image_file_error(path, "deep images are not supported");
  const std::string refusal = image_size_refusal(spec.width, spec.height, spec.nchannels, limits);
  if (!refusal.empty()) throw image_file_error(path, refusal);
}

// Why OpenImageIO could not open the file. A header claiming more than OpenImageIO's own limits ("limits:imagesize_MB",
// "limits:channels"; its TIFF reader checks them as it opens) comes with advice to raise them, which a scene author
// cannot follow: said in the words of our limits, which such an image exceeds anyway.
FieldError open_error(const std::filesystem::path& path, const ImageLimits& limits) {
  const std::string message = one_line(OIIO::geterror());
  if (message.find("\"limits:imagesize_MB\"") != std::string::npos ||
      message.find("\"limits:channels\"") != std::string::npos) {
    return image_file_error(path, "its header claims an image larger than the limits of " +
                                      std::to_string(limits.max_side) + " px per side, " +
                                      std::to_string(limits.max_pixels) + " pixels and " +
                                      std::to_string(limits.max_channels) + " channels; refused before reading it");
  }
  return image_file_error(path, "cannot open: " + message);
}

// Writes pixels of the given type in the given format, whatever the file name says.
void write_pixels(const std::filesystem::path& path, const char* format, std::int32_t width, std::int32_t height,
                  int channels, OIIO::TypeDesc type, const void* pixels) {
  if (width <= 0 || height <= 0) throw image_file_error(path, "cannot write an image of zero size");
  auto out = OIIO::ImageOutput::create(format);
  if (!out) throw image_file_error(path, "cannot write: " + one_line(OIIO::geterror()));
  const OIIO::ImageSpec spec(width, height, channels, type);
  if (!out->open(path.string(), spec)) throw image_file_error(path, "cannot write: " + one_line(out->geterror()));
  const bool written = out->write_image(type, pixels);
  const bool closed = out->close();
  if (!written || !closed) throw image_file_error(path, "cannot write: " + one_line(out->geterror()));
  // OpenImageIO 2.4's writers may report success where the disk was full or the file size limit met, leaving the
  // file cut short: read back, whole, what was written (a tool's pictures and maps; milliseconds for the largest),
  // through the format's own reader (the name may not say it: a temporary name). A PNG is read back by the caller,
  // through the project's own PNG reader (config/image_io.cpp): OpenImageIO's leaks on a PNG cut short.
  if (std::string_view(format) == "png") return;
  const OIIO::ImageSpec config = as_stored_config();
  auto in = OIIO::ImageInput::create(format);
  OIIO::ImageSpec read_spec;
  const bool opened = in && in->open(path.string(), read_spec, config);
  std::vector<unsigned char> back(opened ? in->spec().image_bytes() : 0);
  if (!opened || in->spec().width != width || in->spec().height != height ||
      !in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::UNKNOWN, back.data())) {
    throw image_file_error(path, "cannot write: the file reads back cut short or corrupt (a full disk?)");
  }
}

OIIO::TypeDesc type_desc(image_backend::PixelType type) {
  switch (type) {
    case image_backend::PixelType::uint8:
      return OIIO::TypeDesc::UINT8;
    case image_backend::PixelType::uint16:
      return OIIO::TypeDesc::UINT16;
    case image_backend::PixelType::float32:
      return OIIO::TypeDesc::FLOAT;
  }
  return OIIO::TypeDesc::UNKNOWN;
}

void write_image(const std::filesystem::path& path, const char* format, std::int32_t width, std::int32_t height,
                 std::int32_t channels, image_backend::PixelType type, const void* pixels) {
  const OIIO::TypeDesc desc = type_desc(type);
  if (desc == OIIO::TypeDesc::UNKNOWN) throw image_file_error(path, "cannot write: unknown pixel type");
  write_pixels(path, format, width, height, channels, desc, pixels);
}

ImageSize read_size(const std::filesystem::path& path, const ImageLimits& limits) {
  const OIIO::ImageSpec config = as_stored_config();
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) throw open_error(path, limits);
  check_spec(path, in->spec(), limits);
  const OIIO::TypeDesc format = in->spec().format;
  const std::uint32_t code_max = format == OIIO::TypeDesc::UINT8 ? 255 : format == OIIO::TypeDesc::UINT16 ? 65535 : 0;
  return {in->spec().width, in->spec().height, code_max};
}

// A white-is-zero TIFF (PhotometricInterpretation 0): its values are the stored codes inverted.
bool is_white_is_zero_tiff(const OIIO::ImageInput& in) {
  return std::string_view(in.format_name()) == "tiff" &&
         in.spec().get_int_attribute("tiff:PhotometricInterpretation", -1) == 0;
}

// OpenImageIO 2.4 inverts each deflate strip of such a file over as many strips' worth of values as a pixel has
// channels, and so past the last strip writes beyond the buffer it reads into (heap corruption the image fuzzer
// found: docs/FUZZING.md). One scanline at a time it inverts just that row; tiles, one at a time, are inverted right.
bool reads_wrong_in_strips(const OIIO::ImageInput& in) {
  return is_white_is_zero_tiff(in) && in.spec().tile_width == 0;
}

// It inverts 8-bit values only: a 16-bit white-is-zero image (a depth map, say) would come out as stored, its relief
// upside down. Inverted here.
void invert_white_is_zero_uint16(const OIIO::ImageInput& in, std::vector<unsigned char>& native) {
  if (in.spec().format != OIIO::TypeDesc::UINT16 || !is_white_is_zero_tiff(in)) return;
  for (std::size_t i = 0; i + 1 < native.size(); i += 2) {
    std::uint16_t v = 0;
    std::memcpy(&v, &native[i], 2);
    v = static_cast<std::uint16_t>(65535 - v);
    std::memcpy(&native[i], &v, 2);
  }
}

// The image a row at a time, in `format` (TypeDesc::UNKNOWN: the file's own).
bool read_row_by_row(OIIO::ImageInput& in, OIIO::TypeDesc format, void* pixels) {
  const OIIO::ImageSpec& spec = in.spec();
  const std::size_t row_bytes = format == OIIO::TypeDesc::UNKNOWN
                                    ? static_cast<std::size_t>(spec.scanline_bytes(true))
                                    : static_cast<std::size_t>(spec.width) * spec.nchannels * format.size();
  auto* row = static_cast<unsigned char*>(pixels);
  for (int y = spec.y; y < spec.y + spec.height; ++y, row += row_bytes) {
    if (!in.read_scanline(y, spec.z, format, row)) return false;
  }
  return true;
}

// Reads the whole image as floats. OpenImageIO 2.4 reads any image it is asked to convert through a
// buffer of about 64 MB, whatever the image's size: the reader child pays for it in address space (under
// its RLIMIT_AS), a sanitizer build in poisoning it (55 ms of the image fuzzer's 56 ms per input). Read
// in the file's own type (TypeDesc::UNKNOWN: straight into our buffer), then converted by the function
// OpenImageIO's own read converts with, the values are the same. Files whose channels differ in type
// keep OpenImageIO's path.
bool read_as_float(OIIO::ImageInput& in, std::size_t values, float* pixels) {
  const OIIO::ImageSpec& spec = in.spec();
  const auto read = [&](OIIO::TypeDesc format, void* into) {
    return reads_wrong_in_strips(in) ? read_row_by_row(in, format, into)
                                     : in.read_image(0, 0, 0, spec.nchannels, format, into);
  };
  if (!spec.channelformats.empty()) return read(OIIO::TypeDesc::FLOAT, pixels);
  if (spec.format == OIIO::TypeDesc::FLOAT) return read(OIIO::TypeDesc::UNKNOWN, pixels);
  std::vector<unsigned char> native(values * spec.format.size());
  if (!read(OIIO::TypeDesc::UNKNOWN, native.data())) return false;
  invert_white_is_zero_uint16(in, native);
  return OIIO::convert_pixel_values(spec.format, native.data(), OIIO::TypeDesc::FLOAT, pixels,
                                    static_cast<int>(values));
}

RawImage read_pixels(const std::filesystem::path& path, const ImageLimits& limits) {
  const OIIO::ImageSpec config = as_stored_config();
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) throw open_error(path, limits);
  const OIIO::ImageSpec& spec = in->spec();
  check_spec(path, spec, limits);

  RawImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  image.is_float = is_float_type(spec.format);
  if (spec.format == OIIO::TypeDesc::UINT8) image.code_max = 255;
  if (spec.format == OIIO::TypeDesc::UINT16) image.code_max = 65535;
  const std::size_t values = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height) *
                             static_cast<std::size_t>(spec.nchannels);
  image.pixels.resize(values);
  if (!read_as_float(*in, values, image.pixels.data())) {
    throw image_file_error(path, "truncated or corrupt: " + one_line(in->geterror()));
  }
  in->close();
  return image;
}

constexpr image_backend::Table kTable{image_backend::kVersion, &read_size, &read_pixels, &write_image};

}  // namespace
}  // namespace ph

// The module's one exported symbol (image_backend::kEntryPoint; the version script keeps it so).
// Only the reader the file's extension names may open it (.png, .tif, .exr, ...): by default OpenImageIO
// tries every format it knows on a file its reader refused, each a parser an image file could attack
// (docs/SERVICE.md, "Images").
extern "C" __attribute__((visibility("default"))) const ph::image_backend::Table* ph_image_backend_v1() {
  OIIO::attribute("try_all_readers", 0);
  return &ph::kTable;
}
