#include "config/image_png.hpp"

#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/image_header_check.hpp"
#include "config/png_whole.hpp"

namespace ph {
namespace {

// What libpng said last, filled by its error callback before it jumps back: plain chars, since no C++ object may
// live in a frame that a longjmp leaves.
struct PngMessage {
  char text[200] = {};
};

[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  auto* said = static_cast<PngMessage*>(png_get_error_ptr(png));
  std::snprintf(said->text, sizeof said->text, "%s", message != nullptr ? message : "unknown error");
  png_longjmp(png, 1);
}

void on_warning(png_structp /*png*/, png_const_charp /*message*/) {}

// libpng's own reader says only "Read Error" when the file ends early, the usual way a PNG is broken.
void read_from_file(png_structp png, png_bytep data, std::size_t length) {
  auto* file = static_cast<std::FILE*>(png_get_io_ptr(png));
  if (std::fread(data, 1, length, file) != length)
    png_error(png, std::ferror(file) != 0 ? "read error" : "the file ends before its image does");
}

// The header after the transforms OpenImageIO asks for.
struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int channels = 0;
  int bit_depth = 0;
  std::size_t row_bytes = 0;
  bool interlaced = false;
};

// An open PNG file and libpng's state for reading it; closes and frees both, however far open() got.
class PngFile {
 public:
  explicit PngFile(std::filesystem::path path) : path_(std::move(path)) {}
  ~PngFile() {
    if (png_ != nullptr) png_destroy_read_struct(&png_, info_ != nullptr ? &info_ : nullptr, nullptr);
    if (file_ != nullptr) std::fclose(file_);
  }
  PngFile(const PngFile&) = delete;
  PngFile& operator=(const PngFile&) = delete;

  void open() {
    file_ = std::fopen(path_.c_str(), "rb");
    if (file_ == nullptr) throw image_file_error(path_, std::string("cannot open: ") + std::strerror(errno));
    unsigned char signature[8] = {};
    if (std::fread(signature, 1, sizeof signature, file_) != sizeof signature ||
        png_sig_cmp(signature, 0, sizeof signature) != 0) {
      throw image_file_error(path_, "cannot open: not a PNG file");
    }
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, &message_, on_error, on_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
    if (png_ == nullptr || info_ == nullptr) throw image_file_error(path_, "cannot open: out of memory");
  }

  // The header, refused by the limits as the image module refuses it.
  PngHeader header(const ImageLimits& limits) {
    PngHeader header;
    if (!read_info(header)) throw image_file_error(path_, std::string("cannot open: ") + message_.text);
    // The size before libpng's next step, which allocates a row for the width whatever it is.
    if (const std::string refusal = image_size_refusal(header.width, header.height, 1, limits); !refusal.empty())
      throw image_file_error(path_, refusal);
    if (!read_layout(header)) throw image_file_error(path_, std::string("cannot open: ") + message_.text);
    const std::string refusal = image_size_refusal(header.width, header.height, header.channels, limits);
    if (!refusal.empty()) throw image_file_error(path_, refusal);
    return header;
  }

  // Every row of the image in turn, each given to `take(y, row)` (header.row_bytes each) as soon as it is read: a
  // file stored row by row is read into one row's buffer, so that the stored codes of a large map never lie in
  // memory whole beside their floats; an interlaced one, whose seven passes each fill every row in part, is read
  // whole first.
  template <typename Take>
  void read_rows(const PngHeader& header, const Take& take) {
    auto corrupt = [&] { return image_file_error(path_, std::string("truncated or corrupt: ") + message_.text); };
    if (header.interlaced) {
      std::vector<unsigned char> pixels(header.row_bytes * header.height);
      std::vector<png_bytep> rows(header.height);
      for (png_uint_32 y = 0; y < header.height; ++y) rows[y] = pixels.data() + header.row_bytes * y;
      if (!read_image(rows.data())) throw corrupt();
      for (png_uint_32 y = 0; y < header.height; ++y) take(y, rows[y]);
    } else {
      std::vector<unsigned char> row(header.row_bytes);
      for (png_uint_32 y = 0; y < header.height; ++y) {
        if (!read_row(row.data())) throw corrupt();
        take(y, row.data());
      }
    }
    if (!read_end()) throw corrupt();
  }

 private:
  // libpng's calls, each in a function whose frame holds nothing a longjmp back to it would have to destroy.
  // The chunks before the pixels; the size from the header alone (nothing allocated for it yet).
  bool read_info(PngHeader& header) {
    if (setjmp(png_jmpbuf(png_)) != 0) return false;
    png_set_read_fn(png_, file_, read_from_file);
    png_set_sig_bytes(png_, 8);
    // libpng's own limit (1,000,000 px a side) would refuse a larger header as "Invalid IHDR data" before the limits
    // of image_size_refusal (config/image_header_check.hpp) say plainly what is too large: PNG's own bound here, ours
    // checked (header()) before read_layout allocates anything for that size.
    png_set_user_limits(png_, PNG_UINT_31_MAX, PNG_UINT_31_MAX);
    png_read_info(png_, info_);
    header.width = png_get_image_width(png_, info_);
    header.height = png_get_image_height(png_, info_);
    return true;
  }
  // The pixels' layout as they will be read (libpng allocates its row buffers here).
  bool read_layout(PngHeader& header) {
    if (setjmp(png_jmpbuf(png_)) != 0) return false;
    png_set_expand(png_);              // 1, 2 and 4-bit grey to 8 bits, a palette to RGB, a transparent colour to alpha
    png_set_interlace_handling(png_);  // an interlaced file's 7 passes; 16-bit samples stay big-endian, as stored
    png_read_update_info(png_, info_);
    header.channels = png_get_channels(png_, info_);
    header.bit_depth = png_get_bit_depth(png_, info_);
    header.row_bytes = png_get_rowbytes(png_, info_);
    header.interlaced = png_get_interlace_type(png_, info_) != PNG_INTERLACE_NONE;
    return true;
  }
  bool read_image(png_bytepp rows) {
    if (setjmp(png_jmpbuf(png_)) != 0) return false;
    png_read_image(png_, rows);
    return true;
  }
  bool read_row(png_bytep row) {
    if (setjmp(png_jmpbuf(png_)) != 0) return false;
    png_read_row(png_, row, nullptr);
    return true;
  }
  bool read_end() {
    if (setjmp(png_jmpbuf(png_)) != 0) return false;
    png_read_end(png_, nullptr);
    return true;
  }

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
  PngMessage message_;
};

}  // namespace

ImageSize read_png_size(const std::filesystem::path& path, const ImageLimits& limits) {
  PngFile file(path);
  file.open();
  const PngHeader header = file.header(limits);
  return {static_cast<std::int32_t>(header.width), static_cast<std::int32_t>(header.height),
          header.bit_depth == 16 ? 65535u : 255u};
}

RawImage read_png(const std::filesystem::path& path, const ImageLimits& limits) {
  if (std::optional<RawImage> whole = read_png_whole(path, limits)) return std::move(*whole);
  return read_png_with_libpng(path, limits);
}

RawImage read_png_with_libpng(const std::filesystem::path& path, const ImageLimits& limits) {
  PngFile file(path);
  file.open();
  const PngHeader header = file.header(limits);
  RawImage image = png_raw_image(header.width, header.height, header.channels, header.bit_depth);
  const std::size_t row_values = static_cast<std::size_t>(header.width) * header.channels;
  file.read_rows(header, [&](png_uint_32 y, const unsigned char* row) {
    png_row_to_float(row, header.bit_depth, row_values, image.pixels.data() + row_values * y);
  });
  return image;
}

}  // namespace ph
