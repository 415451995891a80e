// What the walkers share (core/engine/traversal.cpp, core/engine/traversal_variants.cpp): the cell of the texel grid a
// coordinate lies in, where a ray crosses a box, and what a method reads of the region under a texel.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>

#include "core/engine/fast_math.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/scene.hpp"

namespace ph {

// Index of the grid cell a coordinate lies in, taking a coordinate on a cell boundary to belong to the
// cell the motion came from (so a stop exactly on a boundary stays in the texel that was being walked).
inline std::int32_t cell_behind(double v, int step) { return step > 0 ? -floor_to_int(-v) - 1 : floor_to_int(v); }

// cell_behind without a branch on the step's sign, which is random from frame to frame: the two cells differ
// only where v is a whole number, which is rare, so that branch is predicted.
inline std::int32_t cell_behind_predictable(double v, double step) {
  const std::int32_t below = floor_to_int(v);
  if (v == static_cast<double>(below)) [[unlikely]]
    return step > 0.0 ? below - 1 : below;
  return below;
}

// Index of the cell a motion starting at a coordinate moves into.
inline std::int32_t cell_ahead(double v, int step) { return step < 0 ? -floor_to_int(-v) - 1 : floor_to_int(v); }

// The part [t0, t1] of [t_lo, t_hi] in which the ray origin + t d lies in the closed box [lo, hi] (slabs);
// t0 > t1 when it misses the box. Along an axis d does not move, the ray is inside its slab or misses.
struct RaySpan {
  double t0, t1;
  bool hits() const { return t0 <= t1; }
};
inline RaySpan ray_box(Vec2 origin, Vec2 d, Vec2 lo, Vec2 hi, double t_lo, double t_hi) {
  const double o[2] = {origin.x, origin.y}, dir[2] = {d.x, d.y};
  const double b0[2] = {lo.x, lo.y}, b1[2] = {hi.x, hi.y};
  for (int axis = 0; axis < 2; ++axis) {
    if (dir[axis] != 0.0) {
      const double t0 = (b0[axis] - o[axis]) / dir[axis], t1 = (b1[axis] - o[axis]) / dir[axis];
      t_lo = std::max(t_lo, std::min(t0, t1));
      t_hi = std::min(t_hi, std::max(t0, t1));
    } else if (o[axis] < b0[axis] || o[axis] > b1[axis]) {
      return {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    }
  }
  return {t_lo, t_hi};
}

// A region's top-left corner in screen px (bilinear positions are region-local).
inline Vec2 corner(const Region& region) {
  return {static_cast<double>(region.rect.x), static_cast<double>(region.rect.y)};
}
// The same as a texel: a region-local texel plus it is the screen texel.
inline Texel corner_texel(const Region& region) { return {region.rect.x, region.rect.y}; }

// Whether method.cd(from, to, ...) reads `from`; true for a method that does not say.
template <typename M>
bool cd_reads_from(const M& method, const TexelSample& to) {
  if constexpr (requires { method.reads_from(to); }) {
    return method.reads_from(to);
  } else {
    return true;
  }
}

// What `method` reads at texel t for the motion direction m, from the fields of the region that owns t (the
// flat surface's sample outside every region): the texel's value, or with `at` (screen px inside t) the
// value interpolated there (Sampling::bilinear). M is a method's concrete class (calls inline) or Method.
template <typename M>
TexelSample sample_owner(const Scene& scene, const M& method, Texel t, Vec2 m, const Vec2* at = nullptr) {
  const std::optional<std::size_t> owner = scene.owner(t);
  if (!owner) return method.sample(nullptr, {}, m);
  const Region& region = scene.regions()[*owner];
  if (at != nullptr) return method.sample_at(&region.fields, region.local(t), *at - corner(region), m);
  return method.sample(&region.fields, region.local(t), m);
}

}  // namespace ph
