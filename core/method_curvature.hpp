// Curvature-based C/D ratio of Argelaguet et al. 2012, Eq. 1-3 (docs/METHODS.md, "Projection into the
// plane of motion" and "Curvature-based C/D").
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/fast_math.hpp"
#include "core/field_sampling.hpp"
#include "core/method.hpp"

namespace ph {

struct CurvatureParams {
  double kmax_prime = 4.0;  // k'max: largest C/D (uphill) when delta-beta = 0
  double kmin_prime = 1.5;  // k'min: 1 / smallest C/D (downhill) when delta-beta = 0
  double kmax_lo = 1.0, kmax_hi = 30.0;
  double kmin_lo = 1.0, kmin_hi = 5.0;
  double delta_beta_sign = 1.0;  // +1: Eq. 1 as printed (= theta1 - theta2); -1: the paper's prose reading
};

// Empty when valid; otherwise what is wrong, naming the parameter.
std::string validate(const CurvatureParams& params);

// n''_x (docs/METHODS.md, "Projection into the plane of motion") for a unit normal and a unit direction:
// s / sqrt(s^2 + n_z^2).
double projected_normal_x(Normal n, Vec2 direction);

// Slope angle along a direction, positive uphill: atan(g . m).
double slope_angle(Gradient g, Vec2 direction);

// Eq. 1-3 from the two projected values a1 = n''_x(p1), a2 = n''_x(p2) and the slope angles
// theta = asin(-a) of the same texels (passed to avoid recomputing acos). detail may be null.
inline double curvature_cd(const CurvatureParams& p, double a1, double theta1, double a2, double theta2,
                           StepDetail* detail) {
  // Eq. 1: cos(alpha) is the mean of the projected normals; delta-beta = acos(a1) - acos(a2) = theta1 - theta2.
  const double cos_alpha = 0.5 * (a1 + a2);
  const double delta_beta = p.delta_beta_sign * (theta1 - theta2) * (180.0 / std::numbers::pi);
  // Eq. 3 with the limits that keep Eq. 2 meaningful (k >= 1).
  const double kmax = std::clamp(p.kmax_prime * (1.0 + delta_beta), p.kmax_lo, p.kmax_hi);
  const double kmin = std::clamp(p.kmin_prime * (1.0 - delta_beta), p.kmin_lo, p.kmin_hi);
  // Eq. 2: cos(alpha) < 0 is uphill (the projected normal leans against the motion).
  double cd = 1.0;
  if (cos_alpha > 0.0) {
    cd = 1.0 - cos_alpha * (1.0 - 1.0 / kmin);
  } else if (cos_alpha < 0.0) {
    cd = 1.0 - cos_alpha * (kmax - 1.0);
  }
  if (detail != nullptr) *detail = {cos_alpha, delta_beta, kmax, kmin, std::numeric_limits<double>::quiet_NaN()};
  return cd;
}

class CurvatureMethod final : public Method {
 public:
  explicit CurvatureMethod(const CurvatureParams& params);  // throws std::invalid_argument if invalid

  std::string_view name() const override { return "curvature"; }
  FieldNeeds needs() const override { return {.gradient = true, .depth = false}; }
  // Inline: the traversal calls these directly on the final class (core/traversal.cpp).
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 m) const override {
    if (fields == nullptr || !fields->gradient) return {0.0, 0.0};
    const Gradient g = fields->gradient->at(local.x, local.y);
    // With n = (-g, 1)/|.|, n''_x = -t / sqrt(1 + t^2) and theta = atan(t), t = g . m the slope along m.
    const double t = static_cast<double>(g.x) * m.x + static_cast<double>(g.y) * m.y;
    return {-t / std::sqrt(1.0 + t * t), fast_atan(t)};
  }
  // The same from the gradient interpolated at `at` (Sampling::bilinear).
  TexelSample sample_at(const RegionFields* fields, Texel /*local*/, Vec2 at, Vec2 m) const override {
    if (fields == nullptr || !fields->gradient) return {0.0, 0.0};
    const Vec2 g = bilinear(*fields->gradient, at);
    const double t = g.x * m.x + g.y * m.y;
    return {-t / std::sqrt(1.0 + t * t), fast_atan(t)};
  }
  double cd(const TexelSample& from, const TexelSample& to, double /*step_px*/, StepDetail* detail) const override {
    return curvature_cd(params_, from.v0, from.v1, to.v0, to.v1, detail);
  }
  double cd_lower_bound() const override { return 1.0 / params_.kmin_hi; }
  double cd_upper_bound() const override { return params_.kmax_hi; }
  const CurvatureParams& params() const { return params_; }

 private:
  CurvatureParams params_;
};

}  // namespace ph
