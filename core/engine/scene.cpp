#include "core/engine/scene.hpp"

#include <algorithm>

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/engine/direction_lut.hpp"

namespace ph {

namespace {

template <typename T>
bool matches(const std::optional<Grid<T>>& grid, Rect r) {
  return grid && grid->width == r.w && grid->height == r.h &&
         grid->values.size() == static_cast<std::size_t>(r.w) * static_cast<std::size_t>(r.h);
}

void check_region(const Region& region) {
  const std::string who = "region '" + region.name + "': ";
  if (region.rect.w <= 0 || region.rect.h <= 0) throw std::invalid_argument(who + "width and height must be > 0");
  if (!region.method) throw std::invalid_argument(who + "no method");
  for (const EffectPtr& effect : region.effects) {
    if (!effect) throw std::invalid_argument(who + "an empty effect");
  }
  if (region.options) {
    if (const std::string error = validate(*region.options); !error.empty()) throw std::invalid_argument(who + error);
  }
  if (region.effects.size() > kMaxEffectsPerRegion) {
    throw std::invalid_argument(who + "more than " + std::to_string(kMaxEffectsPerRegion) + " effects");
  }
  const FieldNeeds needs = region.method->needs();
  if (needs.gradient && !matches(region.fields.gradient, region.rect)) {
    throw std::invalid_argument(who + "the method needs normals matching the region's size");
  }
  if (needs.depth && !matches(region.fields.depth, region.rect)) {
    throw std::invalid_argument(who + "the method needs a depth field matching the region's size");
  }
  // A field the method may read without needing it must match too: the walk reads every field of a region at
  // one index (core/engine/field.hpp, FieldTexel).
  if ((region.fields.gradient && !matches(region.fields.gradient, region.rect)) ||
      (region.fields.depth && !matches(region.fields.depth, region.rect))) {
    throw std::invalid_argument(who + "a field does not match the region's size");
  }
}

// Whether two boxes share a texel.
bool overlap(Rect a, Rect b) {
  return std::int64_t{a.x} < std::int64_t{b.x} + b.w && std::int64_t{b.x} < std::int64_t{a.x} + a.w &&
         std::int64_t{a.y} < std::int64_t{b.y} + b.h && std::int64_t{b.y} < std::int64_t{a.y} + a.h;
}

// Loaders repair invalid texels; this keeps the no-NaN promise for scenes built any other way.
void flatten_non_finite(RegionFields& fields) {
  if (fields.gradient) {
    for (Gradient& g : fields.gradient->values) {
      if (!std::isfinite(g.x) || !std::isfinite(g.y)) g = {};
    }
  }
  if (fields.depth) {
    for (float& h : fields.depth->values) {
      if (!std::isfinite(h)) h = 0.0f;
    }
  }
}

}  // namespace

Scene::Scene(std::vector<Region> regions) : regions_(std::move(regions)) {
  for (Region& region : regions_) {
    check_region(region);
    flatten_non_finite(region.fields);
    region.method->prepare(region.fields);
    has_effects_ = has_effects_ || !region.effects.empty();
    per_region_options_ = per_region_options_ || region.options.has_value();
  }
  covered_.assign(regions_.size(), 0);
  for (std::size_t i = 0; i < regions_.size(); ++i) {
    for (std::size_t j = i + 1; j < regions_.size() && covered_[i] == 0; ++j) {
      covered_[i] = overlap(regions_[i].rect, regions_[j].rect) ? 1 : 0;
    }
  }
  std::vector<Rect> boxes;
  for (const Region& region : regions_) boxes.push_back(region.rect);
  flat_tiles_ = FlatTiles(boxes);
  if (per_region_options_) set_options(options_);  // the tables the regions' own options need
}

std::size_t Scene::bytes() const {
  std::size_t total = 0;
  for (const Region& region : regions_) {
    total += region.fields.bytes();
    for (const EffectPtr& effect : region.effects) total += effect->bytes();
  }
  return total + lut_bytes() + flat_tiles_.bytes();
}

void Scene::set_region_options(std::size_t i, std::optional<EngineOptions> options) {
  if (options) {
    if (auto error = validate(*options); !error.empty()) throw std::invalid_argument("engine options: " + error);
  }
  regions_.at(i).options = std::move(options);
  per_region_options_ = std::any_of(regions_.begin(), regions_.end(), [](const Region& r) { return r.options; });
}

void Scene::set_options(const EngineOptions& options) {
  if (auto error = validate(options); !error.empty()) throw std::invalid_argument("engine options: " + error);
  std::vector<std::shared_ptr<const DirectionLut>> luts(regions_.size());
  bool any = false;
  for (std::size_t i = 0; i < regions_.size(); ++i) {
    const EngineOptions& own = regions_[i].options.value_or(options);
    if (own.traversal != Traversal::direction_lut) continue;
    const Method& method = *regions_[i].method;
    if (method.cd_lower_bound() == 1.0 && method.cd_upper_bound() == 1.0) continue;  // C/D 1: nothing to look up
    // A table already built for the same number of directions is kept (the fields do not change).
    const bool reuse = i < luts_.size() && luts_[i] && luts_[i]->directions() == own.lut_directions;
    luts[i] =
        reuse ? luts_[i] : std::make_shared<const DirectionLut>(build_direction_lut(*this, i, own.lut_directions));
    any = true;
  }
  options_ = options;
  if (any) {
    luts_ = std::move(luts);
  } else {
    luts_.clear();
    luts_.shrink_to_fit();
  }
}

std::size_t Scene::lut_bytes() const {
  std::size_t total = 0;
  for (const auto& lut : luts_) total += lut ? lut->bytes() : 0;
  return total;
}

}  // namespace ph
