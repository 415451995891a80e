#include "config/png_whole.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "config/image_header_check.hpp"

namespace ph {
namespace {

// The PNG specification's layout (ISO/IEC 15948): an 8-byte signature, then chunks of a 4-byte big-endian length,
// a 4-byte type, the data and a CRC-32 of type and data; IHDR first, IEND last.
constexpr std::array<unsigned char, 8> kSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
constexpr std::size_t kChunkFrame = 12;                                     // length, type, CRC
constexpr std::size_t kHeaderBytes = kSignature.size() + kChunkFrame + 13;  // the signature and a whole IHDR

std::uint32_t big_endian32(const unsigned char* p) {
  return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | std::uint32_t{p[3]};
}

constexpr std::uint32_t chunk_type(const char (&name)[5]) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(name[0])) << 24 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(name[1])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(name[2])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(name[3]));
}

// IHDR's fields this reader takes; anything else it leaves to libpng.
struct Layout {
  std::uint32_t width = 0, height = 0;
  int channels = 0;
  int bit_depth = 0;  // 8 or 16
  std::size_t pixel_bytes() const { return static_cast<std::size_t>(channels * bit_depth / 8); }
  std::size_t row_bytes() const { return std::size_t{width} * pixel_bytes(); }
};

std::optional<Layout> read_layout(const unsigned char* file) {
  if (std::memcmp(file, kSignature.data(), kSignature.size()) != 0) return std::nullopt;
  const unsigned char* chunk = file + kSignature.size();
  if (big_endian32(chunk) != 13 || big_endian32(chunk + 4) != chunk_type("IHDR")) return std::nullopt;
  const unsigned char* ihdr = chunk + 8;
  Layout layout;
  layout.width = big_endian32(ihdr);
  layout.height = big_endian32(ihdr + 4);
  const int bit_depth = ihdr[8], colour_type = ihdr[9];
  if (bit_depth != 8 && bit_depth != 16) return std::nullopt;  // 1, 2 and 4 bits: libpng widens them
  switch (colour_type) {                                       // 3, a palette: libpng expands it
    case 0:
      layout.channels = 1;
      break;
    case 2:
      layout.channels = 3;
      break;
    case 4:
      layout.channels = 2;
      break;
    case 6:
      layout.channels = 4;
      break;
    default:
      return std::nullopt;
  }
  layout.bit_depth = bit_depth;
  // Compression and filter method 0 (the only ones defined); interlace 0 (none: Adam7's passes are libpng's).
  if (ihdr[10] != 0 || ihdr[11] != 0 || ihdr[12] != 0) return std::nullopt;
  return layout;
}

// Whether a file of `size` bytes is no longer than an image of `raw_bytes` stored in the worst case could be
// (deflate's stored blocks add 5 bytes per 65535; chunks and ancillary data a little more): libpng reads a longer one
// as a stream.
bool plausible_size(long size, std::size_t raw_bytes) {
  return size >= 0 && static_cast<std::size_t>(size) <= raw_bytes + raw_bytes / 8 + (std::size_t{1} << 20);
}

// The zlib stream of the image: the data of every IDAT chunk, which must follow one another. Every chunk's CRC
// must hold, the file must end with IEND, and no chunk may be one that changes the samples libpng gives (tRNS, a
// transparent colour, becomes an alpha channel) or that this reader does not know and must understand (a critical
// chunk: its type's first letter upper case). PLTE, a suggested palette in an RGB image (`colour`) before the image
// data, changes nothing.
std::optional<std::vector<unsigned char>> image_data(const std::vector<unsigned char>& file, bool colour) {
  std::vector<unsigned char> data;
  bool in_idat = false, idat_done = false;
  std::size_t at = kSignature.size();
  while (at + kChunkFrame <= file.size()) {
    const std::uint32_t length = big_endian32(&file[at]);
    if (length > file.size() - at - kChunkFrame) return std::nullopt;
    const unsigned char* type_and_data = &file[at + 4];
    const std::uint32_t type = big_endian32(type_and_data);
    const auto letter = [](unsigned char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); };
    if (!std::all_of(type_and_data, type_and_data + 4, letter)) return std::nullopt;  // libpng refuses it
    const unsigned char* body = type_and_data + 4;
    if (libdeflate_crc32(0, type_and_data, std::size_t{length} + 4) != big_endian32(body + length)) return std::nullopt;
    const bool first = at == kSignature.size();
    at += kChunkFrame + length;
    if (first != (type == chunk_type("IHDR"))) return std::nullopt;
    if (type == chunk_type("IDAT")) {
      if (idat_done) return std::nullopt;
      in_idat = true;
      data.insert(data.end(), body, body + length);
      continue;
    }
    idat_done = in_idat;
    if (type == chunk_type("IEND")) return idat_done ? std::optional(std::move(data)) : std::nullopt;
    const bool critical = ((type >> 24) & 0x20) == 0;
    const bool suggested_palette = type == chunk_type("PLTE") && colour && !in_idat;
    if (type == chunk_type("tRNS") || (critical && !first && !suggested_palette)) return std::nullopt;
  }
  return std::nullopt;  // no IEND
}

