#include "core/engine/method_depth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ph {

namespace {

bool in_cd_range(double v) { return v >= 1.0 && v <= kMaxCdFactor; }  // (NaN fails)

}  // namespace

std::string validate(const DepthParams& p) {
  if (!std::isfinite(p.gain)) return "gain must be a finite number";
  if (!in_cd_range(p.kmax)) return "kmax must be a finite number from 1 to 100";
  if (!in_cd_range(p.kmin)) return "kmin must be a finite number from 1 to 100";
  return {};
}

DepthParams DepthMethod::parse_params(const ParamReader& reader) {
  DepthParams p;
  auto number = [&](std::string_view key, double& value, bool (*ok)(double), std::string_view allowed) {
    if (const std::optional<double> v = reader.number(key)) value = *v;
    if (!ok(value)) reader.reject(key, allowed);
  };
  number(
      "gain", p.gain, [](double v) { return static_cast<bool>(std::isfinite(v)); }, "must be a finite number");
  number("kmax", p.kmax, in_cd_range, "must be a finite number from 1 to 100");
  number("kmin", p.kmin, in_cd_range, "must be a finite number from 1 to 100");
  if (auto error = validate(p); !error.empty()) reader.reject("", error);
  return p;
}

DepthMethod::DepthMethod(const DepthParams& params)
    : Method(method_tag<DepthMethod>()), params_(params), lowest_(1.0 / params.kmin) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("depth method: " + error);
}

}  // namespace ph
