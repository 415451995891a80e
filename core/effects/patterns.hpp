// Isophote and contour masks of a region (second paper, Sections 2.1-2.2; docs/METHODS.md, "Isophotes,
// contours and their distance fields"), the patterns that gravity wells attract to, and their nearest-pattern fields
// (core/effects/distance_transform.hpp).
//
// Conventions: screen frame, x right, y down, z toward the viewer; a texel's unit normal is
// n = (-h_x, -h_y, 1) / |(-h_x, -h_y, 1)| from the stored gradient (field.hpp), and the light vector l
// points from the surface toward the light, in the same frame: (0, 0, 1) is a light behind the viewer,
// (-1, -1, 1) one at the top left. A texel is lit as n·l.
//
// Two rules mark a pattern, for a per-texel value v (n·l for isophotes, h for contours) and a target c:
//   crossing: the level c is crossed between a texel and a 4-neighbour (one of them has v >= c, the other
//             v < c), and of the two the texel whose v is nearer c is marked (ties: the one with v >= c).
//             The line is about one texel thin whatever the slope, and 8-connected: consecutive crossings
//             of one line lie in one 2x2 block of texels. A texel with v exactly c counts as above.
//   band:     |v - c| < tol, the paper's literal definition. Its width depends on the slope (wide on
//             shallow ground, broken on steep ground); the only rule that finds c at an extremum of v
//             (the paper's alpha = 0 with l = (0, 0, 1) marks the flat tops and bottoms).
// Non-finite values are never marked and cross nothing. Masks hold 1 for pattern texels, 0 elsewhere.
// Invalid parameters throw std::invalid_argument naming the parameter.
#pragma once

#include <cstdint>
#include <vector>

#include "core/effects/distance_transform.hpp"
#include "core/engine/field.hpp"

namespace ph {

enum class PatternRule { crossing, band };

// Direction toward the light, any length > 0 (normalised before use).
struct LightVector {
  double x = 0.0;
  double y = 0.0;
  double z = 1.0;
};

// The light's length, without overflow or underflow in its squares (std::hypot): a light of (1e200, 1e200, 1e200)
// is a direction as good as (1, 1, 1). Finite and above 0 for every light a pattern can use.
double light_length(const LightVector& light);

struct IsophoteParams {
  LightVector light{-1.0, -1.0, 2.0};  // from the top left, 35.3 degrees off the view axis
  double cos_alpha = 0.95;             // c: the isophote n·l = c, in [-1, 1] (here 18.2 degrees off the light)
  PatternRule rule = PatternRule::crossing;
  double tol = 0.02;  // band half-width in units of n·l (band rule only), >= 0
};

struct ContourParams {
  // Levels, heights in screen px as in the depth field. An explicit list wins; otherwise `count`
  // levels evenly spaced strictly inside the field's range: min + (max - min) k / (count + 1),
  // k = 1..count (the extremes themselves would mark single points). A flat field has none.
  std::int32_t count = 8;      // 0 to kMaxContourLevels
  std::vector<double> levels;  // finite; sorted and deduplicated before use
  PatternRule rule = PatternRule::crossing;
  double tol = 0.5;  // band half-width, px of height (band rule only), >= 0
};

inline constexpr std::int32_t kMaxContourLevels = 4096;

// The levels `contour_mask` uses for `depth`, ascending.
std::vector<double> contour_levels(const DepthField& depth, const ContourParams& params);

// Isophote texels of a gradient field.
Grid<std::uint8_t> isophote_mask(const GradientField& gradient, const IsophoteParams& params);

// Contour texels of a depth field, over all its levels.
Grid<std::uint8_t> contour_mask(const DepthField& depth, const ContourParams& params);

// Mask and nearest-pattern field in one call: what a region recomputes when the light, the levels or
// a tolerance change on reload.
PatternField isophote_field(const GradientField& gradient, const IsophoteParams& params, float radius);
PatternField contour_field(const DepthField& depth, const ContourParams& params, float radius);

}  // namespace ph
