#include "config/image_io.hpp"
#include "common/unique_fd.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "config/exr_header.hpp"
#include "config/image_backend.hpp"
#include "config/image_header_check.hpp"
#include "config/image_png.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

// Raised by load_module, turned into a FieldError that names the image.
class ModuleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Where the image module may be, in the order tried: PH_IMAGE_MODULE alone when set (tests); otherwise
// beside the installed program (PH_IMAGE_MODULE_INSTALLED is relative to the program's folder, e.g.
// ../lib/pseudohaptic/ph_image_oiio.so), in the program's own folder (the image reader, installed in
// lib/pseudohaptic/), then where the build tree made it.
const char* module_from_environment() {
  const char* env = std::getenv("PH_IMAGE_MODULE");
  return env != nullptr && *env != '\0' ? env : nullptr;
}

std::vector<fs::path> module_candidates() {
  if (const char* env = module_from_environment()) return {fs::path(env)};
  std::vector<fs::path> candidates;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    candidates.push_back((self.parent_path() / PH_IMAGE_MODULE_INSTALLED).lexically_normal());
    candidates.push_back(self.parent_path() / image_backend::kModuleFile);
  }
  candidates.emplace_back(PH_IMAGE_MODULE_BUILT);
  return candidates;
}

// "PATH: reason"; dlerror() usually starts with the path already.
std::string failed(const fs::path& candidate, const char* error, const std::string& otherwise) {
  const std::string reason = error != nullptr ? error : otherwise;
  return reason.rfind(candidate.string() + ": ", 0) == 0 ? reason : candidate.string() + ": " + reason;
}

// The first candidate that loads and holds a table of our version. Never unloaded: OpenImageIO keeps
// caches and threads that live until exit. RTLD_LAZY, as for the libraries a program starts with (binding
// every symbol of OpenImageIO's ~260 libraries at once, RTLD_NOW, costs more than the program start did).
// RTLD_LOCAL: nothing the module brings resolves the program's own symbols.
const image_backend::Table* load_module() {
  std::string tried;
  for (const fs::path& candidate : module_candidates()) {
    if (!tried.empty()) tried += "; ";
    void* handle = ::dlopen(candidate.c_str(), RTLD_LAZY | RTLD_LOCAL);
    if (handle == nullptr) {
      tried += failed(candidate, ::dlerror(), "dlopen failed");
      continue;
    }
    void* symbol = ::dlsym(handle, image_backend::kEntryPoint);
    if (symbol == nullptr) {
      tried += failed(candidate, ::dlerror(), std::string("no symbol ") + image_backend::kEntryPoint);
      ::dlclose(handle);
      continue;
    }
    const image_backend::Table* table = reinterpret_cast<image_backend::EntryPoint>(symbol)();
    if (table == nullptr || table->version != image_backend::kVersion) {
      tried +=
          failed(candidate, nullptr,
                 "a module of another version (this program needs " + std::to_string(image_backend::kVersion) + ")");
      ::dlclose(handle);
      continue;
    }
    return table;
  }
  throw ModuleError("cannot load the image module (OpenImageIO) to read or write images; tried " +
                    std::string(module_from_environment() != nullptr ? "PH_IMAGE_MODULE: " : "") + tried);
}

// The image module, loaded on the first call. The cached table is this library's one piece of global
// state: loading is process-wide anyway (dlopen), the module is never unloaded, and passing a handle to
// every image function would change config/image_io.hpp for all its callers. A failed load caches
// nothing (the static's initialisation did not complete), so the next call tries again and says why again.
const image_backend::Table& backend(const fs::path& image) {
  try {
    static const image_backend::Table* const table = load_module();
    return *table;
  } catch (const ModuleError& e) {
    throw image_file_error(image, e.what());
  }
}

// OpenImageIO says only "Could not open file" where the file cannot be made: the file system's reason, first.
void check_writable(const fs::path& path) {
  const UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0666));
  if (!fd) throw image_file_error(path, std::string("cannot write: ") + std::strerror(errno));
}

// Code of a value in [0, 1] for the largest code `code_max`; a non-finite value writes 0.
std::uint16_t unorm_code(double v, double code_max) {
  if (!std::isfinite(v)) v = 0.0;
  return static_cast<std::uint16_t>(std::lround(std::clamp(v, 0.0, 1.0) * code_max));
}

// Writes values in [0, 1] (`channels` interleaved) as integer codes in the given encoding.
// A PNG just written, read back whole: the image module's writer reports success where the disk was full or the file
// size limit met, leaving it cut short (the module reads back the other formats itself).
void check_png_written(const fs::path& path) {
  try {
    read_png(path, ImageLimits{});
  } catch (const FieldError&) {
    throw image_file_error(path, "cannot write: the file reads back cut short or corrupt (a full disk?)");
  }
}

void write_unorm(const fs::path& path, std::int32_t width, std::int32_t height, int channels,
                 const std::vector<double>& values, ImageEncoding encoding) {
  if (encoding.bits != 8 && encoding.bits != 16) {
    throw image_file_error(path, "cannot write " + std::to_string(encoding.bits) + "-bit images, only 8 or 16");
  }
  const char* format = encoding.format == ImageFormat::tiff ? "tiff" : "png";
  if (encoding.bits == 8) {
    std::vector<std::uint8_t> codes(values.size());
    std::transform(values.begin(), values.end(), codes.begin(),
                   [](double v) { return static_cast<std::uint8_t>(unorm_code(v, 255.0)); });
    check_writable(path);
    backend(path).write_image(path, format, width, height, channels, image_backend::PixelType::uint8, codes.data());
    if (encoding.format == ImageFormat::png) check_png_written(path);
  } else {
    std::vector<std::uint16_t> codes(values.size());
    std::transform(values.begin(), values.end(), codes.begin(), [](double v) { return unorm_code(v, 65535.0); });
    check_writable(path);
    backend(path).write_image(path, format, width, height, channels, image_backend::PixelType::uint16, codes.data());
    if (encoding.format == ImageFormat::png) check_png_written(path);
  }
}

