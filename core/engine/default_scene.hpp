// The scene used when no scene file is given: three targets of the curvature paper, built in memory
// from their exact analytic normals (no files), side by side in the middle of the desktop (of its largest output,
// default_scene_area). On the 1920 x 1080
// desktop they were first laid out for:
//   bump-gaussian-h1-r200 at (135, 290), hole-polynomial-h1-r200 at (710, 290),
//   bump-linear-h1-r100 at (1285, 290); each 500 x 500 px, curvature method with default parameters.
// On a desktop too narrow for three, as many as fit (default_scene_layout). About 6 MB of fields (8 bytes per
// texel) for three.
#pragma once

#include <string>
#include <vector>

#include "core/engine/geometry.hpp"
#include "core/engine/method.hpp"
#include "core/engine/scene.hpp"

namespace ph {

// The desktop whose middle the three targets were laid out for: what the scene is without another.
inline constexpr Rect kDefaultSceneDesktop{0, 0, 1920, 1080};

// Where the default scene's targets lie on `desktop`: side by side in its middle, 75 px apart (less where that
// is all that lets three fit), the first of the three that fit its width (at least one, cut where the desktop is
// smaller than a target). Each rectangle's size is its target's.
std::vector<Rect> default_scene_layout(const Rect& desktop);

Scene default_scene(const Rect& desktop = kDefaultSceneDesktop);

// Where on a desktop of `outputs` (core/engine/desktop_outputs.hpp; none: the desktop whole) the default scene is laid
// out: the largest output (the first of those as large), so that no target lies across two monitors or where none
// shows it.
Rect default_scene_area(const Rect& desktop, const std::vector<Rect>& outputs);

// Whether `scene`'s regions lie where default_scene_layout puts the targets on `desktop` (so that a default scene
// need not be built again for it).
bool default_scene_laid_out_for(const Scene& scene, const Rect& desktop);

// "NAME at X,Y, NAME at X,Y (WxH px each)": where a default scene's targets lie, for a log line.
std::string default_scene_places(const Scene& scene);

// The same targets with `method` in every region instead, and the exact fields it needs (heights where it
// reads them): for replaying one recording under each method.
Scene default_scene(const MethodPtr& method, const Rect& desktop = kDefaultSceneDesktop);

}  // namespace ph
