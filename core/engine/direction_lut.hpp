// Traversal::direction_lut: per texel of a region, the C/D ratio of entering the texel from the
// neighbour 1 px behind it, for N quantised motion directions, computed once with the region's method.
// The walk then reads one table entry per texel instead of sampling two texels and evaluating the method.
//
// Storage: int16 codes around 1, cd = 1 + code * scale (one scale above 1, one below), so a flat texel
// reads back exactly 1 (bit-exact identity) and the decode is one multiply-add. 2 bytes per texel and
// direction: 32 bytes per texel at 16 directions, 16 at 8. The quantisation error is at most
// (cd_hi - 1) / 65534 above 1 and (1 - cd_lo) / 65536 below (4.4e-4 and 1.2e-5 for the curvature
// method's defaults), far below the direction quantisation's own error.
// Layout: one plane per direction, so a frame (one direction) walks a plane as dense as a 16-bit field.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph {

class Scene;

class DirectionLut {
 public:
  DirectionLut() = default;
  DirectionLut(std::int32_t width, std::int32_t height, int directions, double cd_lo, double cd_hi);

  int directions() const { return directions_; }
  std::int32_t width() const { return width_; }
  std::int32_t height() const { return height_; }

  // Index of the quantised direction nearest to the unit direction m (angle 2 pi k / N, y down).
  int direction_index(Vec2 m) const { return direction_index(m, directions_); }
  static int direction_index(Vec2 m, int directions);
  // Unit vector of quantised direction k.
  Vec2 direction(int k) const;

  // C/D of entering texel `local` along quantised direction k.
  double cd(int k, Texel local) const {
    const std::int16_t q = codes_[plane_offset(k) + static_cast<std::size_t>(local.y) * width_ + local.x];
    return std::clamp(1.0 + q * (q >= 0 ? up_ : down_), lo_, hi_);
  }
  void set(int k, Texel local, double cd);

  std::size_t bytes() const { return codes_.capacity() * sizeof(std::int16_t); }

 private:
  std::size_t plane_offset(int k) const { return static_cast<std::size_t>(k) * width_ * height_; }

  std::int32_t width_ = 0, height_ = 0;
  int directions_ = 0;
  double lo_ = 1.0, hi_ = 1.0;
  double up_ = 1.0, down_ = 1.0;  // C/D per code above and below 1
  std::vector<std::int16_t> codes_;
};

// The table of region `index` of a scene (any method; the listed ones are called inline).
// The neighbour of texel p behind it along m_k is the texel containing centre(p) - m_k: a 4- or
// 8-neighbour; its sample comes from the region's own field inside the region and from whatever lies
// there (another region, or the flat outside) beyond its edge, as the exact walk reads it. The depth
// method gets the true distance of the two texel centres (1 or sqrt 2) as its step.
DirectionLut build_direction_lut(const Scene& scene, std::size_t index, int directions);

}  // namespace ph
