// What the measuring commands (accuracy, stability) share: the methods they measure.
#pragma once

#include <utility>
#include <vector>

#include "core/engine/methods.hpp"

namespace ph::tools {

// Every method of the registry (core/engine/methods.hpp) that is not C/D 1 throughout, with its default
// parameters, in the registry's order.
inline std::vector<MethodPtr> measured_methods() {
  std::vector<MethodPtr> out;
  const MethodRegistry registry = builtin_methods();
  for (const auto& entry : registry.entries()) {
    MethodPtr method = entry->make(entry->defaults());
    if (method->cd_lower_bound() != 1.0 || method->cd_upper_bound() != 1.0) out.push_back(std::move(method));
  }
  return out;
}

}  // namespace ph::tools
