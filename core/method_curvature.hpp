// Curvature-based C/D ratio of Argelaguet et al. 2012, Eq. 1-3 (ALGORITHMS.md sections 2-3).
#pragma once

#include <string>

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

// n''_x of ALGORITHMS.md section 2 for a unit normal and a unit direction: s / sqrt(s^2 + n_z^2).
double projected_normal_x(Normal n, Vec2 direction);

// Slope angle along a direction, positive uphill: atan(g . m).
double slope_angle(Gradient g, Vec2 direction);

// Eq. 1-3 from the two projected values a1 = n''_x(p1), a2 = n''_x(p2) and the slope angles
// theta = asin(-a) of the same texels (passed to avoid recomputing acos). detail may be null.
double curvature_cd(const CurvatureParams& params, double a1, double theta1, double a2, double theta2,
                    StepDetail* detail);

class CurvatureMethod final : public Method {
 public:
  explicit CurvatureMethod(const CurvatureParams& params);  // throws std::invalid_argument if invalid

  std::string_view name() const override { return "curvature"; }
  FieldNeeds needs() const override { return {.gradient = true, .depth = false}; }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 direction) const override;
  double cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const override;
  double cd_lower_bound() const override { return 1.0 / params_.kmin_hi; }
  double cd_upper_bound() const override { return params_.kmax_hi; }
  const CurvatureParams& params() const { return params_; }

 private:
  CurvatureParams params_;
};

}  // namespace ph
