#include "core/method_depth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ph {

std::string validate(const DepthParams& p) {
  if (!std::isfinite(p.gain)) return "gain must be a finite number";
  if (!std::isfinite(p.kmax) || p.kmax < 1.0) return "kmax must be a finite number >= 1";
  if (!std::isfinite(p.kmin) || p.kmin < 1.0) return "kmin must be a finite number >= 1";
  return {};
}

double depth_cd(const DepthParams& p, double h1, double h2, double step_px, StepDetail* detail) {
  const double dh = h2 - h1;
  const double slope = step_px > 0.0 ? dh / step_px : 0.0;
  double cd = std::clamp(1.0 + p.gain * slope, 1.0 / p.kmin, p.kmax);
  if (!std::isfinite(cd)) cd = 1.0;  // unreachable for finite heights; keeps the no-NaN promise cheap
  if (detail != nullptr) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    *detail = {nan, nan, nan, nan, dh};
  }
  return cd;
}

DepthMethod::DepthMethod(const DepthParams& params) : params_(params) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("depth method: " + error);
}

TexelSample DepthMethod::sample(const RegionFields* fields, Texel local, Vec2 /*direction*/) const {
  if (fields == nullptr || !fields->depth) return {0.0, 0.0};
  return {fields->depth->at(local.x, local.y), 0.0};
}

double DepthMethod::cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const {
  return depth_cd(params_, from.v0, to.v0, step_px, detail);
}

}  // namespace ph
