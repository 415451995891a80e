// PNG files read with libpng (config/image_png.hpp) give what the image module's OpenImageIO gives, to the bit:
// every 8- and 16-bit code, every colour type and bit depth PNG has, palettes, transparent colours and
// interlacing; and a file beyond the limits is refused with the same words. The common PNG is read whole, its
// image data inflated in one call (config/png_whole.hpp): every filter, pixel size and chunking, and what it
// leaves to libpng.
#include "config/image_png.hpp"

#include <png.h>
#include <zlib.h>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "config/image_io.hpp"
#include "config/png_whole.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/thrown_message.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

// What a PNG file holds beyond its samples.
struct PngLayout {
  int bit_depth = 8;
  int color_type = PNG_COLOR_TYPE_GRAY;
  int interlace = PNG_INTERLACE_NONE;
  const png_color* palette = nullptr;
  int palette_size = 0;
  const png_byte* transparent_entries = nullptr;  // tRNS of a palette: alpha of its first entries
  int transparent_count = 0;
  const png_color_16* transparent_colour = nullptr;  // tRNS of grey or RGB: the one colour that is transparent
  int filters = PNG_ALL_FILTERS;  // which row filters the writer may choose from (PNG_FILTER_NONE ... _PAETH)
  std::size_t idat_bytes = 0;     // the largest IDAT chunk (0: libpng's 8 KiB)
};

// Writes a PNG with libpng itself (what OpenImageIO does not write: palettes, 1, 2 and 4-bit grey, a transparent
// colour, interlacing). `rows`: one pointer per row of samples packed as PNG stores them (16-bit big-endian).
// No C++ object lives in this frame, which libpng's error handling longjmps back to.
bool write_png(const char* path, png_uint_32 width, png_uint_32 height, const PngLayout& layout, png_bytepp rows) {
  std::FILE* file = std::fopen(path, "wb");
  if (file == nullptr) return false;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (info == nullptr || setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return false;
  }
  png_init_io(png, file);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, layout.filters);
  if (layout.idat_bytes != 0) png_set_compression_buffer_size(png, layout.idat_bytes);
  png_set_IHDR(png, info, width, height, layout.bit_depth, layout.color_type, layout.interlace,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (layout.palette != nullptr) png_set_PLTE(png, info, layout.palette, layout.palette_size);
  if (layout.transparent_entries != nullptr || layout.transparent_colour != nullptr) {
    png_set_tRNS(png, info, layout.transparent_entries, layout.transparent_count, layout.transparent_colour);
  }
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(file) == 0;
}

int samples_per_pixel(int color_type) {
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY_ALPHA:
      return 2;
    case PNG_COLOR_TYPE_RGB:
      return 3;
    case PNG_COLOR_TYPE_RGB_ALPHA:
      return 4;
    default:
      return 1;  // grey, palette
  }
}

// A width x height PNG of seeded random samples (palette indices below `palette_size` where there is one).
void write_random_png(const fs::path& path, png_uint_32 width, png_uint_32 height, const PngLayout& layout,
                      std::uint64_t seed) {
  const std::size_t bits_per_row = std::size_t{width} * samples_per_pixel(layout.color_type) * layout.bit_depth;
  const std::size_t row_bytes = (bits_per_row + 7) / 8;
  std::mt19937_64 rng(seed);
  std::vector<std::vector<png_byte>> rows(height, std::vector<png_byte>(row_bytes));
  for (std::vector<png_byte>& row : rows) {
    for (png_byte& b : row) b = static_cast<png_byte>(rng());
    if (layout.palette != nullptr) {  // indices of palette entries only: 8-bit indices here
      for (png_byte& b : row) b = static_cast<png_byte>(b % layout.palette_size);
    }
  }
  std::vector<png_bytep> pointers;
  for (std::vector<png_byte>& row : rows) pointers.push_back(row.data());
  ASSERT_TRUE(write_png(path.c_str(), width, height, layout, pointers.data())) << path;
}

