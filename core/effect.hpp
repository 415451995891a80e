// Frame effects: what acts on a whole frame's motor displacement before the per-texel traversal walks it.
// The surface-interrogation renderings of the second paper are effects (docs/INTERROGATION.md):
// materials, whose stick and slip depend on the hand's history, and gravity wells, which depend on where
// the nearest pattern lies. They act once per frame, at the texel under the cursor when the frame
// starts; the geometric C/D methods (curvature, depth) act per texel. A region may have both: its
// effects scale the motor travel, then its method walks it (docs/INTERROGATION.md, "In a scene file").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "core/geometry.hpp"

namespace ph {

// Frames whose time is not known (a trace without timing): effects that need time treat the hand as
// moving steadily and never resting.
inline constexpr TimeUs kNoTime = INT64_MIN;

// What an effect remembers between frames. It lives in the cursor (CursorState::effects), never in the
// effect, so a scene can be shared and a replay is deterministic: only event times drive it.
struct EffectState {
  bool stuck = true;             // materials: the cursor sticks (static friction) until it breaks away
  double travel_px = 0.0;        // materials: motor travel since `stuck` last changed
  TimeUs last_motion = kNoTime;  // time of the last frame that moved the hand
  const void* owner = nullptr;   // the effect the state belongs to; another one starts afresh
};

// The most effects one region may have (Scene checks it): each gets its own state in the cursor, so
// effects layered on one region (materials and wells) never reset each other. Fixed, so the hot path
// allocates nothing.
inline constexpr std::size_t kMaxEffectsPerRegion = 4;

// One state per effect of the region under the cursor, by the effect's place in Region::effects.
using EffectStates = std::array<EffectState, kMaxEffectsPerRegion>;

struct EffectInput {
  Vec2 motor;     // this frame's motor displacement (px at C/D 1): finite and not zero
  TimeUs time;    // the frame's time (us), or kNoTime
  Vec2 position;  // the cursor at the start of the frame (screen px)
  Texel local;    // its texel in the region's fields
};

class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string_view name() const = 0;

  // The motor displacement to walk instead of `in.motor`: finite, and its length within
  // [|motor| * min_gain(), |motor| * max_gain()], so that a sustained push always gets somewhere.
  virtual Vec2 apply(const EffectInput& in, EffectState& state) const = 0;

  virtual double min_gain() const = 0;
  virtual double max_gain() const = 0;
  // Memory the effect's precomputed fields take.
  virtual std::size_t bytes() const = 0;
};

using EffectPtr = std::shared_ptr<const Effect>;

}  // namespace ph
