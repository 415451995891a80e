// The exact per-texel traversal of docs/METHODS.md, "The traversal": the cursor walks the texel grid along the
// motion direction (Amanatides-Woo), each texel segment costs C/D x length of motor travel, and the
// cursor stops where the frame's motor travel runs out. The flat outside is crossed in one jump.
#pragma once

#include <cstdint>
#include <optional>

#include "core/engine/flat_frame.hpp"
#include "core/engine/frame.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/scene.hpp"

namespace ph {

// Motor displacements longer than this (px) are shortened to it: far beyond any screen.
inline constexpr double kMaxMotorPx = 1.0e7;

// advance() for a frame the flat tiles do not judge: the check of the motor, the region list, the effects, the walk.
FrameResult advance_near_regions(const Scene& scene, CursorState& cursor, Vec2 motor, TimeUs time,
                                 StepObserver* observer);

// Moves the cursor by one frame's motor displacement (device counts x base gain, px at C/D = 1) at the
// frame's event time (kNoTime when unknown). The effects of the region under the cursor first rescale
// the displacement (core/engine/effect.hpp); then the traversal walks it. A non-finite or zero displacement
// leaves the cursor where it is. The result is always finite; a frame whose every segment had C/D
// exactly 1 and met no effect returns `motor` itself, bit for bit.
// Inline: a frame far from every region (the scene's FlatTiles) costs no call.
PH_ALWAYS_INLINE inline FrameResult advance(const Scene& scene, CursorState& cursor, Vec2 motor, TimeUs time,
                                            StepObserver* observer = nullptr) {
  constexpr Double2 kZero = {0.0, 0.0};
  const Double2 m = {motor.x, motor.y};
  if (scene.flat_tiles().surely_flat(load2(cursor.position), m)) [[likely]] {
    if (all_true(m == kZero)) return {};
    return flat_frame_pair(cursor, m);
  }
  return advance_near_regions(scene, cursor, motor, time, observer);
}

// The same with no time (traces, benchmarks): effects see kNoTime.
inline FrameResult advance(const Scene& scene, CursorState& cursor, Vec2 motor, StepObserver* observer = nullptr) {
  return advance(scene, cursor, motor, kNoTime, observer);
}

}  // namespace ph
