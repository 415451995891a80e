// The 24 targets of the curvature paper (Fig. 3; docs/METHODS.md, "The 24 targets") as exact analytic surfaces.
#pragma once

#include <string>
#include <vector>

#include "core/engine/field.hpp"
#include "core/engine/geometry.hpp"

namespace ph {

enum class TargetShape { bump, hole };
enum class TargetProfile { linear, gaussian, polynomial };

struct TargetSpec {
  TargetShape shape = TargetShape::bump;
  TargetProfile profile = TargetProfile::gaussian;
  double height = 1.0;       // 0.25 or 1 on a depth normalised to [-1, 1]
  double radius = 200.0;     // px
  std::int32_t size = 500;   // the target is size x size px, centred at (size/2, size/2)
  double relief_px = 100.0;  // screen px of height per unit of normalised depth

  std::string name() const;  // e.g. "bump-gaussian-h1-r200", "hole-linear-h0.25-r100"
};

// All 24, in a fixed order: shape, profile, height, radius.
std::vector<TargetSpec> all_targets();

// Exact height (screen px) and gradient (px per px, y down) at a point in target pixels
// (texel centres are at i + 0.5). h = sign * height * relief_px * f(r / radius) for r <= radius, 0 outside.
// Where the surface has a kink or a step the gradient is a fixed choice, not a mean of limits: at the centre
// (r == 0; the apex of the linear profile) it is 0, and exactly on the rim (r == radius) it is the inside
// value. The Gaussian profile is not 0 at the rim (exp(-4.5) ~ 0.011 of the height): a small step there.
// Texel centres never fall exactly on the centre or the rim of the standard targets.
double target_height(const TargetSpec& spec, Vec2 p);
Gradient target_gradient(const TargetSpec& spec, Vec2 p);

// Rasterised at texel centres.
DepthField target_depth_field(const TargetSpec& spec);
GradientField target_gradient_field(const TargetSpec& spec);
NormalImage target_normal_image(const TargetSpec& spec);

// What a method with `needs` reads of a target, rasterised: the gradient, and the heights where it reads them in a
// region given both maps.
RegionFields target_fields(const TargetSpec& spec, const FieldNeeds& needs);

}  // namespace ph
