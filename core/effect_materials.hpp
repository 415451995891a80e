// Curvature classes rendered as materials (the second paper, Section 2.3; docs/INTERROGATION.md), as a frame
// effect (core/effect.hpp): each texel's Gaussian-curvature class selects a material, and the material sets the
// C/D ratio of the frames that start on it. Planar: none; parabolic: damping (C/D grows with hand speed);
// elliptic: static friction (the cursor sticks, breaks away, slips); hyperbolic: stick-slip (static and dynamic
// friction, sticking again periodically: rough). docs/INTERROGATION.md ("Materials") documents the parameters,
// the state machine, time handling and the no-trap guarantee.
//
// The class map is computed once, at construction, and is all the effect stores (1 byte per texel). The state
// (stuck or slipping, motor travel in the current phase, time of the last motion) lives in the cursor, and only
// event times drive it, so a replay is deterministic.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/curvature_class.hpp"
#include "core/effect.hpp"
#include "core/field.hpp"

namespace ph {

enum class Material : std::uint8_t { none, damping, friction, stick_slip };

const char* material_name(Material m);  // "none", "damping", "friction", "stick_slip"
std::optional<Material> parse_material(std::string_view name);

// Which field the classes come from. automatic: the normals (gradient) when the region has them, else its depth.
enum class ClassSource : std::uint8_t { automatic, normals, depth };

const char* class_source_name(ClassSource s);  // "auto", "normals", "depth"
std::optional<ClassSource> parse_class_source(std::string_view name);

// Viscous damping: C/D = min(1 + k * speed, cd_max), speed = the frame's motor length over the time since the
// previous frame (motor px/s at the screen).
struct DampingParams {
  double k = 0.002;     // C/D per motor px/s: C/D 2 at 500 px/s; bounds [0, 1]
  double cd_max = 3.0;  // cap, reached at 1000 px/s by default; bounds [1, 20]
  // Frame interval assumed when the speed is unknown (no event times, or no later time than the previous frame's):
  // a 125 Hz mouse. 0: no damping then. Bounds [0, 100]
  double fallback_interval_ms = 8.0;
};

// Static friction with breakaway: stuck at stuck_cd (the cursor creeps, it never stops dead) until breakaway_px
// of motor travel, then slipping at slip_cd until the hand rests for rest_ms.
struct FrictionParams {
  double stuck_cd = 6.0;       // bounds [1, 20]
  double breakaway_px = 10.0;  // motor px; bounds [0.1, 500]
  double slip_cd = 1.0;        // bounds [1, 20]
  double rest_ms = 100.0;      // a gap between moving frames this long is a rest; bounds [1, 10000]
};

// Stick-slip: as friction, but the slip phase has a higher (dynamic) C/D and ends after slip_px of motor travel:
// the cursor sticks again, periodically (a period of breakaway_px + slip_px motor px).
struct StickSlipParams {
  double stuck_cd = 4.0;      // bounds [1, 20]
  double breakaway_px = 3.0;  // bounds [0.1, 500]
  double slip_cd = 2.0;       // bounds [1, 20]
  double slip_px = 6.0;       // bounds [0.1, 500]
  double rest_ms = 100.0;     // bounds [1, 10000]
};

struct MaterialsParams {
  ClassSource source = ClassSource::automatic;
  std::int32_t filter_radius = 0;           // derivative filter radius, texels; 0: the default for the map's
                                            // bit depth (DerivativeFilter::recommended); bounds 0 or [1, 64]
  std::optional<double> planar_curvedness;  // 1/px; default by bit depth (ClassTolerances); bounds [0, 1]
  std::optional<double> parabolic_ratio;    // default by bit depth (ClassTolerances); bounds [0, 1]
  std::array<Material, 4> materials = {Material::none, Material::damping, Material::friction,
                                       Material::stick_slip};  // indexed by CurvatureClass
  DampingParams damping;
  FrictionParams friction;
  StickSlipParams stick_slip;

  Material& material(CurvatureClass c) { return materials[static_cast<std::size_t>(c)]; }
  Material material(CurvatureClass c) const { return materials[static_cast<std::size_t>(c)]; }
};

// "" when every parameter is within its bounds, else a message naming the first one that is not and its range.
std::string validate(const MaterialsParams& params);

// The fields the class map is computed from, given what the region has. The effect needs them only while it is
// constructed: it keeps its class map, not the fields.
FieldNeeds materials_needs(const MaterialsParams& params, bool has_normals, bool has_depth);

class MaterialsEffect final : public Effect {
 public:
  // From a class map (CurvatureClass values; anything else counts as planar). Throws std::invalid_argument if
  // validate(params) fails.
  MaterialsEffect(Grid<std::uint8_t> classes, const MaterialsParams& params);

  std::string_view name() const override { return "materials"; }
  Vec2 apply(const EffectInput& in, EffectState& state) const override;
  double min_gain() const override { return 1.0 / cd_high_; }
  double max_gain() const override { return 1.0 / cd_low_; }
  std::size_t bytes() const override { return classes_.bytes(); }

  const Grid<std::uint8_t>& classes() const { return classes_; }
  const MaterialsParams& params() const { return params_; }
  // The range every frame's C/D lies in, over the materials the classes map to.
  double cd_low() const { return cd_low_; }
  double cd_high() const { return cd_high_; }

 private:
  Grid<std::uint8_t> classes_;
  MaterialsParams params_;
  double cd_low_ = 1.0, cd_high_ = 1.0;
};

// The class map of a region (width x height) from its normals or depth as params.source says, with the filter
// and tolerances of params or, where they are left at their defaults, those for bit_depth (8 or 16; anything
// else, e.g. 0 for unknown or 32 for float maps, counts as 16). Throws std::invalid_argument if the field the
// source needs is missing or not width x height.
Grid<std::uint8_t> materials_class_map(const RegionFields& fields, std::int32_t width, std::int32_t height,
                                       const MaterialsParams& params, int bit_depth);

// The effect for a region: materials_class_map, then MaterialsEffect. Throws std::invalid_argument as they do.
EffectPtr make_materials_effect(const RegionFields& fields, std::int32_t width, std::int32_t height,
                                const MaterialsParams& params, int bit_depth);

}  // namespace ph
