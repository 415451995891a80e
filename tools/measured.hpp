// What the measuring commands (accuracy, stability) share: the methods they measure and their CSV files.
#pragma once

#include <fmt/core.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
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

inline std::FILE* open_csv(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error(fmt::format("{}: cannot open for writing", path.string()));
  return f;
}

inline void close_csv(std::FILE* f, const std::filesystem::path& path) {
  if (std::fclose(f) != 0) throw std::runtime_error(fmt::format("{}: write failed", path.string()));
}

}  // namespace ph::tools
