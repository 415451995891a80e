// The per-texel data a region's methods read, stored once at the region's on-screen size.
//
// Normals are not stored as normals: every method that reads orientation only needs the slope of the
// surface along a direction, so a texel keeps the height gradient g = (dh/dx, dh/dy) in screen pixels
// per pixel (y down) as two floats: 8 bytes per texel. A unit normal n with n_z > 0 is
// n = (-g_x, -g_y, 1) / |(-g_x, -g_y, 1)|, so nothing is lost (docs/METHODS.md, "Screen, regions and fields").
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph {

struct Gradient {
  float x = 0.0f;  // dh/dx, screen px of height per px
  float y = 0.0f;  // dh/dy, y down
};

struct Normal {
  float x = 0.0f;  // screen frame: x right, y down, z toward the viewer
  float y = 0.0f;
  float z = 1.0f;
};

// A w x h grid of values in row-major order.
template <typename T>
struct Grid {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::vector<T> values;

  Grid() = default;
  Grid(std::int32_t w, std::int32_t h, T fill = T{})
      : width(w), height(h), values(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), fill) {}

  T& at(std::int32_t x, std::int32_t y) { return values[static_cast<std::size_t>(y) * width + x]; }
  const T& at(std::int32_t x, std::int32_t y) const { return values[static_cast<std::size_t>(y) * width + x]; }
  bool empty() const { return values.empty(); }
  std::size_t bytes() const { return values.capacity() * sizeof(T); }
};

// A texel of a region's fields as a method's reading along a motion needs it: its place in their row-major
// order (y * width + x), and whether its neighbours behind along the motion (one texel against the motion's
// sign along each axis it moves along) lie in the region too. A walk keeps both as it steps, so the reading
// needs no multiplication and no bounds check.
struct FieldTexel {
  std::size_t index = 0;
  bool behind_inside = false;
};

// The same worked out from the texel (region-local, inside a width x height field) and the offsets to the
// neighbours behind (-1, 0 or 1 per axis).
inline FieldTexel field_texel(Texel local, std::int32_t width, std::int32_t height, std::int32_t ox, std::int32_t oy) {
  // One unsigned compare per axis: a neighbour at -1 wraps to above the width.
  const auto nx = static_cast<std::uint32_t>(local.x + ox), ny = static_cast<std::uint32_t>(local.y + oy);
  return {static_cast<std::size_t>(local.y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(local.x),
          nx < static_cast<std::uint32_t>(width) && ny < static_cast<std::uint32_t>(height)};
}

using GradientField = Grid<Gradient>;  // from a normal map, or derived from depth
using DepthField = Grid<float>;        // height h in screen px (toward the viewer)
using NormalImage = Grid<Normal>;      // decoded unit normals, only while loading

// What a method declares it reads; the loader builds nothing else.
struct FieldNeeds {
  bool gradient = false;
  bool depth = false;
  bool depth_if_given = false;  // reads the heights where the region has a depth map, works without them

  // Whether the heights are read in a region that has a depth map (`depth_given`) or not: the one rule every loader,
  // the image wire and the lab follow (a copy of it that forgot depth_if_given once kept the hybrid's depth map from
  // the daemon).
  constexpr bool reads_depth(bool depth_given) const { return depth || (depth_if_given && depth_given); }
};

// What two readers of one region's fields read together (a method and an effect).
constexpr FieldNeeds joined(FieldNeeds a, FieldNeeds b) {
  return {a.gradient || b.gradient, a.depth || b.depth, a.depth_if_given || b.depth_if_given};
}

// What a method derives from the fields when a scene is built (Method::prepare): the hybrid method's texels
// where the height changes more than the normals explain (1) and the rest (0).
using DiscontinuityField = Grid<std::uint8_t>;

// The fields of one region, each present only when the region's method needs it.
// How a normal map's slopes compare with a depth map's, each figure empty where too few slopes were read to tell.
struct SlopeComparison {
  // The normals' slopes over the depth map's where both show the relief sloping: 1 where the two maps hold it at
  // one scale.
  std::optional<double> ratio;
  // Of the slopes along x (along y) that both maps resolve, the share whose signs differ: near 0 where the maps
  // agree, near 1 where one of them is the other's relief upside down (along y alone: the other green convention).
  std::optional<double> opposite_x, opposite_y;
  // Of the slopes the normal map resolves, the share where the depth map's lie below what it resolves: near 1 where
  // the depth map is all but flat beside the normals (a relief_px far too small).
  std::optional<double> depth_flat;
  bool operator==(const SlopeComparison&) const = default;
};

struct RegionFields {
  std::optional<GradientField> gradient;
  std::optional<DepthField> depth;
  std::optional<DiscontinuityField> discontinuity;
  // The standard deviation of the gradient's error from the storage of the map it was decoded from (core/engine/
  // decode.hpp: an 8-bit normal map's 0.0023); 0 for a float map and for fields made in code: exact.
  double gradient_rounding = 0.0;
  // The same for the heights, from the depth map's storage (px; height_rounding_of_depth): 0 for a float map, for
  // fields made in code and where there is no depth field.
  double depth_rounding = 0.0;
  // Where the hybrid method's preparation pulled the normals toward the depth map's slopes, the normals' weight in
  // that mean (core/engine/method_hybrid.cpp); empty where it did not (and for every other method).
  std::optional<double> fused_normals_weight;
  // Where the hybrid method's preparation compared the normals with a depth map, how their slopes compare
  // (compare_slopes_with_depth in core/engine/method_hybrid.hpp); empty for every other method.
  std::optional<SlopeComparison> slope_comparison;
  // How many texels the hybrid method's preparation smoothed within the rounding of the map's storage, and at how
  // many of those it took the smoothing's flattening off again (core/engine/method_hybrid.cpp); 0 for every other
  // method.
  std::size_t smoothed_texels = 0;
  std::size_t unflattened_texels = 0;

  std::size_t bytes() const {
    return (gradient ? gradient->bytes() : 0) + (depth ? depth->bytes() : 0) +
           (discontinuity ? discontinuity->bytes() : 0);
  }
};

// Gradient of a unit normal with n_z > 0: g = (-n_x / n_z, -n_y / n_z).
inline Gradient gradient_from_normal(Normal n) { return {-n.x / n.z, -n.y / n.z}; }

// Gradients of decoded normals, as a region's field holds them: a texel with n_z just above 0 is a wall, and
// its slope is clamped to +-kMaxSlope so that later arithmetic never sees inf.
inline constexpr float kMaxSlope = 1.0e6f;
GradientField gradient_from_normals(const NormalImage& normals);
// One texel of it: the gradient with each slope clamped to +-kMaxSlope.
Gradient clamped_gradient(Normal n);

// Unit normal of a height gradient.
Normal normal_from_gradient(Gradient g);

// Gradient of a height field by central differences (one-sided at the border), in bands of rows on `threads` threads
// (0: one per core, at most kMaxRowBandThreads; bands of kMinRowBandRows rows at least), the same values as in one.
GradientField gradient_from_depth(const DepthField& depth, unsigned threads = 0);

}  // namespace ph
