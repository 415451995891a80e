// Curvature of a height field per texel (docs/INTERROGATION.md, "Curvature"): Gaussian curvature K,
// mean curvature H and principal curvatures k1 >= k2, in 1/px, from a depth field or from a gradient field.
//
// Sign convention: height points toward the viewer and H follows the formula of section 7, so a bump (a cap,
// h_xx < 0) has H < 0 and a hole H > 0; K > 0 on both (elliptic), K < 0 on a saddle (hyperbolic).
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>

#include "core/engine/field.hpp"
#include "core/engine/row_bands.hpp"

namespace ph {

// Height derivatives at one point, in screen px (y down).
struct HeightDerivatives {
  double hx = 0.0, hy = 0.0;               // px per px
  double hxx = 0.0, hxy = 0.0, hyy = 0.0;  // 1/px
};

struct Curvatures {
  double gaussian = 0.0;  // K = k1 k2, 1/px^2
  double mean = 0.0;      // H = (k1 + k2) / 2, 1/px
  double k1 = 0.0;        // H + sqrt(max(H^2 - K, 0)) >= k2
  double k2 = 0.0;        // H - sqrt(max(H^2 - K, 0))
};

// K, H, k1, k2 of the graph z = h(x, y) (section 7). Always finite: computed in double, non-finite results are 0
// and the rest is clamped to the float range.
Curvatures curvatures_from_derivatives(const HeightDerivatives& d);

// The derivative filter: a least-squares fit over a (2r+1) x (2r+1) window centred on the texel (a 2D
// Savitzky-Golay filter): a quadric to heights, a plane to each gradient component. On a square window the fit
// separates into 1D kernels, so it costs O(r) per texel and per derivative. r = 1 is close to central differences
// (with a 3-texel average across); larger r averages out quantisation. A depth map needs a larger r than a normal
// map of the same bit depth (one more derivative amplifies its quantisation), and an 8-bit map a much larger one;
// recommended() gives the radii measured on the analytic surfaces at 512 px (docs/INTERROGATION.md). Near the
// border the window stays inside the image and the fit is evaluated off its centre (exact on a quadric, noisier
// than in the interior); a map narrower than 2r+1 texels uses the widest window that fits.
struct DerivativeFilter {
  std::int32_t radius = 3;  // r, texels; values below 1 count as 1

  // bits: 8 or 16 for integer maps (anything else, e.g. 32 for float maps, is taken as 16).
  static DerivativeFilter recommended(bool from_depth, int bits) {
    if (bits == 8) return {16};
    return {from_depth ? 8 : 3};
  }
};

// Which grids to fill: only those asked for are allocated.
struct CurvatureRequest {
  bool gaussian = true;
  bool mean = true;
  bool principal = false;  // k1 and k2
};

struct CurvatureFields {
  Grid<float> gaussian;  // K, 1/px^2 (empty unless asked)
  Grid<float> mean;      // H, 1/px
  Grid<float> k1, k2;    // 1/px

  std::size_t bytes() const { return gaussian.bytes() + mean.bytes() + k1.bytes() + k2.bytes(); }
};

// Fitted derivatives per texel (the filter above), for callers that need them directly.
Grid<HeightDerivatives> derivatives_from_depth(const DepthField& depth, const DerivativeFilter& filter);
// From a gradient field (p = h_x, q = h_y, e.g. decoded from a normal map): p and q are fitted with planes and
// h_xy = (p_y + q_x) / 2. Slopes beyond +-1e6 (a vertical wall) are clamped to +-1e6 first.
Grid<HeightDerivatives> derivatives_from_gradient(const GradientField& gradient, const DerivativeFilter& filter);

// The principal curvatures k1 and k2 of every texel of `rows`, one row at a time, rounded to float as the grids
// store them: for callers that reduce them at once (class maps) and need no grid. A row's values do not depend on
// which other rows are asked for, so bands of rows may be worked out apart (on threads of their own) and agree to
// the bit with the whole field's.
using PrincipalRowVisitor = std::function<void(std::int32_t y, const float* k1, const float* k2)>;
void principal_rows_from_depth(const DepthField& depth, const DerivativeFilter& filter, RowRange rows,
                               const PrincipalRowVisitor& visit);
void principal_rows_from_gradient(const GradientField& gradient, const DerivativeFilter& filter, RowRange rows,
                                  const PrincipalRowVisitor& visit);

CurvatureFields curvature_from_depth(const DepthField& depth, const DerivativeFilter& filter = {},
                                     const CurvatureRequest& request = {});
CurvatureFields curvature_from_gradient(const GradientField& gradient, const DerivativeFilter& filter = {},
                                        const CurvatureRequest& request = {});

}  // namespace ph
