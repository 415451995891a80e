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

// Magic number and version field (version 2, the given flags).
Bytes start(std::uint32_t flags = 0) {
  const std::uint32_t version = 2 | flags;
  return {0x76,
          0x2f,
          0x31,
          0x01,
          static_cast<std::uint8_t>(version),
          static_cast<std::uint8_t>(version >> 8),
          static_cast<std::uint8_t>(version >> 16),
          static_cast<std::uint8_t>(version >> 24)};
}

// One attribute: name, type, a size field of `claimed` and `actual` bytes of value.
void add_attribute(Bytes& file, const std::string& name, const std::string& type, std::int32_t claimed,
                   std::size_t actual) {
  file.insert(file.end(), name.begin(), name.end());
  file.push_back(0);
  file.insert(file.end(), type.begin(), type.end());
  file.push_back(0);
  const auto size = static_cast<std::uint32_t>(claimed);
  for (int shift = 0; shift < 32; shift += 8) file.push_back(static_cast<std::uint8_t>(size >> shift));
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
