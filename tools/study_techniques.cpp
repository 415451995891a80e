#include "tools/study_techniques.hpp"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "core/effects/effect_materials.hpp"
#include "core/effects/effect_wells.hpp"
#include "core/engine/methods.hpp"

namespace ph::tools {

namespace {

// Reads one value, delta_beta_sign, and nothing else: every other parameter keeps its default.
class SignReader final : public ParamReader {
 public:
  explicit SignReader(double sign) : sign_(sign) {}
  std::optional<double> number(std::string_view key) const override {
    if (key == "delta_beta_sign") return sign_;
    return std::nullopt;
  }
  std::optional<std::pair<double, double>> pair(std::string_view) const override { return std::nullopt; }
  [[noreturn]] void reject(std::string_view key, std::string_view message) const override {
    throw std::invalid_argument(std::string(key) + ": " + std::string(message));
  }

 private:
  double sign_;
};

bool has_key(const MethodEntry& entry, std::string_view key) {
  return std::find(entry.keys.begin(), entry.keys.end(), key) != entry.keys.end();
}

// 0: float fields (the targets are exact), which the class map treats as 16-bit.
constexpr int kExactFields = 0;

}  // namespace

std::vector<StudyTechnique> study_techniques() {
  std::vector<StudyTechnique> out;
  const MethodRegistry registry = builtin_methods();
  for (const auto& entry : registry.entries()) {
    if (has_key(*entry, "delta_beta_sign")) {
      for (double sign : {1.0, -1.0}) {
        out.push_back(
            {entry->name + (sign > 0 ? ":sign+1" : ":sign-1"), entry->make(entry->parse(SignReader(sign))), {}});
      }
    } else {
      out.push_back({entry->name, entry->make(entry->defaults()), {}});
    }
  }
  const MethodPtr curvature = make_default_method(registry, "curvature");
  out.push_back({"curvature+materials", curvature, [](const RegionFields& f, std::int32_t w, std::int32_t h) {
                   return std::vector<EffectPtr>{make_materials_effect(f, w, h, MaterialsParams{}, kExactFields)};
                 }});
  out.push_back({"curvature+wells", curvature, [](const RegionFields& f, std::int32_t w, std::int32_t h) {
                   return std::vector<EffectPtr>{make_wells_effect(f, w, h, WellsParams{})};
                 }});
  return out;
}

std::string paper_method_of(const std::string& technique) {
  if (technique == kPaperDepth) return "depth";
  if (technique.rfind("curvature:sign", 0) == 0) return "curvature";
  return "";
}

}  // namespace ph::tools
