// Gravity wells (second paper, Section 2.3; docs/INTERROGATION.md, "Gravity
// wells"): isophotes or contour lines attract the cursor. Within a radius of influence R of the nearest
// pattern texel, motion toward it is faster and motion away slower, by a display gain
//
//   g = clamp(1 + strength · c · f(d / R), min_gain, max_gain),   f(s) = 1 - s² (3 - 2 s)
//
// with d the distance from the cursor to that texel's centre, c the cosine between the motor
// displacement and the direction toward it. Optionally, within snap_px of the pattern a frame also
// moves the cursor toward it by at most snap_fraction × |motor| (never past the pattern texel's centre).
// Bounded both ways, so a sustained push in any direction leaves the well (no trap).
//
// The pattern and its nearest-pattern field (core/patterns.hpp, core/distance_transform.hpp) are built
// once when the effect is made, which is what a config reload redoes: the field is all that is stored,
// 4 bytes per texel. The effect is stateless: it never touches EffectState.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/distance_transform.hpp"
#include "core/effect.hpp"
#include "core/field.hpp"
#include "core/patterns.hpp"

namespace ph {

enum class WellPattern { isophotes, contours };

// Bounds (validate() enforces them; every one keeps a sustained push escaping in bounded travel).
inline constexpr double kWellsMinRadiusPx = 1.0;
inline constexpr double kWellsMaxRadiusPx = 1024.0;
inline constexpr double kWellsMaxStrength = 10.0;
inline constexpr double kWellsMaxGainLimit = 4.0;  // max_gain in [1, 4]
inline constexpr double kWellsMinGainLimit = 0.1;  // min_gain in [0.1, 1]
inline constexpr double kWellsOnPatternPx = 0.5;   // closer than this to the pattern texel's centre: no pull

struct WellsParams {
  WellPattern pattern = WellPattern::isophotes;  // isophotes need the gradient field, contours the depth field
  IsophoteParams isophotes;                      // light, cos_alpha, rule, tol (defaults: core/patterns.hpp)
  ContourParams contours;                        // count or levels, rule, tol (defaults: core/patterns.hpp)
  double radius_px = 16.0;                       // R, radius of influence: [1, 1024] px
  double strength = 1.0;        // gain change at the pattern for motion straight toward (+) or away (-): [0, 10]
  double max_gain = 2.0;        // most speed-up (display / motor) toward the pattern: [1, 4]
  double min_gain = 0.5;        // most slow-down away from it: [0.1, 1]
  double snap_px = 0.0;         // snap within this distance of the pattern; 0 = no snap: [0, radius_px]
  double snap_fraction = 0.25;  // most snap displacement per frame, × |motor|: [0, min_gain / 2]
};

// "" when valid; otherwise a message naming the parameter and its allowed range.
std::string validate(const WellsParams& params);

// The fields the wells read: the gradient for isophotes, the depth for contours.
FieldNeeds wells_needs(const WellsParams& params);

class WellsEffect final : public Effect {
 public:
  // `field` as make_wells_effect builds it (radius radius_px + 1, so every point within radius_px of a
  // pattern texel's centre finds one). Throws std::invalid_argument if params are invalid.
  WellsEffect(PatternField field, const WellsParams& params);

  std::string_view name() const override { return "wells"; }
  Vec2 apply(const EffectInput& in, EffectState& state) const override;
  // With snap the bounds widen by snap_fraction (the pull toward the pattern adds or takes that much).
  double min_gain() const override { return min_gain_; }
  double max_gain() const override { return max_gain_; }
  std::size_t bytes() const override { return field_.bytes(); }

  const PatternField& field() const { return field_; }
  const WellsParams& params() const { return params_; }

 private:
  PatternField field_;
  WellsParams params_;
  double min_gain_;
  double max_gain_;
};

// The wells of a width x height region from its fields: builds the mask and the nearest-pattern field.
// Throws std::invalid_argument if params are invalid or the field the pattern needs is missing or not
// width x height.
EffectPtr make_wells_effect(const RegionFields& fields, std::int32_t width, std::int32_t height,
                            const WellsParams& params);

}  // namespace ph
