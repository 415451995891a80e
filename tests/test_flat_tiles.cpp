// The flat tiles (core/engine/flat_tiles.hpp): advance()'s judgement that a frame is far from every region, and
// the inline flat frame it then makes, which must be the walk's own to the bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "core/engine/flat_tiles.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/traversal.hpp"

namespace ph {
namespace {

bool surely_flat(const FlatTiles& tiles, Vec2 p, Vec2 motor) {
  return tiles.surely_flat(Double2{p.x, p.y}, Double2{motor.x, motor.y});
}

// Whether the segment from p by motor touches the closed box of r (its bounding box does: conservative, as the
// flat tiles must be).
bool touches(const Rect& r, Vec2 p, Vec2 motor) {
  const Vec2 end = p + motor;
  return std::max(p.x, end.x) >= r.x && std::min(p.x, end.x) <= static_cast<double>(r.x) + r.w &&
         std::max(p.y, end.y) >= r.y && std::min(p.y, end.y) <= static_cast<double>(r.y) + r.h;
}

// Distance from p to the closed box of r along the nearer axis gap (0 inside or on it), the larger of the two.
double gap(const Rect& r, Vec2 p) {
  const double dx = std::max({r.x - p.x, p.x - (static_cast<double>(r.x) + r.w), 0.0});
  const double dy = std::max({r.y - p.y, p.y - (static_cast<double>(r.y) + r.h), 0.0});
  return std::max(dx, dy);
}

TEST(FlatTiles, WithoutRegionsEveryShortFiniteMotorIsFlat) {
  const FlatTiles tiles;
  const double tile = tiles.tile_px();
  EXPECT_TRUE(surely_flat(tiles, {960.5, 540.25}, {3.0, -4.0}));
  EXPECT_TRUE(surely_flat(tiles, {-1e6, 2e6}, {tile, -tile}));
  EXPECT_FALSE(surely_flat(tiles, {960.5, 540.25}, {tile * 1.01, 0.0}));  // longer than a tile: not judged
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(surely_flat(tiles, {0.0, 0.0}, {nan, 1.0}));
  EXPECT_FALSE(surely_flat(tiles, {0.0, 0.0}, {1.0, -inf}));
  // Near the world's limits the walk clamps the cursor: not judged.
  EXPECT_FALSE(surely_flat(tiles, {FlatTiles::kNearPx, 0.0}, {1.0, 1.0}));
  EXPECT_FALSE(surely_flat(tiles, {0.0, -0.9 * kWorldLimitPx}, {1.0, 1.0}));
}

TEST(FlatTiles, NeverJudgesFlatAFrameThatTouchesARegionAndJudgesTheFarOnes) {
  std::mt19937_64 rng(31);
  std::uniform_int_distribution<int> place(-3000, 3000), side(1, 600);
  for (int scene = 0; scene < 20; ++scene) {
    std::vector<Rect> boxes;
    const int count = 1 + scene % 7;
    for (int i = 0; i < count; ++i) boxes.push_back({place(rng), place(rng), side(rng), side(rng)});
    const FlatTiles tiles(boxes);
    const double tile = tiles.tile_px();
    ASSERT_GE(tile, FlatTiles::kMinTilePx);
    std::uniform_real_distribution<double> where(-4500.0, 4500.0), motion(-tile, tile);
    int far = 0, judged_far = 0;
    for (int i = 0; i < 20000; ++i) {
      // Whole coordinates and tile-long motions too: the edges of tiles and boxes.
      Vec2 p{where(rng), where(rng)};
      if (i % 3 == 0) p = {std::round(p.x), std::round(p.y)};
      Vec2 motor{motion(rng), motion(rng)};
      if (i % 5 == 0) motor = {i % 2 == 0 ? tile : -tile, 0.0};
      const bool flat = surely_flat(tiles, p, motor);
      bool near = false;
      double nearest = std::numeric_limits<double>::infinity();
      for (const Rect& r : boxes) {
        near = near || touches(r, p, motor);
        nearest = std::min(nearest, gap(r, p));
      }
      ASSERT_FALSE(flat && near) << "scene " << scene << " p " << p.x << "," << p.y << " motor " << motor.x << ","
                                 << motor.y;
      // A point three tiles and the margin away from every box lies in an unmarked tile or off the grid.
      if (nearest > 3.0 * tile + 2.0) {
        ++far;
        judged_far += flat ? 1 : 0;
      }
    }
    EXPECT_GT(far, 1000);
    EXPECT_EQ(judged_far, far) << "scene " << scene;
  }
}

TEST(FlatTiles, AGridTooNearTheWorldsLimitsJudgesOnlyTheZeroMotor) {
  const std::vector<Rect> boxes = {{0, 0, 100, 100}, {static_cast<std::int32_t>(FlatTiles::kNearPx) - 50, 0, 10, 10}};
  const FlatTiles tiles(boxes);
  EXPECT_FALSE(surely_flat(tiles, {5000.0, 5000.0}, {1.0, 0.0}));
  EXPECT_FALSE(surely_flat(tiles, {-1e6, 5000.0}, {0.0, 1.0}));
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// advance() takes a frame it judges far from every region inline; advance_near_regions() always goes the walk's
// way (the region list, then the flat crossing). Both must leave the cursor and report the frame alike, bit for bit.
TEST(FlatTiles, TheInlineFlatFrameIsTheWalksToTheBit) {
  std::vector<Region> regions;
  for (Rect rect : {Rect{0, 0, 300, 300}, Rect{1620, 0, 300, 300}, Rect{0, 780, 300, 300}, Rect{700, 400, 5, 3}}) {
    Region region;
    region.rect = rect;
    region.fields.gradient = GradientField(rect.w, rect.h, Gradient{0.3f, -0.2f});
    region.method = std::make_shared<CurvatureMethod>(CurvatureParams{});
    regions.push_back(std::move(region));
  }
  const Scene scene(std::move(regions));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 7);
  CursorState fast = cursor_at({960.0, 540.0}), slow = fast;
  int inline_frames = 0;
  for (int i = 0; i < 50000; ++i) {
    Vec2 motor;
    switch (kind(rng)) {
      case 0:
        motor = {std::floor(unit(rng) * 5.0) - 2.0, 0.0};
        break;  // whole px along x: positions stay whole
      case 1:
        motor = {0.0, std::floor(unit(rng) * 5.0) - 2.0};
        break;
      case 2:
        motor = {std::floor(unit(rng) * 5.0) - 2.0, std::floor(unit(rng) * 5.0) - 2.0};
        break;
      case 3:
        motor = {-0.0, 0.5 * std::floor(unit(rng) * 9.0) - 2.0};
        break;
      case 4:
        motor = {0.0, 0.0};
        break;
      default: {
        const double angle = 2.0 * std::acos(-1.0) * unit(rng), length = 40.0 * unit(rng);
        motor = {length * std::cos(angle), length * std::sin(angle)};
      }
    }
    inline_frames += scene.flat_tiles().surely_flat(load2(fast.position), Double2{motor.x, motor.y}) ? 1 : 0;
    const FrameResult a = advance(scene, fast, motor);
    const FrameResult b = advance_near_regions(scene, slow, motor, kNoTime, nullptr);
    ASSERT_TRUE(same_bits(a.display.x, b.display.x) && same_bits(a.display.y, b.display.y)) << "frame " << i;
    ASSERT_TRUE(same_bits(a.cd_min, b.cd_min) && same_bits(a.cd_max, b.cd_max) && a.steps == b.steps) << "frame " << i;
    ASSERT_TRUE(same_bits(fast.position.x, slow.position.x) && same_bits(fast.position.y, slow.position.y))
        << "frame " << i;
    ASSERT_EQ(fast.texel, slow.texel) << "frame " << i;
    ASSERT_EQ(fast.came_from, slow.came_from) << "frame " << i;
    // Stay on the screen's middle, between the regions and sometimes across the small one.
    if (std::abs(fast.position.x - 960.0) > 500.0 || std::abs(fast.position.y - 540.0) > 300.0) {
      fast = slow = cursor_at({std::round(700.0 + 400.0 * unit(rng)), std::round(380.0 + 300.0 * unit(rng))});
    }
  }
  EXPECT_GT(inline_frames, 25000);  // most frames took the inline way: the comparison is not vacuous
  EXPECT_LT(inline_frames, 50000);
}

}  // namespace
}  // namespace ph
