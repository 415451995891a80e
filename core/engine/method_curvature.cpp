#include "core/engine/method_curvature.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <tuple>

namespace ph {

StepDetail empty_step_detail() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan, nan, nan, nan};
}

namespace {

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

std::string check_limits(const char* name, double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo < 1.0 || hi < lo || hi > kMaxCdFactor) {
    return std::string(name) + " limits must be finite with 1 <= lower <= upper <= 100";
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

double slope_angle(Gradient g, Vec2 m) {
  return fast_atan(static_cast<double>(g.x) * m.x + static_cast<double>(g.y) * m.y);
}

CurvatureParams CurvatureMethod::parse_params(const ParamReader& reader) {
  CurvatureParams p;
  auto number = [&](std::string_view key, double& value, bool (*ok)(double), std::string_view allowed) {
    if (const std::optional<double> v = reader.number(key)) value = *v;
    if (!ok(value)) reader.reject(key, allowed);
  };
  number("kmax_prime", p.kmax_prime, positive_finite, "must be a finite number > 0");
  number("kmin_prime", p.kmin_prime, positive_finite, "must be a finite number > 0");
  const char* limits = "must be [lower, upper] with 1 <= lower <= upper <= 100 (Eq. 2 needs k >= 1)";
  if (const auto v = reader.pair("kmax_limits")) {
    std::tie(p.kmax_lo, p.kmax_hi) = *v;
    if (!check_limits("kmax", p.kmax_lo, p.kmax_hi).empty()) reader.reject("kmax_limits", limits);
  }
  if (const auto v = reader.pair("kmin_limits")) {
    std::tie(p.kmin_lo, p.kmin_hi) = *v;
    if (!check_limits("kmin", p.kmin_lo, p.kmin_hi).empty()) reader.reject("kmin_limits", limits);
  }
  number(
      "delta_beta_sign", p.delta_beta_sign, [](double v) { return v == 1.0 || v == -1.0; },
      "must be 1 or -1 (1: Eq. 1 as printed; -1: reversed)");
  if (auto error = validate(p); !error.empty()) reader.reject("", error);
  return p;
}

CurvatureMethod::CurvatureMethod(const CurvatureParams& params)
    : Method(method_tag<CurvatureMethod>()), params_(params) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("curvature method: " + error);
}

}  // namespace ph
