#include "core/method_curvature.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace ph {

StepDetail empty_step_detail() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan, nan, nan, nan};
}

namespace {

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

std::string check_limits(const char* name, double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo < 1.0 || hi < lo) {
    return std::string(name) + " limits must be finite with 1 <= lower <= upper";
  }
  return {};
}

}  // namespace

std::string validate(const CurvatureParams& p) {
  if (!positive_finite(p.kmax_prime)) return "kmax_prime must be a finite number > 0";
  if (!positive_finite(p.kmin_prime)) return "kmin_prime must be a finite number > 0";
  if (auto e = check_limits("kmax", p.kmax_lo, p.kmax_hi); !e.empty()) return e;
  if (auto e = check_limits("kmin", p.kmin_lo, p.kmin_hi); !e.empty()) return e;
  if (p.delta_beta_sign != 1.0 && p.delta_beta_sign != -1.0) return "delta_beta_sign must be 1 or -1";
  return {};
}

double projected_normal_x(Normal n, Vec2 m) {
  const double s = n.x * m.x + n.y * m.y;
  const double denom = std::sqrt(s * s + static_cast<double>(n.z) * n.z);
  return denom > 0.0 ? s / denom : 0.0;
}

double slope_angle(Gradient g, Vec2 m) { return std::atan(g.x * m.x + g.y * m.y); }

double curvature_cd(const CurvatureParams& p, double a1, double theta1, double a2, double theta2, StepDetail* detail) {
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
  if (detail != nullptr) {
    *detail = {cos_alpha, delta_beta, kmax, kmin, std::numeric_limits<double>::quiet_NaN()};
  }
  return cd;
}

CurvatureMethod::CurvatureMethod(const CurvatureParams& params) : params_(params) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("curvature method: " + error);
}

TexelSample CurvatureMethod::sample(const RegionFields* fields, Texel local, Vec2 m) const {
  if (fields == nullptr || !fields->gradient) return {0.0, 0.0};
  const Gradient g = fields->gradient->at(local.x, local.y);
  // With n = (-g, 1)/|.|, n''_x = -t / sqrt(1 + t^2) and theta = atan(t), t = g . m the slope along m.
  const double t = static_cast<double>(g.x) * m.x + static_cast<double>(g.y) * m.y;
  return {-t / std::sqrt(1.0 + t * t), std::atan(t)};
}

double CurvatureMethod::cd(const TexelSample& from, const TexelSample& to, double /*step_px*/,
                           StepDetail* detail) const {
  return curvature_cd(params_, from.v0, from.v1, to.v0, to.v1, detail);
}

}  // namespace ph
