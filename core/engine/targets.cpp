// The 24 targets of the curvature paper, Fig. 3 (docs/METHODS.md, "The 24 targets"), as exact analytic surfaces.
//
// A target is radially symmetric about (size/2, size/2): h(r) = sign * height * relief_px * f(u), u = r / radius,
// for r <= radius and 0 outside. Its gradient is h'(r) * (dx, dy) / r with h'(r) = sign * height * relief_px *
// f'(u) / radius, taken from the formula rather than from finite differences, so the written normal maps are exact.
//
// Discontinuities the rest of the project must cope with (they are part of the targets, not bugs):
//  - linear: a kink at the apex (gradient undefined at r == 0; we use 0) and at the rim (slope jumps to 0);
//  - polynomial: a kink at the rim (f'(1) = -4, the outside is flat);
//  - Gaussian: a step at the rim, because f(1) = exp(-4.5) ~ 0.011 is not 0 (1.1 px for height 1 and
//    relief 100 px), and a kink there too. We keep the profile as docs/METHODS.md states it rather than
//    shifting it to reach 0, so the targets stay those of the paper's stated formula.
#include "core/engine/targets.hpp"

#include <cmath>
#include <locale>
#include <sstream>

namespace ph {
namespace {

constexpr double gaussian_sigma = 1.0 / 3.0;  // our choice: the paper does not give it

// f(u) for 0 <= u <= 1.
double profile_value(TargetProfile profile, double u) {
  switch (profile) {
    case TargetProfile::linear:
      return 1.0 - u;
    case TargetProfile::gaussian:
      return std::exp(-u * u / (2.0 * gaussian_sigma * gaussian_sigma));
    case TargetProfile::polynomial:
      return 1.0 - u * u * u * u;
  }
  return 0.0;
}

// df/du for 0 <= u <= 1.
double profile_slope(TargetProfile profile, double u) {
  switch (profile) {
    case TargetProfile::linear:
      return -1.0;
    case TargetProfile::gaussian:
      return -u / (gaussian_sigma * gaussian_sigma) * profile_value(profile, u);
    case TargetProfile::polynomial:
      return -4.0 * u * u * u;
  }
  return 0.0;
}

const char* shape_name(TargetShape shape) { return shape == TargetShape::bump ? "bump" : "hole"; }

const char* profile_name(TargetProfile profile) {
  switch (profile) {
    case TargetProfile::linear:
      return "linear";
    case TargetProfile::gaussian:
      return "gaussian";
    case TargetProfile::polynomial:
      return "polynomial";
  }
  return "unknown";
}

// Screen px of height at the apex, signed: + for a bump, - for a hole.
double peak_px(const TargetSpec& spec) {
  const double sign = spec.shape == TargetShape::bump ? 1.0 : -1.0;
  return sign * spec.height * spec.relief_px;
}

// Displacement of p from the target's centre.
Vec2 from_centre(const TargetSpec& spec, Vec2 p) {
  const double c = static_cast<double>(spec.size) / 2.0;
  return p - Vec2{c, c};
}

// Centre of texel (x, y) in target pixels.
Vec2 texel_centre(std::int32_t x, std::int32_t y) { return {x + 0.5, y + 0.5}; }

// Applies value(texel centre) to every texel of a size x size grid.
template <typename T, typename F>
Grid<T> rasterise(const TargetSpec& spec, F value) {
  Grid<T> grid(spec.size, spec.size);
  for (std::int32_t y = 0; y < spec.size; ++y) {
    for (std::int32_t x = 0; x < spec.size; ++x) grid.at(x, y) = value(texel_centre(x, y));
  }
  return grid;
}

}  // namespace

std::string TargetSpec::name() const {
  // Default stream formatting prints 1, 0.25, 200: the shortest form for these values. The classic locale
  // keeps the decimal point a '.' whatever the process locale is.
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << shape_name(shape) << '-' << profile_name(profile) << "-h" << height << "-r" << radius;
  return out.str();
}

std::vector<TargetSpec> all_targets() {
  std::vector<TargetSpec> targets;
  for (TargetShape shape : {TargetShape::bump, TargetShape::hole}) {
    for (TargetProfile profile : {TargetProfile::linear, TargetProfile::gaussian, TargetProfile::polynomial}) {
      for (double height : {0.25, 1.0}) {
        for (double radius : {100.0, 200.0}) {
          TargetSpec spec;
          spec.shape = shape;
          spec.profile = profile;
          spec.height = height;
          spec.radius = radius;
          targets.push_back(spec);
        }
      }
    }
  }
  return targets;
}

double target_height(const TargetSpec& spec, Vec2 p) {
  const double r = length(from_centre(spec, p));
  if (r > spec.radius) return 0.0;
  return peak_px(spec) * profile_value(spec.profile, r / spec.radius);
}

Gradient target_gradient(const TargetSpec& spec, Vec2 p) {
  const Vec2 d = from_centre(spec, p);
  const double r = length(d);
  // Outside is flat; at the centre every profile is flat or (linear) a cone's apex, where we choose 0.
  if (r > spec.radius || r == 0.0) return {};
  const double dh_dr = peak_px(spec) * profile_slope(spec.profile, r / spec.radius) / spec.radius;
  return {static_cast<float>(dh_dr * d.x / r), static_cast<float>(dh_dr * d.y / r)};
}

DepthField target_depth_field(const TargetSpec& spec) {
  return rasterise<float>(spec, [&](Vec2 p) { return static_cast<float>(target_height(spec, p)); });
}

GradientField target_gradient_field(const TargetSpec& spec) {
  return rasterise<Gradient>(spec, [&](Vec2 p) { return target_gradient(spec, p); });
}

NormalImage target_normal_image(const TargetSpec& spec) {
  return rasterise<Normal>(spec, [&](Vec2 p) { return normal_from_gradient(target_gradient(spec, p)); });
}

RegionFields target_fields(const TargetSpec& spec, const FieldNeeds& needs) {
  RegionFields fields;
  if (needs.gradient) fields.gradient = target_gradient_field(spec);
  if (needs.reads_depth(true)) fields.depth = target_depth_field(spec);
  return fields;
}

}  // namespace ph
