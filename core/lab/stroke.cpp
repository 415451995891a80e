#include "core/lab/stroke.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace ph {

namespace {

// Keeps a frame's steps until the stroke knows whether the frame is its last one, and how long.
class FrameSteps final : public StepObserver {
 public:
  void on_step(const StepRecord& step) override { steps.push_back(step); }
  std::vector<StepRecord> steps;
};

// Bisection steps to find the last frame's motor travel: enough to get from a whole step down to the
// rounding of the position, whatever the step.
constexpr int kMaxBisections = 200;

}  // namespace

StrokeResult run_stroke(const Scene& scene, const StrokeSpec& spec, const StrokeStepFn& on_step) {
  const Vec2 span = spec.to - spec.from;
  const double length_px = length(span);
  if (!(length_px > 0.0) || !std::isfinite(length_px)) throw std::invalid_argument("the stroke has no length");
  if (!(spec.motor_step_px > 0.0) || !std::isfinite(spec.motor_step_px)) {
    throw std::invalid_argument("the motor step must be a finite number > 0");
  }
  if (!(spec.rate_hz >= 0.0) || !std::isfinite(spec.rate_hz)) {
    throw std::invalid_argument("the frame rate must be a finite number >= 0");
  }
  // (Held within 1e18 us, 31 700 years, at any rate: a TimeUs holds it.)
  const auto time_of = [&spec](std::size_t frame) {
    return spec.rate_hz > 0.0
               ? static_cast<TimeUs>(std::llround(std::min(static_cast<double>(frame) * 1e6 / spec.rate_hz, 1e18)))
               : kNoTime;
  };
  const Vec2 m = span * (1.0 / length_px);
  // The end is reached within a nanometre's worth of rounding, so that a stroke ending on a texel boundary
  // stops in the texel it walked, not a hair into the next one.
  const double goal = length_px - 1e-9 * std::max(1.0, length_px);
  auto reached = [&](const CursorState& c) {
    const Vec2 done = c.position - spec.from;
    return done.x * m.x + done.y * m.y >= goal;
  };

  FrameSteps steps;
  StepObserver* observer = on_step ? &steps : nullptr;
  StrokeResult result;
  result.end = cursor_at(spec.from);
  result.cd_min = INFINITY;
  result.cd_max = -INFINITY;
  while (result.frames < spec.max_frames) {
    const CursorState before = result.end;
    steps.steps.clear();
    const TimeUs time = time_of(result.frames);
    FrameResult frame = advance(scene, result.end, m * spec.motor_step_px, time, observer);
    if (reached(result.end)) {
      // The hand stops at `to`: the last frame's motor travel is the least that gets there (bisection; the
      // cursor's travel grows with the motor travel), walked again from where the frame started. No more than the
      // kMaxMotorPx a frame walks: from a step of 1e66 the halvings never came down to the stroke's length.
      double lo = 0.0, hi = std::min(spec.motor_step_px, kMaxMotorPx);
      for (int i = 0; i < kMaxBisections; ++i) {
        const double mid = lo + (hi - lo) / 2.0;
        if (!(mid > lo && mid < hi)) break;
        CursorState trial = before;
        advance(scene, trial, m * mid, time);
        (reached(trial) ? hi : lo) = mid;
      }
      result.end = before;
      steps.steps.clear();
      frame = advance(scene, result.end, m * hi, time, observer);
      result.reached = true;
      result.motor_px += hi;
    } else {
      result.motor_px += spec.motor_step_px;
    }
    for (const StepRecord& s : steps.steps) on_step(result.frames, s);
    ++result.frames;
    result.cd_min = std::min(result.cd_min, frame.cd_min);
    result.cd_max = std::max(result.cd_max, frame.cd_max);
    if (result.reached) break;
  }
  if (result.frames == 0) result.cd_min = result.cd_max = 1.0;
  return result;
}

}  // namespace ph
