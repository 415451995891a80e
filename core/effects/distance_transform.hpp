// The nearest-pattern field behind gravity wells: for every texel of a region, the exact Euclidean
// distance to the nearest texel of a pattern (an isophote or contour mask, core/effects/patterns.hpp) and which
// texel that is, within a radius of influence.
//
// Stored layout: one PatternOffset per texel, the offset (dx, dy) in texels from the texel to the
// nearest pattern texel, as two int16: 4 bytes per texel. The distance is sqrt(dx² + dy²) (texel centre
// to texel centre), computed on lookup. A texel farther than the radius from every pattern texel, or any
// texel of an empty mask, holds the sentinel kNoPattern. The radius is at most kMaxPatternRadius, so
// every stored offset fits in an int16 whatever the region's size.
//
// Algorithm: Felzenszwalb & Huttenlocher's separable exact EDT (lower envelope of parabolas) in
// integers, carrying the argmin: O(width x height), exact for all texels within the radius.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

#include "core/engine/field.hpp"
#include "core/engine/geometry.hpp"

namespace ph {

// Offset from a texel to its nearest pattern texel, in texels (y down).
struct PatternOffset {
  std::int16_t dx = 0;
  std::int16_t dy = 0;
};

inline constexpr std::int16_t kNoPatternComponent = std::numeric_limits<std::int16_t>::min();
inline constexpr PatternOffset kNoPattern{kNoPatternComponent, kNoPatternComponent};
inline constexpr float kMaxPatternRadius = 32767.0f;  // largest |dx|, |dy| an int16 offset holds

// A lookup's answer: the nearest pattern texel of the queried one.
struct NearestPattern {
  std::int32_t dx = 0;  // texels from the queried texel to the pattern texel
  std::int32_t dy = 0;

  std::int64_t distance_squared() const { return std::int64_t{dx} * dx + std::int64_t{dy} * dy; }
  double distance() const;  // texel centre to texel centre, screen px
  Texel target(Texel from) const { return {from.x + dx, from.y + dy}; }
};

// Nearest pattern texel of every texel of a w x h region, within `radius` texels.
struct PatternField {
  Grid<PatternOffset> offsets;  // kNoPattern: no pattern texel within the radius
  float radius = 0.0f;          // as applied: clamped to [0, kMaxPatternRadius]

  std::int32_t width() const { return offsets.width; }
  std::int32_t height() const { return offsets.height; }
  std::size_t bytes() const { return offsets.bytes(); }

  // Nearest pattern texel of texel t (region coordinates); nullopt outside the grid or beyond the radius.
  std::optional<NearestPattern> nearest(Texel t) const {
    if (t.x < 0 || t.y < 0 || t.x >= offsets.width || t.y >= offsets.height) return std::nullopt;
    const PatternOffset o = offsets.at(t.x, t.y);
    if (o.dx == kNoPatternComponent) return std::nullopt;
    return NearestPattern{o.dx, o.dy};
  }

  // From a point p (region coordinates, px) to the centre of the nearest pattern texel of the texel
  // containing p: the direction a well pulls toward and its length. nullopt as for nearest().
  std::optional<Vec2> toward(Vec2 p) const;
};

// Exact EDT of `mask` (any nonzero texel is part of the pattern), capped at `radius` texels: texels
// with distance <= radius get their offset, the others kNoPattern. A non-finite or negative radius is
// taken as 0 (only the pattern texels themselves), one above kMaxPatternRadius as kMaxPatternRadius.
// Ties between equally near pattern texels are broken deterministically but unspecified.
PatternField make_pattern_field(const Grid<std::uint8_t>& mask, float radius);

}  // namespace ph
