// A straight stroke of the hand: constant motor steps along one direction, frame after frame, until the
// cursor has travelled the stroke's length on screen; the last frame is only as long as it takes to get
// there, so the stroke ends at `to` (within 1e-9 of its length) however large the step. What the paper's
// Fig. 5 plots; what traces and the demo run.
#pragma once

#include <cstddef>
#include <functional>

#include "core/engine/scene.hpp"
#include "core/engine/traversal.hpp"

namespace ph {

struct StrokeSpec {
  Vec2 from;
  Vec2 to;
  double motor_step_px = 1.0;           // motor travel per frame (px at C/D = 1)
  std::size_t max_frames = 10'000'000;  // a stroke that cannot finish stops here
  // Frames per second, which times each frame (frame k at k / rate s) for the effects that read time (a material's
  // damping reads the hand's speed); 0: frames without a time, and such effects take their fallback interval.
  double rate_hz = 0.0;
};

struct StrokeResult {
  std::size_t frames = 0;
  CursorState end;
  double cd_min = 1.0;
  double cd_max = 1.0;
  bool reached = false;   // the cursor got to `to` (projected on the stroke) within max_frames and stopped there
  double motor_px = 0.0;  // the hand's motor travel: whole frames, then the last frame's share
};

using StrokeStepFn = std::function<void(std::size_t frame, const StepRecord& step)>;

// on_step sees every texel segment of every frame, in order, the last frame's only up to `to`.
// Throws std::invalid_argument for a zero-length stroke or a non-positive step.
StrokeResult run_stroke(const Scene& scene, const StrokeSpec& spec, const StrokeStepFn& on_step = {});

}  // namespace ph
