// The OpenEXR header check that runs before OpenImageIO sees a file (config/exr_header.hpp): a file whose
// attributes claim more bytes than it holds is refused, any other layout is left to the decoder.
#include "config/exr_header.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace ph {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Appends a 32-bit value, little-endian as OpenEXR stores it.
void put32(Bytes& out, std::uint32_t v) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

// Magic number and version field (version 2, the given flags).
Bytes start(std::uint32_t flags = 0) {
  Bytes file = {0x76, 0x2f, 0x31, 0x01};
  put32(file, 2 | flags);
  return file;
}

// One attribute: name, type, a size field of `claimed` and `actual` bytes of value.
void add_attribute(Bytes& file, const std::string& name, const std::string& type, std::int32_t claimed,
                   std::size_t actual) {
  file.insert(file.end(), name.begin(), name.end());
  file.push_back(0);
  file.insert(file.end(), type.begin(), type.end());
  file.push_back(0);
  put32(file, static_cast<std::uint32_t>(claimed));
  file.insert(file.end(), actual, 0x2a);
}

std::optional<std::string> problem(const Bytes& file) { return exr_header_problem(file, file.size()); }

TEST(ExrHeader, AHeaderWhoseAttributesFitPasses) {
  Bytes file = start();
  add_attribute(file, "compression", "compression", 1, 1);
  add_attribute(file, "comments", "string", 5, 5);
  file.push_back(0);                  // end of header
  file.insert(file.end(), 16, 0x00);  // offset table and pixels follow
  EXPECT_EQ(problem(file), std::nullopt);
}

TEST(ExrHeader, AnAttributeClaimingMoreBytesThanTheFileHoldsIsRefused) {
  Bytes file = start();
  add_attribute(file, "compression", "compression", 1, 1);
  add_attribute(file, "comments", "string", 0x7fffffff, 3);
  file.push_back(0);
  const std::optional<std::string> why = problem(file);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("attribute 'comments' claims 2147483647 bytes, and the file has 4 left"), std::string::npos)
      << *why;
  // One byte more than the file holds is already too many.
  Bytes exact = start();
  add_attribute(exact, "comments", "string", 3, 3);
  exact.push_back(0);
  EXPECT_EQ(problem(exact), std::nullopt);
  Bytes one_over = start();
  add_attribute(one_over, "comments", "string", 5, 3);
  one_over.push_back(0);
  EXPECT_NE(problem(one_over), std::nullopt);
}

TEST(ExrHeader, ANegativeSizeIsRefused) {
  Bytes file = start();
  add_attribute(file, "comments", "string", -8, 0);
  file.push_back(0);
  const std::optional<std::string> why = problem(file);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("negative size (-8)"), std::string::npos) << *why;
}

TEST(ExrHeader, NotAnExrFileOrOneCutInsideItsHeaderIsRefused) {
  EXPECT_NE(problem({0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a, 0}), std::nullopt);
  EXPECT_NE(problem({0x76, 0x2f, 0x31}), std::nullopt);
  Bytes cut = start();
  add_attribute(cut, "compression", "compression", 1, 1);
  cut.insert(cut.end(), {'c', 'o', 'm'});  // the next name never ends
  EXPECT_NE(problem(cut), std::nullopt);
  Bytes long_name = start();
  long_name.insert(long_name.end(), 300, 'a');
  long_name.push_back(0);
  const std::optional<std::string> why = problem(long_name);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("longer than 255 bytes"), std::string::npos) << *why;
}

// OpenEXR reads a box2i as 16 bytes whatever its size field says, and the rest of the value as the next
// attribute: a walk by the size field would check other bytes than OpenEXR reads (a fuzzer's input that
// passed the size check this way made OpenEXR allocate a 2 GB attribute further on).
TEST(ExrHeader, AKnownFixedTypeWithAnotherSizeIsRefused) {
  Bytes file = start();
  add_attribute(file, "dataWindow", "box2i", 16, 16);
  add_attribute(file, "caow", "box2i", 20, 20);
  file.push_back(0);
  const std::optional<std::string> why = problem(file);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("attribute 'caow' of type box2i: size 20, not 16"), std::string::npos) << *why;
}