// The two readers agree on everything a RawImage holds, every sample to the bit.
void expect_same_as_openimageio(const fs::path& path) {
  SCOPED_TRACE(path.filename().string());
  const RawImage ours = read_image(path);
  const RawImage theirs = read_image_with_openimageio(path);
  EXPECT_EQ(ours.width, theirs.width);
  EXPECT_EQ(ours.height, theirs.height);
  EXPECT_EQ(ours.channels, theirs.channels);
  EXPECT_EQ(ours.is_float, theirs.is_float);
  EXPECT_EQ(ours.code_max, theirs.code_max);
  ASSERT_EQ(ours.pixels.size(), theirs.pixels.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < ours.pixels.size(); ++i) {
    if (std::memcmp(&ours.pixels[i], &theirs.pixels[i], sizeof(float)) != 0) ++differ;
  }
  EXPECT_EQ(differ, 0u) << "of " << ours.pixels.size() << " samples";
  const ImageSize size = read_image_size(path);
  EXPECT_EQ(size.width, theirs.width);
  EXPECT_EQ(size.height, theirs.height);
  EXPECT_EQ(size.code_max, theirs.code_max);
}

TEST(ImagePng, EveryCodeAsOpenImageIOReadsIt) {
  const ScratchDir dir("image-png");
  // 16-bit grey, 256 x 256: code y * 256 + x, each of the 65536 once.
  std::vector<std::vector<png_byte>> rows(256, std::vector<png_byte>(512));
  for (int y = 0; y < 256; ++y) {
    for (int x = 0; x < 256; ++x) {
      rows[y][2 * x] = static_cast<png_byte>(y);  // big-endian: the high byte first
      rows[y][2 * x + 1] = static_cast<png_byte>(x);
    }
  }
  std::vector<png_bytep> pointers;
  for (std::vector<png_byte>& row : rows) pointers.push_back(row.data());
  ASSERT_TRUE(write_png((dir / "all16.png").c_str(), 256, 256, {.bit_depth = 16}, pointers.data()));
  expect_same_as_openimageio(dir / "all16.png");
  EXPECT_TRUE(read_png_whole(dir / "all16.png", {}).has_value());
  // 8-bit grey, 16 x 16: each of the 256 codes once.
  std::vector<std::vector<png_byte>> rows8(16, std::vector<png_byte>(16));
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) rows8[y][x] = static_cast<png_byte>(y * 16 + x);
  }
  std::vector<png_bytep> pointers8;
  for (std::vector<png_byte>& row : rows8) pointers8.push_back(row.data());
  ASSERT_TRUE(write_png((dir / "all8.png").c_str(), 16, 16, {}, pointers8.data()));
  expect_same_as_openimageio(dir / "all8.png");
  EXPECT_TRUE(read_png_whole(dir / "all8.png", {}).has_value());
}

TEST(ImagePng, EveryColourTypeAndDepthAsOpenImageIOReadsIt) {
  const ScratchDir dir("image-png");
  struct Case {
    const char* name;
    int color_type;
    int bit_depth;
  };
  const Case cases[] = {
      {"grey1", PNG_COLOR_TYPE_GRAY, 1},
      {"grey2", PNG_COLOR_TYPE_GRAY, 2},
      {"grey4", PNG_COLOR_TYPE_GRAY, 4},
      {"grey8", PNG_COLOR_TYPE_GRAY, 8},
      {"grey16", PNG_COLOR_TYPE_GRAY, 16},
      {"grey-alpha8", PNG_COLOR_TYPE_GRAY_ALPHA, 8},
      {"grey-alpha16", PNG_COLOR_TYPE_GRAY_ALPHA, 16},
      {"rgb8", PNG_COLOR_TYPE_RGB, 8},
      {"rgb16", PNG_COLOR_TYPE_RGB, 16},
      {"rgba8", PNG_COLOR_TYPE_RGB_ALPHA, 8},
      {"rgba16", PNG_COLOR_TYPE_RGB_ALPHA, 16},
  };
  std::uint64_t seed = 1;
  for (const Case& c : cases) {
    for (int interlace : {PNG_INTERLACE_NONE, PNG_INTERLACE_ADAM7}) {
      const fs::path path = dir / (std::string(c.name) + (interlace == PNG_INTERLACE_ADAM7 ? "-adam7" : "") + ".png");
      write_random_png(path, 13, 7, {.bit_depth = c.bit_depth, .color_type = c.color_type, .interlace = interlace},
                       seed++);
      expect_same_as_openimageio(path);
    }
  }
}

