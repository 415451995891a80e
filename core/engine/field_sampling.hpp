// Bilinear interpolation of a region's fields at a continuous position (Sampling::bilinear). Texel
// (i, j) holds the value at its centre (i + 0.5, j + 0.5); outside the centres' hull the border texels
// extend. lerp is a + t (b - a), so a constant field interpolates to exactly its value (a flat region
// stays bit-exact flat).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "core/engine/fast_math.hpp"
#include "core/engine/field.hpp"
#include "core/engine/geometry.hpp"

namespace ph {

// The four texels and weights around a local position (px from the region's corner).
struct BilinearCell {
  std::int32_t x0, y0, x1, y1;
  double fx, fy;
};

inline BilinearCell bilinear_cell(std::int32_t width, std::int32_t height, Vec2 local) {
  const double u = std::clamp(local.x - 0.5, 0.0, static_cast<double>(width - 1));
  const double v = std::clamp(local.y - 0.5, 0.0, static_cast<double>(height - 1));
  BilinearCell c;
  c.x0 = std::min(static_cast<std::int32_t>(u), width - 1);
  c.y0 = std::min(static_cast<std::int32_t>(v), height - 1);
  c.x1 = std::min(c.x0 + 1, width - 1);
  c.y1 = std::min(c.y0 + 1, height - 1);
  c.fx = u - c.x0;
  c.fy = v - c.y0;
  return c;
}

// How many rows ahead of the texel it reads a walk asks the cache for: each step along y enters a new row, which
// is not in the cache yet, and a walk reaches the row this many y-steps later.
inline constexpr std::ptrdiff_t kRowsAhead = 8;

// Bytes from a texel to the one a walk along m reaches kRowsAhead rows later: that many rows along y and, as the
// walk moves along x meanwhile, kRowsAhead |m_x| / |m_y| texels along x (at most a row's width). A motion with
// no y component enters no new row: 0.
inline std::ptrdiff_t bytes_ahead(Vec2 m, std::int32_t width, std::size_t texel_bytes) {
  if (m.y == 0.0) return 0;
  const double along_x = std::min(static_cast<double>(kRowsAhead) * std::abs(m.x / m.y), static_cast<double>(width));
  const auto x = static_cast<std::ptrdiff_t>(along_x + 0.5) * (m.x < 0.0 ? -1 : 1);
  const std::ptrdiff_t y = kRowsAhead * width * (m.y < 0.0 ? -1 : 1);
  return (x + y) * static_cast<std::ptrdiff_t>(texel_bytes);
}

// Asks the cache for the line `bytes` away from `texel` (a texel rows ahead of the walk). Integer arithmetic:
// the address may lie outside the field, which a prefetch never reads.
PH_ALWAYS_INLINE inline void prefetch_ahead(const void* texel, std::ptrdiff_t bytes) {
#if defined(__GNUC__)
  __builtin_prefetch(reinterpret_cast<const void*>(reinterpret_cast<std::uintptr_t>(texel) + bytes));
#else
  static_cast<void>(texel);
  static_cast<void>(bytes);
#endif
}

inline double lerp_exact(double a, double b, double t) { return a + t * (b - a); }

inline double bilinear(const DepthField& f, Vec2 local) {
  const BilinearCell c = bilinear_cell(f.width, f.height, local);
  const double top = lerp_exact(f.at(c.x0, c.y0), f.at(c.x1, c.y0), c.fx);
  const double bottom = lerp_exact(f.at(c.x0, c.y1), f.at(c.x1, c.y1), c.fx);
  return lerp_exact(top, bottom, c.fy);
}

// The gradient as two doubles (x, y).
inline Vec2 bilinear(const GradientField& f, Vec2 local) {
  const BilinearCell c = bilinear_cell(f.width, f.height, local);
  const Gradient g00 = f.at(c.x0, c.y0), g10 = f.at(c.x1, c.y0), g01 = f.at(c.x0, c.y1), g11 = f.at(c.x1, c.y1);
  return {lerp_exact(lerp_exact(g00.x, g10.x, c.fx), lerp_exact(g01.x, g11.x, c.fx), c.fy),
          lerp_exact(lerp_exact(g00.y, g10.y, c.fx), lerp_exact(g01.y, g11.y, c.fx), c.fy)};
}

}  // namespace ph
