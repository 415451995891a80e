// The scene used when no scene file is given: three targets of the curvature paper, built in memory
// from their exact analytic normals (no files), side by side in the middle of a 1920 x 1080 desktop:
//   bump-gaussian-h1-r200 at (135, 290), hole-polynomial-h1-r200 at (710, 290),
//   bump-linear-h1-r100 at (1285, 290); each 500 x 500 px, curvature method with default parameters.
// About 6 MB of fields (8 bytes per texel).
#pragma once

#include "core/engine/method.hpp"
#include "core/engine/scene.hpp"

namespace ph {

Scene default_scene();

// The same three targets with `method` in every region instead, and the exact fields it needs (heights where it
// reads them): for replaying one recording under each method.
Scene default_scene(const MethodPtr& method);

}  // namespace ph