TEST(ImagePng, PalettesAndTransparentColoursAsOpenImageIOReadsThem) {
  const ScratchDir dir("image-png");
  std::vector<png_color> palette(20);
  for (std::size_t i = 0; i < palette.size(); ++i) {
    palette[i] = {static_cast<png_byte>(13 * i), static_cast<png_byte>(255 - 7 * i), static_cast<png_byte>(i * i)};
  }
  const png_byte alphas[5] = {0, 40, 128, 200, 255};
  write_random_png(dir / "palette.png", 11, 9,
                   {.color_type = PNG_COLOR_TYPE_PALETTE, .palette = palette.data(), .palette_size = 20}, 7);
  expect_same_as_openimageio(dir / "palette.png");
  write_random_png(dir / "palette-alpha.png", 11, 9,
                   {.color_type = PNG_COLOR_TYPE_PALETTE,
                    .palette = palette.data(),
                    .palette_size = 20,
                    .transparent_entries = alphas,
                    .transparent_count = 5},
                   8);
  expect_same_as_openimageio(dir / "palette-alpha.png");
  // A transparent grey and a transparent RGB colour (16-bit): both readers add an alpha channel.
  png_color_16 grey{};
  grey.gray = 3;
  write_random_png(dir / "grey-trns.png", 9, 5, {.bit_depth = 2, .transparent_colour = &grey}, 9);
  expect_same_as_openimageio(dir / "grey-trns.png");
  png_color_16 rgb{};
  rgb.red = 0x1234;
  rgb.green = 0x5678;
  rgb.blue = 0x9abc;
  write_random_png(dir / "rgb-trns.png", 9, 5,
                   {.bit_depth = 16, .color_type = PNG_COLOR_TYPE_RGB, .transparent_colour = &rgb}, 10);
  expect_same_as_openimageio(dir / "rgb-trns.png");
}

// The maps the project's own tools write (through OpenImageIO) read back alike.
TEST(ImagePng, TheProjectsOwnMapsAsOpenImageIOReadsThem) {
  const ScratchDir dir("image-png");
  NormalImage normals(17, 5);
  Grid<float> heights(17, 5);
  for (std::int32_t x = 0; x < 17; ++x) {
    const float t = static_cast<float>(x) / 16.0f;
    for (std::int32_t y = 0; y < 5; ++y) {
      normals.at(x, y) = {0.6f * t, -0.3f * t, 0.8f};
      heights.at(x, y) = t * t;
    }
  }
  for (int bits : {8, 16}) {
    const std::string b = std::to_string(bits);
    write_normal_image(dir / ("normal" + b + ".png"), normals, {ImageFormat::png, bits});
    write_gray_image(dir / ("depth" + b + ".png"), heights, {ImageFormat::png, bits});
    expect_same_as_openimageio(dir / ("normal" + b + ".png"));
    expect_same_as_openimageio(dir / ("depth" + b + ".png"));
  }
}