// The bytes of one pixel (up to 8) as 16-bit lanes, for the Paeth filter a pixel at a time: the compiler's vector
// extension (GCC and clang; SSE2 on x86-64). Reading a pixel reads 8 bytes, past the pixel's own: the rows it
// reads are padded (kPad).
using Bytes8 = unsigned char __attribute__((vector_size(8)));
using Lanes = std::int16_t __attribute__((vector_size(16)));
constexpr std::size_t kPad = 8;

Lanes load_pixel(const unsigned char* p) {
  Bytes8 bytes;
  std::memcpy(&bytes, p, sizeof bytes);
  return __builtin_convertvector(bytes, Lanes);
}

template <std::size_t Bpp>
void store_pixel(unsigned char* p, Lanes v) {
  const Bytes8 bytes = __builtin_convertvector(v, Bytes8);  // the low 8 bits of each lane
  std::memcpy(p, &bytes, Bpp);
}

Lanes abs_lanes(Lanes v) {
  const Lanes negative = v < 0;
  return (v & ~negative) | (-v & negative);
}

// Paeth: each byte plus whichever of left (a), above (b) and upper left (c) is nearest to a + b - c, ties to a, then
// b; all bytes of a pixel at once, with selects: which of the three wins changes from byte to byte. The pixel left
// of the first, and the one above it, are zero.
template <std::size_t Bpp>
void unpaeth(unsigned char* row, const unsigned char* prev, std::size_t n) {
  Lanes a{}, c{};
  for (std::size_t i = 0; i < n; i += Bpp) {
    const Lanes b = load_pixel(prev + i), x = load_pixel(row + i);
    const Lanes pa = abs_lanes(b - c), pb = abs_lanes(a - c), pc = abs_lanes(a + b - c - c);
    const Lanes take_a = (pa <= pb) & (pa <= pc), take_b = ~take_a & (pb <= pc);
    const Lanes predictor = (a & take_a) | (b & take_b) | (c & ~(take_a | take_b));
    a = (x + predictor) & 0xff;
    store_pixel<Bpp>(row + i, a);
    c = b;
  }
}

// Undoes the filter of one row in place (`prev`: the row before, already unfiltered; zeros for the first), `n` bytes
// with `bpp` (1-8) bytes per pixel, both rows readable 8 bytes past their end; false for a filter type PNG does not
// define.
bool unfilter(int filter, unsigned char* row, const unsigned char* prev, std::size_t n, std::size_t bpp) {
  switch (filter) {
    case 0:
      return true;
    case 1:  // Sub: the byte bpp to the left
      for (std::size_t i = bpp; i < n; ++i) row[i] = static_cast<unsigned char>(row[i] + row[i - bpp]);
      return true;
    case 2:  // Up: the byte above
      for (std::size_t i = 0; i < n; ++i) row[i] = static_cast<unsigned char>(row[i] + prev[i]);
      return true;
    case 3:  // Average of left and above
      for (std::size_t i = 0; i < bpp; ++i) row[i] = static_cast<unsigned char>(row[i] + (prev[i] >> 1));
      for (std::size_t i = bpp; i < n; ++i)
        row[i] = static_cast<unsigned char>(row[i] + ((unsigned{row[i - bpp]} + prev[i]) >> 1));
      return true;
    case 4: {
      // One instance per pixel size of 8- and 16-bit grey, grey and alpha, RGB, RGBA.
      using Unpaeth = void (*)(unsigned char*, const unsigned char*, std::size_t);
      constexpr std::array<Unpaeth, 9> kByPixelSize{nullptr, unpaeth<1>, unpaeth<2>, unpaeth<3>, unpaeth<4>,
                                                    nullptr, unpaeth<6>, nullptr,    unpaeth<8>};
      if (bpp >= kByPixelSize.size() || kByPixelSize[bpp] == nullptr) return false;
      kByPixelSize[bpp](row, prev, n);
      return true;
    }
    default:
      return false;
  }
}

}  // namespace

