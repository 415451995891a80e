// What the traversal keeps between frames and what a frame gives back (core/engine/traversal.hpp).
#pragma once

#include <cstdint>

#include "core/engine/effect.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/method.hpp"

namespace ph {

struct Region;

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

}  // namespace ph
