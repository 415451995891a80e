// traversal = "auto" (docs/METHODS.md, "Choosing the variant per region"): the cheapest traversal variant
// whose error on the region stays within a budget, estimated at load from the region's own fields. Model no
// more than a scene needs: a region whose C/D barely changes within a frame's length does not need the exact
// walk. Pure: reads the region's method and fields only.
#pragma once

#include <string>

#include "core/engine/engine_options.hpp"
#include "core/engine/scene.hpp"

namespace ph {

struct VariantBudget {
  double accuracy_px = 0.25;  // the display error a frame may add, px
  double frame_px = 10.0;     // the frame length it is judged on: the top of a 125 Hz hand's typical frames
};

struct VariantChoice {
  EngineOptions options;
  double midpoint_error_px = 0.0;  // the estimated error of frame_midpoint over one frame of frame_px
  std::string reason;              // one line: what was chosen and why
};

// The candidates, cheapest first (docs/PERFORMANCE.md, "Traversal variants"): frame_midpoint (one C/D per
// frame), then the exact walk. The direction tables cost more per typical frame than the exact walk and
// memory besides, so they are never chosen. frame_midpoint's error over a frame of length L is at most
// L * max |1/CD(p) - 1/CD(q)| over points q within L/2 of p along the motion (the midpoint's C/D stands for
// the whole frame); that spread is sampled on a grid of at most ~20 000 texels, in 8 directions, at 1, L/4
// and L/2 px, and at every edge texel against the flat outside (C/D 1), which a frame crossing the border meets.
VariantChoice choose_variant(const Region& region, const VariantBudget& budget = {});

}  // namespace ph