// Each of the five row filters alone, for every pixel size the whole reader takes (1, 2, 3, 4, 6 and 8 bytes), in
// rows long enough for the filters to meet every case of their neighbours, and in chunks of 100 bytes of image data.
TEST(ImagePng, EveryFilterAndPixelSizeReadWholeAsOpenImageIOReadsIt) {
  const ScratchDir dir("image-png");
  const int filters[] = {PNG_FILTER_NONE, PNG_FILTER_SUB, PNG_FILTER_UP, PNG_FILTER_AVG, PNG_FILTER_PAETH};
  const int colour_types[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                              PNG_COLOR_TYPE_RGB_ALPHA};
  std::uint64_t seed = 100;
  for (int bit_depth : {8, 16}) {
    for (int colour_type : colour_types) {
      for (int f = 0; f < 5; ++f) {
        const fs::path path = dir / ("f" + std::to_string(f) + "-c" + std::to_string(colour_type) + "-" +
                                     std::to_string(bit_depth) + ".png");
        write_random_png(path, 37, 11, {.bit_depth = bit_depth, .color_type = colour_type, .filters = filters[f]},
                         seed++);
        EXPECT_TRUE(read_png_whole(path, {}).has_value()) << path;
        expect_same_as_openimageio(path);
      }
    }
  }
  const fs::path chunked = dir / "chunked.png";
  write_random_png(chunked, 40, 30, {.bit_depth = 16, .color_type = PNG_COLOR_TYPE_RGB, .idat_bytes = 100}, 7);
  EXPECT_TRUE(read_png_whole(chunked, {}).has_value());
  expect_same_as_openimageio(chunked);
}

// The offset of the first chunk of that type's data.
std::size_t chunk_data(const std::vector<unsigned char>& png, const char* type) {
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const std::size_t length =
        std::size_t{png[at]} << 24 | std::size_t{png[at + 1]} << 16 | std::size_t{png[at + 2]} << 8 | png[at + 3];
    if (std::memcmp(&png[at + 4], type, 4) == 0) return at + 8;
    at += 12 + length;
  }
  ADD_FAILURE() << "no " << type << " chunk";
  return 0;
}

