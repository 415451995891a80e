#include "core/engine/default_scene.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include "core/engine/method_curvature.hpp"
#include "core/engine/targets.hpp"

namespace ph {

namespace {

// In the order they are dropped from the right where the desktop is narrow: a bump and a hole stay together.
constexpr std::array<std::string_view, 3> kTargets = {"bump-gaussian-h1-r200", "hole-polynomial-h1-r200",
                                                      "bump-linear-h1-r100"};
constexpr std::int32_t kSide = 500;  // each target's size, px
constexpr std::int32_t kGap = 75;    // between targets where the desktop is wide enough

const TargetSpec& target_named(const std::vector<TargetSpec>& targets, std::string_view name) {
  return *std::find_if(targets.begin(), targets.end(), [name](const TargetSpec& t) { return t.name() == name; });
}

}  // namespace

std::vector<Rect> default_scene_layout(const Rect& desktop) {
  std::int64_t count = kTargets.size();
  while (count > 1 && count * kSide > desktop.w) --count;
  const std::int64_t gap = count > 1 ? std::min<std::int64_t>(kGap, (desktop.w - count * kSide) / (count + 1)) : 0;
  const std::int64_t width = count * kSide + (count - 1) * gap;
  const std::int64_t left = desktop.x + (desktop.w - width) / 2, top = desktop.y + (desktop.h - kSide) / 2;
  std::vector<Rect> rects;
  for (std::int64_t i = 0; i < count; ++i)
    rects.push_back(
        {static_cast<std::int32_t>(left + i * (kSide + gap)), static_cast<std::int32_t>(top), kSide, kSide});
  return rects;
}

Scene default_scene(const Rect& desktop) {
  return default_scene(std::make_shared<CurvatureMethod>(CurvatureParams{}), desktop);
}

bool default_scene_laid_out_for(const Scene& scene, const Rect& desktop) {
  const std::vector<Rect> places = default_scene_layout(desktop);
  if (places.size() != scene.regions().size()) return false;
  for (std::size_t i = 0; i < places.size(); ++i) {
    if (scene.regions()[i].rect != places[i]) return false;
  }
  return true;
}

std::string default_scene_places(const Scene& scene) {
  std::string places;
  for (const Region& r : scene.regions()) {
    places +=
        (places.empty() ? "" : ", ") + r.name + " at " + std::to_string(r.rect.x) + "," + std::to_string(r.rect.y);
  }
  const Rect first = scene.regions().empty() ? Rect{} : scene.regions().front().rect;
  return places + " (" + std::to_string(first.w) + "x" + std::to_string(first.h) + " px each)";
}

Scene default_scene(const MethodPtr& method, const Rect& desktop) {
  const std::vector<TargetSpec> targets = all_targets();
  std::vector<Region> regions;
  const std::vector<Rect> rects = default_scene_layout(desktop);
  for (std::size_t i = 0; i < rects.size(); ++i) {
    const TargetSpec& spec = target_named(targets, kTargets[i]);
    Region region;
    region.name = std::string(kTargets[i]);
    region.rect = rects[i];
    region.fields = target_fields(spec, method->needs());
    region.method = method;
    regions.push_back(std::move(region));
  }
  return Scene(std::move(regions));
}

Rect default_scene_area(const Rect& desktop, const std::vector<Rect>& outputs) {
  Rect largest = desktop;
  std::int64_t largest_area = -1;
  for (const Rect& o : outputs) {
    if (o.area() > largest_area) {
      largest = o;
      largest_area = o.area();
    }
  }
  return largest;
}

}  // namespace ph
