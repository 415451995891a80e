// The flat method: C/D 1 everywhere. For a region whose only rendering is its frame effects (materials,
// gravity wells), so that the region exists for them without changing the walk.
#pragma once

#include <array>
#include <string_view>

#include "core/engine/method.hpp"
#include "core/engine/method_registry.hpp"

namespace ph {

class FlatMethod final : public Method {
 public:
  struct Params {};
  static constexpr std::string_view kName = "none";
  static constexpr std::array<std::string_view, 0> kParamKeys = {};
  static Params parse_params(const ParamReader&) { return {}; }

  FlatMethod() : Method(method_tag<FlatMethod>()) {}
  explicit FlatMethod(const Params&) : FlatMethod() {}

  std::string_view name() const override { return kName; }
  FieldNeeds needs() const override { return {}; }
  TexelSample sample(const RegionFields*, Texel, Vec2) const override { return {}; }
  double cd(const TexelSample&, const TexelSample&, double, StepDetail* detail) const override {
    if (detail != nullptr) *detail = empty_step_detail();
    return 1.0;
  }
  double cd_lower_bound() const override { return 1.0; }
  double cd_upper_bound() const override { return 1.0; }
};

}  // namespace ph