// The values OpenEXR reads with sizes of their own must end where the declared size does.
TEST(ExrHeader, ChannelListsStringVectorsAndPreviewsMustFitTheirSize) {
  const auto with_value = [](const std::string& type, const Bytes& value) {
    Bytes file = start();
    add_attribute(file, "a", type, static_cast<std::int32_t>(value.size()), 0);
    file.insert(file.end(), value.begin(), value.end());
    file.push_back(0);
    return file;
  };
  Bytes channel = {'Y', 0};
  channel.insert(channel.end(), 16, 0);
  Bytes chlist = channel;
  chlist.push_back(0);  // the list's end
  EXPECT_EQ(problem(with_value("chlist", chlist)), std::nullopt);
  Bytes unterminated = channel;
  EXPECT_NE(problem(with_value("chlist", unterminated)), std::nullopt);
  Bytes short_channel = {'Y', 0, 1, 2, 3, 0};
  EXPECT_NE(problem(with_value("chlist", short_channel)), std::nullopt);

  const Bytes two_strings = {2, 0, 0, 0, 'h', 'i', 0, 0, 0, 0};
  EXPECT_EQ(problem(with_value("stringvector", two_strings)), std::nullopt);
  const Bytes huge_string = {0xff, 0xff, 0xff, 0x7f, 'h', 'i'};
  const std::optional<std::string> why = problem(with_value("stringvector", huge_string));
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("a string claims 2147483647 bytes"), std::string::npos) << *why;

  Bytes preview = {1, 0, 0, 0, 2, 0, 0, 0};  // 1 x 2 px
  preview.insert(preview.end(), 8, 0x80);
  EXPECT_EQ(problem(with_value("preview", preview)), std::nullopt);
  const Bytes huge_preview = {0xff, 0xff, 0, 0, 0xff, 0xff, 0, 0, 1, 2, 3, 4};  // 65535 x 65535 px claimed
  EXPECT_NE(problem(with_value("preview", huge_preview)), std::nullopt);
}

// OpenEXR allocates its line buffers for the data window when it opens the file: a window beyond the limits
// is refused from the header, as the reader would refuse the image after opening it.
TEST(ExrHeader, ADataWindowOrChannelListBeyondTheLimitsIsRefused) {
  const auto with_window = [](std::int32_t xmax, std::int32_t ymax) {
    Bytes file = start();
    add_attribute(file, "dataWindow", "box2i", 16, 0);
    for (const std::int32_t v : {0, 0, xmax, ymax}) put32(file, static_cast<std::uint32_t>(v));
    file.push_back(0);
    return file;
  };
  ImageLimits limits;
  limits.max_side = 1024;
  limits.max_pixels = 1 << 16;
  limits.max_channels = 4;
  const Bytes fits = with_window(255, 255);
  EXPECT_EQ(exr_header_problem(fits, fits.size(), limits), std::nullopt);
  const Bytes wide = with_window(2047, 0);
  std::optional<std::string> why = exr_header_problem(wide, wide.size(), limits);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("image is 2048 x 1 px, more than the limit of 1024 px per side"), std::string::npos) << *why;
  const Bytes many = with_window(511, 511);
  EXPECT_NE(exr_header_problem(many, many.size(), limits), std::nullopt);
  const Bytes empty = with_window(-1, 0);
  EXPECT_NE(exr_header_problem(empty, empty.size(), limits), std::nullopt);

  Bytes chlist;
  for (const char c : {'R', 'G', 'B', 'A', 'Z'}) {
    chlist.push_back(static_cast<std::uint8_t>(c));
    chlist.push_back(0);
    chlist.insert(chlist.end(), 16, 0);
  }
  chlist.push_back(0);
  Bytes five = start();
  add_attribute(five, "channels", "chlist", static_cast<std::int32_t>(chlist.size()), 0);
  five.insert(five.end(), chlist.begin(), chlist.end());
  five.push_back(0);
  why = exr_header_problem(five, five.size(), limits);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("image has 5 channels, more than the limit of 4"), std::string::npos) << *why;
  EXPECT_EQ(exr_header_problem(five, five.size()), std::nullopt);  // the default limits: 16
}

TEST(ExrHeader, WhatTheFirstBytesDoNotShowIsNotJudged) {
  // A large value (a preview image, say) runs past the bytes read: the rest of the file is not checked.
  Bytes file = start();
  add_attribute(file, "preview", "preview", 100, 10);
  const std::uint64_t whole_size = file.size() + 90 + 1;
  EXPECT_EQ(exr_header_problem(file, whole_size), std::nullopt);
  // The same claim against a file that really ends there is refused.
  EXPECT_NE(exr_header_problem(file, file.size()), std::nullopt);
}

TEST(ExrHeader, EveryHeaderOfAMultipartFileIsChecked) {
  constexpr std::uint32_t kMultipart = 0x1000;
  Bytes file = start(kMultipart);
  add_attribute(file, "name", "string", 1, 1);
  file.push_back(0);  // end of the first part's header
  add_attribute(file, "name", "string", 1000000, 1);
  file.push_back(0);
  file.push_back(0);  // end of the list of headers
  const std::optional<std::string> why = problem(file);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("claims 1000000 bytes"), std::string::npos) << *why;
}

}  // namespace
}  // namespace ph