std::string lowercase_extension(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

// What can be refused before a decoder sees the file: an OpenEXR file whose headers claim more bytes than
// it holds, or an image beyond the limits (config/exr_header.hpp). The module opens a file only with the
// reader its extension names.
void check_before_decoding(const fs::path& path, const ImageLimits& limits) {
  if (lowercase_extension(path) == ".exr") check_exr_header(path, limits);
}

// Whether the file begins with the PNG signature, whatever its name says.
bool starts_as_png(const fs::path& path) {
  constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd) return false;
  unsigned char head[sizeof kSignature] = {};
  const ssize_t n = ::read(fd.get(), head, sizeof head);
  return n == static_cast<ssize_t>(sizeof head) && std::memcmp(head, kSignature, sizeof head) == 0;
}

// A file named .png, or one that is a PNG under another name (a map saved without its extension), is read with
// libpng here (config/image_png.hpp), without loading the module.
bool read_here(const fs::path& path) { return lowercase_extension(path) == ".png" || starts_as_png(path); }

// A folder named as an image is said as such, not as a format no reader knows or a file that is not a PNG; a FIFO, a
// device or a socket too, before an open() or read() that would wait for ever for a writer that never comes (the
// daemon's reader is given up after two minutes, a tool's is not; and no image reader reads a stream whole).
void check_a_regular_file(const fs::path& path) {
  std::error_code ignored;
  const fs::file_status status = fs::status(path, ignored);  // (through links; missing: the open says so)
  if (fs::is_directory(status)) throw image_file_error(path, "is a folder, not an image file");
  if (fs::exists(status) && !fs::is_regular_file(status))
    throw image_file_error(path, "is not a regular file (a FIFO, a device or a socket), not an image file");
  if (fs::is_regular_file(status) && fs::file_size(path, ignored) == 0)
    throw image_file_error(path, "is empty (0 bytes), not an image file");
}

// Maps are PNG, TIFF or OpenEXR (docs/pseudohapticd.8): the module's other readers (JPEG, BMP, GIF, ...) are neither
// documented nor fuzzed (docs/FUZZING.md), and a lossy format's artefacts are relief the hand would feel.
void check_a_map_format(const fs::path& path) {
  const std::string extension = lowercase_extension(path);
  std::error_code ignored;
  if (extension == ".tif" || extension == ".tiff" || extension == ".exr" || !fs::exists(path, ignored)) return;
  throw image_file_error(path, (extension.empty() ? std::string("not a PNG and named without an extension")
                                                  : "a " + extension + " file, a format not read here") +
                                   ": maps are PNG, TIFF or OpenEXR files (.png, .tif, .tiff, .exr); convert it to "
                                   "one of those (a 16-bit PNG for a depth map)");
}

}  // namespace

ImageSize read_image_size(const fs::path& path, const ImageLimits& limits) {
  check_a_regular_file(path);
  if (read_here(path)) return read_png_size(path, limits);
  check_a_map_format(path);
  check_before_decoding(path, limits);
  return backend(path).read_image_size(path, limits);
}

RawImage read_image(const fs::path& path, const ImageLimits& limits) {
  check_a_regular_file(path);
  if (read_here(path)) return read_png(path, limits);
  check_a_map_format(path);
  return read_image_with_openimageio(path, limits);
}

RawImage read_image_with_openimageio(const fs::path& path, const ImageLimits& limits) {
  check_before_decoding(path, limits);
  return backend(path).read_image(path, limits);
}

void write_normal_image(const std::filesystem::path& path, const NormalImage& normals, ImageEncoding encoding) {
  std::vector<double> values;
  values.reserve(normals.values.size() * 3);
  for (const Normal& n : normals.values) {
    // Tangent space, OpenGL convention: +green points to the top of the image, screen -y.
    values.push_back((n.x + 1.0) / 2.0);
    values.push_back((-n.y + 1.0) / 2.0);
    values.push_back((n.z + 1.0) / 2.0);
  }
  write_unorm(path, normals.width, normals.height, 3, values, encoding);
}

void write_normal_png16(const std::filesystem::path& path, const NormalImage& normals) {
  write_normal_image(path, normals, {ImageFormat::png, 16});
}

void write_gray_image(const std::filesystem::path& path, const Grid<float>& values, ImageEncoding encoding) {
  write_unorm(path, values.width, values.height, 1, std::vector<double>(values.values.begin(), values.values.end()),
              encoding);
}

void write_gray_png16(const std::filesystem::path& path, const Grid<float>& values) {
  write_gray_image(path, values, {ImageFormat::png, 16});
}

void write_float_exr(const std::filesystem::path& path, const Grid<float>& values) {
  check_writable(path);
  backend(path).write_image(path, "openexr", values.width, values.height, 1, image_backend::PixelType::float32,
                            values.values.data());
}

void write_rgb_png8(const std::filesystem::path& path, std::int32_t width, std::int32_t height,
                    const std::vector<std::uint8_t>& rgb) {
  if (rgb.size() != static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0)) * 3)
    throw image_file_error(path, "cannot write: pixel count does not match the size");
  check_writable(path);
  backend(path).write_image(path, "png", width, height, 3, image_backend::PixelType::uint8, rgb.data());
  check_png_written(path);
}

}  // namespace ph
