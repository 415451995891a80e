// Depth-based C/D ratio of Lécuyer et al. 2004, as the curvature paper describes it (ALGORITHMS.md section 4).
#pragma once

#include <string>

#include "core/method.hpp"

namespace ph {

struct DepthParams {
  double gain = 3.0;  // C/D change per px of height change per px travelled
  double kmax = 4.0;  // largest C/D
  double kmin = 1.5;  // 1 / smallest C/D
};

std::string validate(const DepthParams& params);

// CD = clamp(1 + gain * dh / step, 1 / kmin, kmax). detail may be null.
double depth_cd(const DepthParams& params, double h1, double h2, double step_px, StepDetail* detail);

class DepthMethod final : public Method {
 public:
  explicit DepthMethod(const DepthParams& params);  // throws std::invalid_argument if invalid

  std::string_view name() const override { return "depth"; }
  FieldNeeds needs() const override { return {.gradient = false, .depth = true}; }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 direction) const override;
  double cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const override;
  double cd_lower_bound() const override { return 1.0 / params_.kmin; }
  double cd_upper_bound() const override { return params_.kmax; }
  const DepthParams& params() const { return params_; }

 private:
  DepthParams params_;
};

}  // namespace ph
