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

DepthMethod::DepthMethod(const DepthParams& params) : Method(BuiltinMethod::depth), params_(params) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("depth method: " + error);
}

}  // namespace ph
