#include "core/stroke.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ph {

namespace {

class ForwardSteps final : public StepObserver {
 public:
  explicit ForwardSteps(const StrokeStepFn& fn) : fn_(fn) {}
  void on_step(const StepRecord& step) override { fn_(frame, step); }
  std::size_t frame = 0;

 private:
  const StrokeStepFn& fn_;
};

}  // namespace

StrokeResult run_stroke(const Scene& scene, const StrokeSpec& spec, const StrokeStepFn& on_step) {
  const Vec2 span = spec.to - spec.from;
  const double length_px = length(span);
  if (!(length_px > 0.0) || !std::isfinite(length_px)) throw std::invalid_argument("the stroke has no length");
  if (!(spec.motor_step_px > 0.0) || !std::isfinite(spec.motor_step_px)) {
    throw std::invalid_argument("the motor step must be a finite number > 0");
  }
  const Vec2 m = span * (1.0 / length_px);
  const Vec2 step = m * spec.motor_step_px;

  ForwardSteps forward(on_step);
  StepObserver* observer = on_step ? &forward : nullptr;
  StrokeResult result;
  result.end = cursor_at(spec.from);
  result.cd_min = INFINITY;
  result.cd_max = -INFINITY;
  while (result.frames < spec.max_frames) {
    forward.frame = result.frames;
    const FrameResult frame = advance(scene, result.end, step, observer);
    ++result.frames;
    result.cd_min = std::min(result.cd_min, frame.cd_min);
    result.cd_max = std::max(result.cd_max, frame.cd_max);
    const Vec2 done = result.end.position - spec.from;
    if (done.x * m.x + done.y * m.y >= length_px) {
      result.reached = true;
      break;
    }
  }
  if (result.frames == 0) result.cd_min = result.cd_max = 1.0;
  return result;
}

}  // namespace ph