RawImage png_raw_image(std::uint32_t width, std::uint32_t height, int channels, int bit_depth) {
  RawImage image;
  image.width = static_cast<std::int32_t>(width);
  image.height = static_cast<std::int32_t>(height);
  image.channels = channels;
  image.is_float = false;
  image.code_max = bit_depth == 16 ? 65535 : 255;
  image.pixels.resize(std::size_t{width} * height * static_cast<std::size_t>(channels));
  return image;
}

// Eight samples at a time in vector lanes, each lane the scalar conversion and product, so the same bits.
void png_row_to_float(const unsigned char* row, int bit_depth, std::size_t count, float* out) {
  using Codes8 = std::uint16_t __attribute__((vector_size(16)));
  using Floats8 = float __attribute__((vector_size(32)));
  std::size_t i = 0;
  if (bit_depth == 16) {
    constexpr float kScale = 1.0f / 65535.0f;
    for (; i + 8 <= count; i += 8) {
      Codes8 codes;
      std::memcpy(&codes, row + 2 * i, sizeof codes);
      codes = static_cast<Codes8>(codes >> 8 | codes << 8);  // big-endian samples
      const Floats8 values = __builtin_convertvector(codes, Floats8) * kScale;
      std::memcpy(out + i, &values, sizeof values);
    }
    for (; i < count; ++i) out[i] = static_cast<float>(unsigned{row[2 * i]} << 8 | row[2 * i + 1]) * kScale;
  } else {
    constexpr float kScale = 1.0f / 255.0f;
    for (; i + 8 <= count; i += 8) {
      Bytes8 codes;
      std::memcpy(&codes, row + i, sizeof codes);
      const Floats8 values = __builtin_convertvector(codes, Floats8) * kScale;
      std::memcpy(out + i, &values, sizeof values);
    }
    for (; i < count; ++i) out[i] = static_cast<float>(row[i]) * kScale;
  }
}

std::optional<RawImage> read_png_whole(const std::filesystem::path& path, const ImageLimits& limits) {
  // The header first, from the file's first bytes: a file beyond the limits is never read whole.
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> stream(std::fopen(path.c_str(), "rb"), &std::fclose);
  std::array<unsigned char, kHeaderBytes> head{};
  if (stream == nullptr || std::fread(head.data(), 1, head.size(), stream.get()) != head.size()) return std::nullopt;
  const std::optional<Layout> layout = read_layout(head.data());
  if (!layout || !image_size_refusal(layout->width, layout->height, layout->channels, limits).empty())
    return std::nullopt;
  const std::size_t row_bytes = layout->row_bytes(), stride = row_bytes + 1;  // each row starts with its filter type
  const std::size_t raw_bytes = stride * layout->height;
  if (std::fseek(stream.get(), 0, SEEK_END) != 0) return std::nullopt;
  const long size = std::ftell(stream.get());
  if (!plausible_size(size, raw_bytes) || std::fseek(stream.get(), 0, SEEK_SET) != 0) return std::nullopt;
  std::optional<std::vector<unsigned char>> file(static_cast<std::size_t>(size));
  if (std::fread(file->data(), 1, file->size(), stream.get()) != file->size()) return std::nullopt;
  stream.reset();
  const std::optional<std::vector<unsigned char>> compressed = image_data(*file, layout->channels >= 3);
  file.reset();  // the image data is all it needs of the file
  if (!compressed) return std::nullopt;

  std::vector<unsigned char> raw(raw_bytes + kPad);
  {
    std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> inflater(
        libdeflate_alloc_decompressor(), &libdeflate_free_decompressor);
    std::size_t inflated = 0;
    // Exactly the image's bytes, the stream's Adler-32 checked; more data or less is libpng's to judge.
    if (inflater == nullptr ||
        libdeflate_zlib_decompress(inflater.get(), compressed->data(), compressed->size(), raw.data(), raw_bytes,
                                   &inflated) != LIBDEFLATE_SUCCESS ||
        inflated != raw_bytes) {
      return std::nullopt;
    }
  }

  RawImage image = png_raw_image(layout->width, layout->height, layout->channels, layout->bit_depth);
  const std::size_t row_values = std::size_t{layout->width} * layout->channels;
  const std::vector<unsigned char> zeros(row_bytes + kPad, 0);
  for (std::size_t y = 0; y < layout->height; ++y) {
    unsigned char* row = raw.data() + y * stride + 1;
    const unsigned char* prev = y == 0 ? zeros.data() : row - stride;
    if (!unfilter(row[-1], row, prev, row_bytes, layout->pixel_bytes())) return std::nullopt;
    png_row_to_float(row, layout->bit_depth, row_values, image.pixels.data() + row_values * y);
  }
  return image;
}

}  // namespace ph
