// Which parts of the screen lie far from every region: a coarse grid of square tiles, each marked when some
// region's box comes within a tile (and a margin) of it. A frame that starts in an unmarked tile, or off the grid,
// and moves at most a tile along each axis cannot touch any region, so advance() can take it as flat without
// going through the region list: a pointer outside every region costs the same whatever the number of regions
// (docs/PERFORMANCE.md, "Outside every region").
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/engine/fast_math.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/pair_math.hpp"

namespace ph {

class FlatTiles {
 public:
  // The smallest and the largest tile side (px, powers of two). A tile grows from the smallest until the grid
  // holds at most kMaxTiles; a scene spread so wide that even the largest does not fit judges no frame.
  static constexpr double kMinTilePx = 64.0;
  static constexpr double kMaxTilePx = 4096.0;
  static constexpr std::size_t kMaxTiles = std::size_t{1} << 16;

  // Frames are judged only where they start within kNearPx of the origin along both axes: there no flat frame
  // comes near the world's limits, which would clamp it (core/engine/traversal.cpp).
  static constexpr double kNearPx = kWorldLimitPx / 4;

  // No regions: every frame short enough is far from them.
  FlatTiles() = default;
  // The closed boxes [x, x + w] x [y, y + h] of the regions.
  explicit FlatTiles(std::span<const Rect> boxes);

  // True when the segment from p by `motor` surely touches no region's closed box and starts within kNearPx: the
  // motor is finite and at most a tile along each axis, and p lies in an unmarked tile, or off the grid within
  // kNearPx. False says nothing. p must be finite (a cursor position always is).
  PH_ALWAYS_INLINE bool surely_flat(Double2 p, Double2 motor) const {
    constexpr Double2 kNear = {kNearPx, kNearPx};
    if (!all_true(abs2(motor) <= tile_)) return false;  // NaN compares false
    const Double2 q = (p - origin_) * inverse_tile_;
    if (!all_within(q, size_)) [[likely]]  // off the grid: over a tile from every box
      return all_true(abs2(p) < kNear);
    // On the grid (which lies within kNearPx), 0 <= q < size_ <= kMaxTiles: the signed conversion is exact.
    const auto tx = static_cast<std::int32_t>(q[0]), ty = static_cast<std::int32_t>(q[1]);
    return near_[static_cast<std::size_t>(ty * columns_ + tx)] == 0;
  }

  double tile_px() const { return tile_[0]; }
  std::size_t columns() const { return static_cast<std::size_t>(size_[0]); }
  std::size_t rows() const { return static_cast<std::size_t>(size_[1]); }
  std::size_t bytes() const { return near_.capacity(); }

 private:
  Double2 tile_ = {kMinTilePx, kMinTilePx};  // the side in both lanes, and its inverse
  Double2 inverse_tile_ = {1.0 / kMinTilePx, 1.0 / kMinTilePx};
  Double2 origin_ = {0.0, 0.0};  // screen px of the grid's top-left corner
  Double2 size_ = {0.0, 0.0};    // columns and rows, as doubles
  std::int32_t columns_ = 0;
  // Per tile, row by row: 1 where a region's box comes within a tile and a margin. Never empty (without a grid one
  // unread tile), so that no compiler sees surely_flat() index an empty array.
  std::vector<std::uint8_t> near_ = std::vector<std::uint8_t>(1, 0);
};

}  // namespace ph
