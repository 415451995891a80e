// Curvature classes of a surface (docs/INTERROGATION.md, "Classes"; the second paper, Section 2.3): planar, parabolic,
// elliptic, hyperbolic, from the principal curvatures of each texel.
#pragma once

#include <cstdint>

#include "core/effects/curvature_field.hpp"
#include "core/engine/field.hpp"

namespace ph {

enum class CurvatureClass : std::uint8_t { planar = 0, parabolic = 1, elliptic = 2, hyperbolic = 3 };

const char* class_name(CurvatureClass c);  // "planar", "parabolic", "elliptic", "hyperbolic"

// planar: curvedness sqrt((k1^2 + k2^2) / 2) < planar_curvedness (1/px);
// else parabolic: |k_small| / |k_large| < parabolic_ratio;
// else elliptic (K > 0) or hyperbolic (K < 0).
// Curvedness is in 1/px, so it depends on the region's size on screen: 1e-4 is a radius of curvature of 10000 px,
// a bend that changes the slope by 0.01 over a 100 px stroke. 8-bit maps need larger tolerances because their
// curvature is noisier (docs/INTERROGATION.md has the measurements behind these defaults).
struct ClassTolerances {
  double planar_curvedness = 5e-5;
  double parabolic_ratio = 0.1;

  // bits: 8 or 16 for integer maps (anything else, e.g. 32 for float maps, is taken as 16).
  static ClassTolerances recommended(int bits) { return bits == 8 ? ClassTolerances{1e-4, 0.25} : ClassTolerances{}; }
};

CurvatureClass classify(double k1, double k2, const ClassTolerances& tolerances);
inline CurvatureClass classify(const Curvatures& c, const ClassTolerances& tolerances) {
  return classify(c.k1, c.k2, tolerances);
}

// One CurvatureClass value per texel. Uses k1 and k2 when present, else derives them from K and H (both must be
// present then); returns an empty grid when neither is.
Grid<std::uint8_t> class_map(const CurvatureFields& fields, const ClassTolerances& tolerances);

// The same map straight from a field, without the curvature grids: equal to class_map(curvature_from_...(
// field, filter, {false, false, true}), tolerances), in less time and memory. Bands of rows are worked out on
// `threads` threads at once (0: one per core, at most kMaxRowBandThreads; never bands of fewer than
// kMinRowBandRows rows), each texel's class the same whatever the number.
Grid<std::uint8_t> class_map_from_depth(const DepthField& depth, const DerivativeFilter& filter,
                                        const ClassTolerances& tolerances, unsigned threads = 0);
Grid<std::uint8_t> class_map_from_gradient(const GradientField& gradient, const DerivativeFilter& filter,
                                           const ClassTolerances& tolerances, unsigned threads = 0);

}  // namespace ph
