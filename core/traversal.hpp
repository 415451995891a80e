// The exact per-texel traversal of docs/METHODS.md, "The traversal": the cursor walks the texel grid along the
// motion direction (Amanatides-Woo), each texel segment costs C/D x length of motor travel, and the
// cursor stops where the frame's motor travel runs out. The flat outside is crossed in one jump.
#pragma once

#include <cstdint>
#include <optional>

#include "core/effect.hpp"
#include "core/geometry.hpp"
#include "core/method.hpp"
#include "core/scene.hpp"

namespace ph {

// The cursor model kept between frames. The texel is kept explicitly because a position on a texel
// boundary belongs to the texel the cursor was walking in; came_from makes consecutive frames seamless.
struct CursorState {
  Vec2 position;
  Texel texel;
  Texel came_from;       // == texel when there is no history (start, or after a flat stretch)
  EffectStates effects;  // what the frame effects of the region under the cursor remember, one each
};

// A cursor with no history at a position (clamped to the world; a non-finite coordinate becomes 0).
CursorState cursor_at(Vec2 position);

// One texel segment of a frame, for traces and tests.
struct StepRecord {
  Vec2 entry;            // cursor position where the segment starts (screen px)
  Texel texel;           // screen texel of the segment
  Texel came_from;       // screen texel it was entered from
  bool entered = false;  // false for the texel the frame started in
  double cd = 1.0;
  StepDetail detail{};  // method quantities of the step (NaN where a method has none)
  const Region* region = nullptr;
};

class StepObserver {
 public:
  virtual ~StepObserver() = default;
  virtual void on_step(const StepRecord& step) = 0;
};

struct FrameResult {
  Vec2 display;         // cursor displacement on screen
  double cd_min = 1.0;  // range of C/D met in the frame (1 on the flat outside)
  double cd_max = 1.0;
  std::uint32_t steps = 0;  // texel boundaries crossed inside regions
};

// Motor displacements longer than this (px) are shortened to it: far beyond any screen.
inline constexpr double kMaxMotorPx = 1.0e7;
// The cursor model never leaves [-kWorldLimitPx, kWorldLimitPx]^2, so texel indices always fit.
inline constexpr double kWorldLimitPx = 1.0e9;

// Moves the cursor by one frame's motor displacement (device counts x base gain, px at C/D = 1) at the
// frame's event time (kNoTime when unknown). The effects of the region under the cursor first rescale
// the displacement (core/effect.hpp); then the traversal walks it. A non-finite or zero displacement
// leaves the cursor where it is. The result is always finite; a frame whose every segment had C/D
// exactly 1 and met no effect returns `motor` itself, bit for bit.
FrameResult advance(const Scene& scene, CursorState& cursor, Vec2 motor, TimeUs time, StepObserver* observer = nullptr);

// The same with no time (traces, benchmarks): effects see kNoTime.
inline FrameResult advance(const Scene& scene, CursorState& cursor, Vec2 motor, StepObserver* observer = nullptr) {
  return advance(scene, cursor, motor, kNoTime, observer);
}

}  // namespace ph
