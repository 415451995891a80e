#include "core/engine/flat_tiles.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ph {

FlatTiles::FlatTiles(std::span<const Rect> boxes) {
  if (boxes.empty()) return;
  double x0 = boxes[0].x, y0 = boxes[0].y, x1 = x0, y1 = y0;
  for (const Rect& r : boxes) {
    x0 = std::min(x0, static_cast<double>(r.x));
    y0 = std::min(y0, static_cast<double>(r.y));
    x1 = std::max(x1, static_cast<double>(r.x) + r.w);
    y1 = std::max(y1, static_cast<double>(r.y) + r.h);
  }
  // A tile is marked when it meets a box widened by a tile and 2 px. A motion of at most a tile from a point of an
  // unmarked tile then stays over 2 px from every box (the margin covers the rounding of the tile's index), and so
  // does one from a point off the grid, which reaches a tile past the widest box. The grid starts two tiles and
  // 2 px before the boxes, so its first column and row are never marked (surely_flat() relies on it).
  for (double tile = kMinTilePx; tile <= kMaxTilePx; tile *= 2.0) {
    const double reach = 2.0 * tile + 2.0;
    const double columns = std::ceil((x1 - x0 + 2.0 * reach) / tile), rows = std::ceil((y1 - y0 + 2.0 * reach) / tile);
    if (columns * rows > static_cast<double>(kMaxTiles)) continue;
    // A grid reaching past kNearPx would judge frames surely_flat() must leave to the walk.
    const double far_x = std::max(std::abs(x0 - reach), std::abs(x0 - reach + columns * tile));
    const double far_y = std::max(std::abs(y0 - reach), std::abs(y0 - reach + rows * tile));
    if (std::max(far_x, far_y) >= kNearPx) break;
    tile_ = splat(tile);
    inverse_tile_ = splat(1.0 / tile);
    origin_ = Double2{x0 - reach, y0 - reach};
    columns_ = static_cast<std::uint32_t>(columns);
    rows_ = static_cast<std::uint32_t>(rows);
    const auto width = static_cast<std::size_t>(columns_);
    near_.assign(width * static_cast<std::size_t>(rows), 0);
    const double widen = tile + 2.0;
    // The tiles [first, last] that meet [lo - widen, hi + widen] along an axis whose grid starts at `start`.
    auto tiles = [&](double lo, double hi, double start, double count) {
      const double first = std::floor((lo - widen - start) / tile), last = std::floor((hi + widen - start) / tile);
      return std::pair{static_cast<std::size_t>(std::max(first, 0.0)),
                       static_cast<std::size_t>(std::min(last, count - 1))};
    };
    for (const Rect& r : boxes) {
      const auto [cx0, cx1] = tiles(r.x, static_cast<double>(r.x) + r.w, origin_[0], columns);
      const auto [cy0, cy1] = tiles(r.y, static_cast<double>(r.y) + r.h, origin_[1], rows);
      for (std::size_t ty = cy0; ty <= cy1; ++ty) {
        std::fill(near_.begin() + static_cast<std::ptrdiff_t>(ty * width + cx0),
                  near_.begin() + static_cast<std::ptrdiff_t>(ty * width + cx1 + 1), std::uint8_t{1});
      }
    }
    return;
  }
  // Too wide for any tile, or too near the world's limits: judge no frame (a motor no longer than a tile of 0 px
  // is only the zero motor, which advance() returns at once).
  tile_ = splat(0.0);
  inverse_tile_ = splat(0.0);
}

}  // namespace ph
