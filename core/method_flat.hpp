// The flat method: C/D 1 everywhere. For a region whose only rendering is its frame effects (materials,
// gravity wells), so that the region exists for them without changing the walk.
#pragma once

#include "core/method.hpp"

namespace ph {

class FlatMethod final : public Method {
 public:
  std::string_view name() const override { return "none"; }
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
