// A scene: regions on the screen, each with its fields and its method. Later regions lie on top of
// earlier ones; outside every region the surface is flat (docs/METHODS.md, "Screen, regions and fields").
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/effect.hpp"
#include "core/engine_options.hpp"
#include "core/field.hpp"
#include "core/geometry.hpp"
#include "core/method.hpp"

namespace ph {

class DirectionLut;

struct Region {
  std::string name;
  Rect rect;  // on screen; the fields are exactly rect.w x rect.h texels
  RegionFields fields;
  MethodPtr method;
  std::vector<EffectPtr> effects;  // applied in order to each frame that starts in the region (at most
                                   // kMaxEffectsPerRegion), each to what the one before handed on

  // Texel of the region's fields under a screen texel the region contains.
  Texel local(Texel screen) const { return {screen.x - rect.x, screen.y - rect.y}; }
};

class Scene {
 public:
  Scene() = default;
  // Throws std::invalid_argument if a region is empty, has no method, has an empty effect or more than
  // kMaxEffectsPerRegion, or its fields do not match its size or lack what its method needs.
  explicit Scene(std::vector<Region> regions);

  const std::vector<Region>& regions() const { return regions_; }
  bool empty() const { return regions_.empty(); }
  bool has_effects() const { return has_effects_; }

  // Index of the topmost region containing the texel, or nullopt on the flat outside.
  std::optional<std::size_t> owner(Texel t) const {
    for (std::size_t i = regions_.size(); i-- > 0;) {
      if (regions_[i].rect.contains(t)) return i;
    }
    return std::nullopt;
  }

  std::size_t bytes() const;  // fields, effects and direction tables

  // How advance() walks this scene (core/engine_options.hpp); default: exact, nearest. Selecting
  // direction_lut builds the table of every region with a built-in method (memory: Scene::lut_bytes);
  // any other traversal frees them. Throws std::invalid_argument if the options are invalid.
  void set_options(const EngineOptions& options);
  const EngineOptions& options() const { return options_; }

  // Direction table of region i, or null (direction_lut not selected, or not a built-in method).
  const DirectionLut* direction_lut(std::size_t i) const { return i < luts_.size() ? luts_[i].get() : nullptr; }
  std::size_t lut_bytes() const;

 private:
  std::vector<Region> regions_;
  bool has_effects_ = false;
  EngineOptions options_;
  std::vector<std::shared_ptr<const DirectionLut>> luts_;  // empty unless direction_lut is selected
};

}  // namespace ph
