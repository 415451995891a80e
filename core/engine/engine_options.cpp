#include "core/engine/engine_options.hpp"

namespace ph {

std::string validate(const EngineOptions& o) {
  if (o.lut_directions != 8 && o.lut_directions != 16) return "lut_directions must be 8 or 16";
  if (o.traversal == Traversal::direction_lut && o.sampling != Sampling::nearest) {
    return "direction_lut precomputes one C/D per texel: it takes sampling = \"nearest\" only";
  }
  return {};
}

std::string_view name_of(Traversal t) {
  switch (t) {
    case Traversal::exact:
      return "exact";
    case Traversal::unit_steps:
      return "unit_steps";
    case Traversal::frame_midpoint:
      return "frame_midpoint";
    case Traversal::direction_lut:
      return "direction_lut";
  }
  return "exact";
}

std::string_view name_of(Sampling s) { return s == Sampling::bilinear ? "bilinear" : "nearest"; }

std::optional<Traversal> parse_traversal(std::string_view name) {
  for (Traversal t : kAllTraversals) {
    if (name_of(t) == name) return t;
  }
  return std::nullopt;
}

std::optional<Sampling> parse_sampling(std::string_view name) {
  for (Sampling s : kAllSamplings) {
    if (name_of(s) == name) return s;
  }
  return std::nullopt;
}

std::vector<EngineOptions> all_engine_variants() {
  std::vector<EngineOptions> out;
  for (Traversal t : {Traversal::exact, Traversal::unit_steps, Traversal::frame_midpoint}) {
    for (Sampling s : kAllSamplings) out.push_back({t, s, 16});
  }
  out.push_back({Traversal::direction_lut, Sampling::nearest, 8});
  out.push_back({Traversal::direction_lut, Sampling::nearest, 16});
  return out;
}

std::string label_of(const EngineOptions& o) {
  std::string label(name_of(o.traversal));
  if (o.traversal == Traversal::direction_lut) label += std::to_string(o.lut_directions);
  if (o.sampling != Sampling::nearest) {
    label += '+';  // not "+" + std::string(...): GCC 12 -O3 warns -Wrestrict on that (a false positive)
    label += name_of(o.sampling);
  }
  return label;
}

}  // namespace ph
