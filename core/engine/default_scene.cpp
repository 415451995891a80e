#include "core/engine/default_scene.hpp"

#include <memory>

#include "core/engine/method_curvature.hpp"
#include "core/engine/targets.hpp"

namespace ph {

namespace {

Region target_region(const char* name, std::int32_t x, std::int32_t y, const MethodPtr& method) {
  for (const TargetSpec& spec : all_targets()) {
    if (spec.name() != name) continue;
    Region region;
    region.name = name;
    region.rect = {x, y, spec.size, spec.size};
    region.fields = target_fields(spec, method->needs());
    region.method = method;
    return region;
  }
  return {};  // unreachable: the names below are targets
}

}  // namespace

Scene default_scene() { return default_scene(std::make_shared<CurvatureMethod>(CurvatureParams{})); }

Scene default_scene(const MethodPtr& method) {
  std::vector<Region> regions;
  regions.push_back(target_region("bump-gaussian-h1-r200", 135, 290, method));
  regions.push_back(target_region("hole-polynomial-h1-r200", 710, 290, method));
  regions.push_back(target_region("bump-linear-h1-r100", 1285, 290, method));
  return Scene(std::move(regions));
}

}  // namespace ph
