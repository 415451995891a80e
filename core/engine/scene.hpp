// A scene: regions on the screen, each with its fields and its method. Later regions lie on top of
// earlier ones; outside every region the surface is flat (docs/METHODS.md, "Screen, regions and fields").
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/engine/effect.hpp"
#include "core/engine/engine_options.hpp"
#include "core/engine/field.hpp"
#include "core/engine/flat_tiles.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/method.hpp"

namespace ph {

class DirectionLut;

struct Region {
  std::string name;
  Rect rect;  // on screen; the fields are exactly rect.w x rect.h texels
  RegionFields fields;
  MethodPtr method;
  std::vector<EffectPtr> effects;  // applied in order to each frame that starts in the region (at most
                                   // kMaxEffectsPerRegion), each to what the one before handed on
  // The region's own traversal variant, for the frames that start in it (all of such a frame, wherever it
  // goes); none: the scene's (Scene::set_options).
  std::optional<EngineOptions> options;

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

  // Whether a later region overlaps region i: only then can a texel of its box belong to another region, and
  // a walk through it must look up the owner of each texel it enters.
  bool covered(std::size_t i) const { return covered_[i] != 0; }

  // Where a frame surely meets no region, judged from a coarse grid without the region list (FlatTiles).
  const FlatTiles& flat_tiles() const { return flat_tiles_; }

  std::size_t bytes() const;  // fields, effects, direction tables and the flat tiles

  // How advance() walks this scene (core/engine/engine_options.hpp); default: exact, nearest. Regions with
  // options of their own keep them. Every region that walks with direction_lut (its own options or these) and
  // whose method is not C/D 1 throughout gets its table, with its own number of directions (memory:
  // Scene::lut_bytes); the others have none. Throws std::invalid_argument if the options are invalid.
  void set_options(const EngineOptions& options);
  // Region `i`'s own options (none: the scene's), set after the scene is made: what traversal = "auto" chooses
  // looks at the region as its method prepared it (the hybrid's step marks). Call set_options after it.
  void set_region_options(std::size_t i, std::optional<EngineOptions> options);
  const EngineOptions& options() const { return options_; }

  // The options of a frame that starts on texel `start`: its region's, else the scene's.
  const EngineOptions& frame_options(Texel start) const {
    if (!per_region_options_) [[likely]]
      return options_;
    const std::optional<std::size_t> i = owner(start);
    return i && regions_[*i].options ? *regions_[*i].options : options_;
  }

  // Direction table of region i, or null (direction_lut not selected, or a method that is C/D 1 throughout).
  const DirectionLut* direction_lut(std::size_t i) const { return i < luts_.size() ? luts_[i].get() : nullptr; }
  std::size_t lut_bytes() const;

 private:
  std::vector<Region> regions_;
  std::vector<std::uint8_t> covered_;  // per region: covered(i)
  FlatTiles flat_tiles_;
  bool has_effects_ = false;
  bool per_region_options_ = false;  // some region has options of its own
  EngineOptions options_;
  std::vector<std::shared_ptr<const DirectionLut>> luts_;  // empty unless some region walks with direction_lut
};

}  // namespace ph