// What the whole reader leaves to libpng: the layouts libpng transforms, and every file with something wrong in it,
// which libpng then reads, or refuses, as it did before there was a whole reader.
TEST(ImagePng, WhatTheWholeReaderLeavesToLibpng) {
  const ScratchDir dir("image-png");
  std::vector<png_color> palette(4, png_color{10, 20, 30});
  png_color_16 grey{};
  grey.gray = 7;
  const struct {
    const char* name;
    PngLayout layout;
  } layouts[] = {
      {"adam7", {.bit_depth = 16, .color_type = PNG_COLOR_TYPE_RGB, .interlace = PNG_INTERLACE_ADAM7}},
      {"palette", {.color_type = PNG_COLOR_TYPE_PALETTE, .palette = palette.data(), .palette_size = 4}},
      {"grey4", {.bit_depth = 4}},
      {"grey8-trns", {.transparent_colour = &grey}},
  };
  for (const auto& [name, layout] : layouts) {
    const fs::path path = dir / (std::string(name) + ".png");
    write_random_png(path, 9, 6, layout, 3);
    EXPECT_FALSE(read_png_whole(path, {}).has_value()) << name;
    expect_same_as_openimageio(path);
  }

  const fs::path good = dir / "good.png";
  write_random_png(good, 24, 16, {.bit_depth = 16, .color_type = PNG_COLOR_TYPE_RGB_ALPHA}, 5);
  ASSERT_TRUE(read_png_whole(good, {}).has_value());
  EXPECT_FALSE(read_png_whole(good, ImageLimits{.max_pixels = 100}).has_value());
  const std::vector<unsigned char> bytes = read_file_bytes<unsigned char>(good);

  std::vector<unsigned char> bad_data = bytes;  // the deflate stream's first block header
  bad_data[chunk_data(bytes, "IDAT") + 2] ^= 0x04;
  write_file_bytes(dir / "bad-data.png", bad_data);
  EXPECT_FALSE(read_png_whole(dir / "bad-data.png", {}).has_value());
  EXPECT_NE(thrown_message<FieldError>([&] { read_image(dir / "bad-data.png"); }).find("truncated or corrupt: IDAT"),
            std::string::npos);

  std::vector<unsigned char> bad_crc = bytes;  // IEND's, the file's last 4 bytes
  bad_crc.back() ^= 0x01;
  write_file_bytes(dir / "bad-crc.png", bad_crc);
  EXPECT_FALSE(read_png_whole(dir / "bad-crc.png", {}).has_value());
  EXPECT_NE(thrown_message<FieldError>([&] { read_image(dir / "bad-crc.png"); }).find("CRC error"), std::string::npos);

  const std::vector<unsigned char> truncated(bytes.begin(),
                                             bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2));
  write_file_bytes(dir / "truncated.png", truncated);
  EXPECT_FALSE(read_png_whole(dir / "truncated.png", {}).has_value());
  EXPECT_NE(thrown_message<FieldError>([&] {
              read_image(dir / "truncated.png");
            }).find("truncated or corrupt: the file ends before its image does"),
            std::string::npos);

  // A chunk of its own before IEND: an ancillary one (its type's first letter lower case) changes nothing; a type
  // that is not four letters libpng refuses, so the whole reader leaves it to libpng.
  const auto with_chunk_before_end = [&](const char* type) {
    std::vector<unsigned char> out(bytes.begin(), bytes.end() - 12);
    const unsigned char chunk[] = {0,
                                   0,
                                   0,
                                   1,
                                   static_cast<unsigned char>(type[0]),
                                   static_cast<unsigned char>(type[1]),
                                   static_cast<unsigned char>(type[2]),
                                   static_cast<unsigned char>(type[3]),
                                   42};
    const uLong crc = crc32(0, chunk + 4, 5);
    out.insert(out.end(), std::begin(chunk), std::end(chunk));
    for (int shift : {24, 16, 8, 0}) out.push_back(static_cast<unsigned char>(crc >> shift));
    out.insert(out.end(), bytes.end() - 12, bytes.end());
    return out;
  };
  write_file_bytes(dir / "ancillary.png", with_chunk_before_end("teSt"));
  EXPECT_TRUE(read_png_whole(dir / "ancillary.png", {}).has_value());
  expect_same_as_openimageio(dir / "ancillary.png");
  write_file_bytes(dir / "bad-type.png", with_chunk_before_end("te5t"));
  EXPECT_FALSE(read_png_whole(dir / "bad-type.png", {}).has_value());

  // No IEND: libpng has the image before it looks for one, and reads it.
  std::vector<unsigned char> no_end(bytes.begin(), bytes.end() - 12);
  write_file_bytes(dir / "no-end.png", no_end);
  EXPECT_FALSE(read_png_whole(dir / "no-end.png", {}).has_value());
}

TEST(ImagePng, ImagesBeyondTheLimitsAreRefusedInTheSameWords) {
  const ScratchDir dir("image-png");
  const fs::path path = dir / "rgba.png";
  write_random_png(path, 12, 10, {.color_type = PNG_COLOR_TYPE_RGB_ALPHA}, 11);
  for (const ImageLimits& limits :
       {ImageLimits{100, 32768, 16}, ImageLimits{1 << 20, 11, 16}, ImageLimits{1 << 20, 32768, 3}}) {
    const std::string ours = thrown_message<FieldError>([&] { read_image(path, limits); });
    const std::string theirs = thrown_message<FieldError>([&] { read_image_with_openimageio(path, limits); });
    EXPECT_EQ(ours, theirs);
    EXPECT_EQ(thrown_message<FieldError>([&] { read_image_size(path, limits); }), theirs);
    EXPECT_NE(ours.find("more than the limit"), std::string::npos) << ours;
  }
}

}  // namespace
}  // namespace ph
