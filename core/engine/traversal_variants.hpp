// The traversal variants that do not walk the texel grid (core/engine/engine_options.hpp): unit steps along the
// motion and one C/D per frame. Internal to core/engine/traversal.cpp, which applies the effects first and
// finishes the frame (bit-exact identity when every C/D was 1, world limits) for every variant.
#pragma once

#include "core/engine/engine_options.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/traversal.hpp"

namespace ph {

// Both take the unit direction m and the motor length d (finite, > 0, at most kMaxMotorPx), fill the
// result's C/D range and steps, set all_unit to whether every C/D met was exactly 1, and return the
// cursor's end state (effect state left to the caller).

// Traversal::unit_steps: steps of 1 px of display along m; a step's C/D comes from the texel (or, bilinear:
// the point) at its start against the previous step's (the first step of a frame: the cursor's came_from
// texel, or the point 1 px behind). The last step is partial. The flat outside is crossed in one jump.
CursorState walk_unit_steps(const Scene& scene, const CursorState& cursor, Vec2 m, double d, Sampling sampling,
                            StepObserver* observer, FrameResult& result, bool& all_unit);

// Traversal::frame_midpoint: one C/D for the whole frame, from the texel (point) at the frame's midpoint
// assuming C/D 1 against the texel (point) 1 px behind it along m; display = motor / C/D.
CursorState walk_frame_midpoint(const Scene& scene, const CursorState& cursor, Vec2 m, double d, Sampling sampling,
                                StepObserver* observer, FrameResult& result, bool& all_unit);

}  // namespace ph
