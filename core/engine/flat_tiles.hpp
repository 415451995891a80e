// Which parts of the screen lie far from every region: a coarse grid of square tiles, each marked when some
// region's box comes within a tile (and a margin) of it. A frame that starts in an unmarked tile, or off the grid,
// and moves at most a tile along each axis cannot touch any region, so advance() can take it as flat without
// going through the region list: a pointer outside every region costs the same whatever the number of regions
// (docs/PERFORMANCE.md, "Outside every region").
#pragma once

#include <array>
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
    // The tile, as unsigned whole parts of q: off the grid they are at least columns_ or rows_. A q in (-1, 0), less
    // than a tile before the grid, truncates to 0, the first column or row, which is never marked (see the .cpp).
    const auto [tx, ty] = whole_parts(q);
    if (tx >= columns_ || ty >= rows_) [[unlikely]]  // off the grid: over a tile from every box
      return all_true(abs2(p) < kNear);
    // On the grid (which lies within kNearPx).
    return near_[std::size_t{ty} * columns_ + tx] == 0;
  }

  // q's two lanes truncated toward 0, as unsigned: a lane below 0 (but above -1, which truncates to 0), past 2^31 or
  // NaN gives at least 2^31.
  PH_ALWAYS_INLINE static std::array<std::uint32_t, 2> whole_parts(Double2 q) {
#if PH_SSE2
    const __m128i cells = _mm_cvttpd_epi32(__m128d(q));  // 0x80000000 where out of range or NaN
    return {static_cast<std::uint32_t>(_mm_cvtsi128_si32(cells)),
            static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_shuffle_epi32(cells, 0x01)))};
#else
    constexpr double kOff = 2147483648.0;
    auto part = [](double v) {
      return v > -1.0 && v < kOff ? static_cast<std::uint32_t>(static_cast<std::int64_t>(v)) : std::uint32_t{1} << 31;
    };
    return {part(q[0]), part(q[1])};
#endif
  }

  double tile_px() const { return tile_[0]; }
  std::size_t columns() const { return columns_; }
  std::size_t rows() const { return rows_; }
  std::size_t bytes() const { return near_.capacity(); }

 private:
  Double2 tile_ = {kMinTilePx, kMinTilePx};  // the side in both lanes, and its inverse
  Double2 inverse_tile_ = {1.0 / kMinTilePx, 1.0 / kMinTilePx};
  Double2 origin_ = {0.0, 0.0};  // screen px of the grid's top-left corner
  std::uint32_t columns_ = 0, rows_ = 0;
  // Per tile, row by row: 1 where a region's box comes within a tile and a margin. Never empty (without a grid one
  // unread tile), so that no compiler sees surely_flat() index an empty array.
  std::vector<std::uint8_t> near_ = std::vector<std::uint8_t>(1, 0);
};

}  // namespace ph
