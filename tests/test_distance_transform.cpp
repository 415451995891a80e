// The exact Euclidean distance transform with nearest feature (core/effects/distance_transform.hpp), against a
// brute-force search.
#include "core/effects/distance_transform.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <string>

namespace ph {
namespace {

using Mask = Grid<std::uint8_t>;

Mask random_mask(std::int32_t w, std::int32_t h, double density, std::mt19937& rng) {
  Mask m(w, h, 0);
  std::bernoulli_distribution set(density);
  for (auto& v : m.values) v = set(rng) ? 1 : 0;
  return m;
}

// Smallest squared distance from (x, y) to a set texel, or nullopt for an empty mask.
std::optional<std::int64_t> brute_force(const Mask& m, std::int32_t x, std::int32_t y) {
  std::optional<std::int64_t> best;
  for (std::int32_t v = 0; v < m.height; ++v) {
    for (std::int32_t u = 0; u < m.width; ++u) {
      if (m.at(u, v) == 0) continue;
      const std::int64_t d2 = std::int64_t{u - x} * (u - x) + std::int64_t{v - y} * (v - y);
      if (!best || d2 < *best) best = d2;
    }
  }
  return best;
}

// Every texel: within the radius, the exact squared distance and a nearest texel that is set and at that
// distance; beyond it, none.
void expect_exact(const Mask& m, float radius, const std::string& what) {
  const PatternField f = make_pattern_field(m, radius);
  ASSERT_EQ(f.width(), m.width) << what;
  ASSERT_EQ(f.height(), m.height) << what;
  const double r2 = static_cast<double>(f.radius) * f.radius;
  for (std::int32_t y = 0; y < m.height; ++y) {
    for (std::int32_t x = 0; x < m.width; ++x) {
      const std::optional<std::int64_t> want = brute_force(m, x, y);
      const std::optional<NearestPattern> got = f.nearest({x, y});
      const bool in_reach = want && static_cast<double>(*want) <= r2;
      ASSERT_EQ(got.has_value(), in_reach) << what << " at " << x << "," << y;
      if (!got) continue;
      ASSERT_EQ(got->distance_squared(), *want) << what << " at " << x << "," << y;
      const Texel t = got->target({x, y});
      ASSERT_TRUE(t.x >= 0 && t.y >= 0 && t.x < m.width && t.y < m.height) << what;
      ASSERT_NE(m.at(t.x, t.y), 0) << what << " at " << x << "," << y;
    }
  }
}

TEST(DistanceTransform, MatchesBruteForceOnRandomMasks) {
  std::mt19937 rng(20260521);
  const std::int32_t sizes[][2] = {{1, 1},  {1, 17},  {17, 1},  {2, 2},   {5, 5},  {31, 7},
                                   {7, 31}, {64, 48}, {48, 64}, {100, 3}, {3, 100}};
  const double densities[] = {0.0, 0.001, 0.01, 0.05, 0.2, 0.5, 0.9, 1.0};
  for (const auto& s : sizes) {
    for (double d : densities) {
      const Mask m = random_mask(s[0], s[1], d, rng);
      expect_exact(m, kMaxPatternRadius, std::to_string(s[0]) + "x" + std::to_string(s[1]) + " p=" + std::to_string(d));
    }
  }
}

TEST(DistanceTransform, MatchesBruteForceOnManySmallMasks) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int32_t> side(1, 24);
  std::uniform_real_distribution<double> density(0.0, 0.6);
  for (int i = 0; i < 400; ++i) {
    const std::int32_t w = side(rng);
    const std::int32_t h = side(rng);
    expect_exact(random_mask(w, h, density(rng), rng), kMaxPatternRadius, "case " + std::to_string(i));
  }
}

TEST(DistanceTransform, SingleTexelAndOneRow) {
  for (const Texel t : {Texel{0, 0}, Texel{39, 0}, Texel{0, 29}, Texel{39, 29}, Texel{17, 11}}) {
    Mask m(40, 30, 0);
    m.at(t.x, t.y) = 1;
    expect_exact(m, kMaxPatternRadius, "single " + std::to_string(t.x) + "," + std::to_string(t.y));
  }
  Mask row(40, 30, 0);
  for (std::int32_t x = 0; x < 40; ++x) row.at(x, 12) = 1;
  expect_exact(row, kMaxPatternRadius, "one row");
  Mask column(40, 30, 0);
  for (std::int32_t y = 0; y < 30; ++y) column.at(5, y) = 1;
  expect_exact(column, kMaxPatternRadius, "one column");
}

TEST(DistanceTransform, FarSingleTexelOnALargeGrid) {
  Mask m(700, 300, 0);
  m.at(650, 20) = 1;
  const PatternField f = make_pattern_field(m, kMaxPatternRadius);
  for (std::int32_t y = 0; y < 300; y += 7) {
    for (std::int32_t x = 0; x < 700; x += 3) {
      const std::optional<NearestPattern> n = f.nearest({x, y});
      ASSERT_TRUE(n);
      EXPECT_EQ(n->dx, 650 - x);
      EXPECT_EQ(n->dy, 20 - y);
    }
  }
}

TEST(DistanceTransform, RadiusCapIsExactWithinIt) {
  std::mt19937 rng(99);
  for (float r : {0.0f, 0.5f, 1.0f, 1.5f, 2.0f, 2.9f, 5.0f, 10.0f}) {
    expect_exact(random_mask(50, 37, 0.01, rng), r, "r=" + std::to_string(r));
    expect_exact(random_mask(50, 37, 0.2, rng), r, "r=" + std::to_string(r));
  }
  // A texel exactly at the radius is in reach: (3, 4) is 5 from the origin.
  Mask m(10, 10, 0);
  m.at(0, 0) = 1;
  EXPECT_TRUE(make_pattern_field(m, 5.0f).nearest({3, 4}));
  EXPECT_FALSE(make_pattern_field(m, 4.99f).nearest({3, 4}));
}

TEST(DistanceTransform, OddRadiiAreClamped) {
  Mask m(20, 20, 0);
  m.at(3, 3) = 1;
  for (float r : {-1.0f, std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::infinity()}) {
    const PatternField f = make_pattern_field(m, r);
    EXPECT_EQ(f.radius, 0.0f);
    EXPECT_TRUE(f.nearest({3, 3}));
    EXPECT_FALSE(f.nearest({3, 4}));
  }
  const PatternField inf = make_pattern_field(m, std::numeric_limits<float>::infinity());
  EXPECT_EQ(inf.radius, kMaxPatternRadius);
  EXPECT_TRUE(inf.nearest({19, 19}));
}

TEST(DistanceTransform, EmptyMaskGivesNoneEverywhere) {
  const PatternField f = make_pattern_field(Mask(33, 21, 0), kMaxPatternRadius);
  for (const PatternOffset& o : f.offsets.values) {
    EXPECT_EQ(o.dx, kNoPattern.dx);
    EXPECT_EQ(o.dy, kNoPattern.dy);
  }
  EXPECT_FALSE(f.nearest({0, 0}));
  EXPECT_FALSE(f.toward({10.5, 3.2}));
  const PatternField none = make_pattern_field(Mask{}, 10.0f);
  EXPECT_TRUE(none.offsets.empty());
  EXPECT_FALSE(none.nearest({0, 0}));
}

TEST(DistanceTransform, LookupOutsideTheGridAndToward) {
  Mask m(10, 8, 0);
  m.at(7, 2) = 1;
  const PatternField f = make_pattern_field(m, 100.0f);
  EXPECT_FALSE(f.nearest({-1, 0}));
  EXPECT_FALSE(f.nearest({10, 0}));
  EXPECT_FALSE(f.nearest({0, 8}));
  const std::optional<Vec2> v = f.toward({1.25, 5.75});  // texel (1, 5): pattern centre (7.5, 2.5)
  ASSERT_TRUE(v);
  EXPECT_DOUBLE_EQ(v->x, 6.25);
  EXPECT_DOUBLE_EQ(v->y, -3.25);
  EXPECT_FALSE(f.toward({std::numeric_limits<double>::quiet_NaN(), 1.0}));
  const std::optional<NearestPattern> n = f.nearest({1, 5});
  ASSERT_TRUE(n);
  EXPECT_DOUBLE_EQ(n->distance(), std::sqrt(36.0 + 9.0));
}

TEST(DistanceTransform, FourBytesPerTexel) {
  static_assert(sizeof(PatternOffset) == 4);
  const PatternField f = make_pattern_field(Mask(64, 32, 1), 8.0f);
  EXPECT_EQ(f.bytes(), 64u * 32u * 4u);
}

}  // namespace
}  // namespace ph
