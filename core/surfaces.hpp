// The analytic test surfaces of the second paper (docs/INTERROGATION.md, "The test surfaces") as height fields
// over a square subdomain, with exact heights, gradients, second derivatives and curvatures.
//
// Conventions as in core/targets: a surface is size x size px, y down, texel centres at i + 0.5; heights in
// screen px toward the viewer, gradients in px per px. Every length scales with the half-size s = size / 2 (so a
// surface looks the same at any size and its curvatures scale as 1/s), and heights stay within +-relief_px()
// = +-s / 4 (+-64 px at the default 512 px). No surface has a singularity inside the square: the cone's apex
// lies 0.5 s to the left of it, the sphere and ellipsoid rims lie outside its corners.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/curvature_class.hpp"
#include "core/curvature_field.hpp"
#include "core/field.hpp"
#include "core/geometry.hpp"

namespace ph {

// X = x - s, Y = y - s (px from the centre):
//   plane          h = 0.12 X - 0.08 Y
//   cylinder       h = sqrt(R^2 - X^2), R = 2 s, axis along y                       (bulges toward the viewer)
//   cone           h = -0.15 sqrt((X + 1.5 s)^2 + Y^2), apex at X = -1.5 s          (slope 0.15)
//   paraboloid     h = -(0.14 X^2 + 0.08 Y^2) / s                                   (elliptic paraboloid, a cap)
//   ellipsoid      h = c sqrt(1 - X^2/a^2 - Y^2/b^2), a = 2.2 s, b = 1.8 s, c = 0.6 s
//   sphere         h = sqrt(R^2 - X^2 - Y^2), R = 3 s                               (K = 1 / R^2 exactly)
//   hyperboloid    h = c sqrt(1 - X^2/a^2 + Y^2/b^2), a = 1.6 s, b = 2 s, c = 0.6 s (one sheet, over its waist)
//   simple-saddle  h = 0.2 (X^2 - Y^2) / s
//   monkey-saddle  h = 0.1 (X^3 - 3 X Y^2) / s^2                                    (flat point at the centre)
// each plus a constant that centres its range of heights on 0.
enum class SurfaceKind {
  plane,
  cylinder,
  cone,
  paraboloid,
  ellipsoid,
  sphere,
  hyperboloid,
  simple_saddle,
  monkey_saddle
};

struct SurfaceSpec {
  SurfaceKind kind = SurfaceKind::sphere;
  std::int32_t size = 512;

  std::string name() const;  // "plane", "cylinder", ..., "simple-saddle", "monkey-saddle"
  double half_size() const { return size / 2.0; }
  double relief_px() const { return size / 8.0; }  // every height lies within +-relief_px()
};

// All nine, in the order above.
std::vector<SurfaceSpec> all_surfaces(std::int32_t size = 512);

// The class every point of the surface has exactly (the monkey saddle is hyperbolic except at its centre, where
// it is planar).
CurvatureClass surface_class(SurfaceKind kind);

// Exact values at a point in surface pixels.
double surface_height(const SurfaceSpec& spec, Vec2 p);
HeightDerivatives surface_derivatives(const SurfaceSpec& spec, Vec2 p);
inline Curvatures surface_curvatures(const SurfaceSpec& spec, Vec2 p) {
  return curvatures_from_derivatives(surface_derivatives(spec, p));
}

// Rasterised at texel centres.
DepthField surface_depth_field(const SurfaceSpec& spec);
GradientField surface_gradient_field(const SurfaceSpec& spec);
NormalImage surface_normal_image(const SurfaceSpec& spec);
CurvatureFields surface_curvature_fields(const SurfaceSpec& spec);  // K, H, k1 and k2, exact

}  // namespace ph
