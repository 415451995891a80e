#include "core/lab/study_hand.hpp"

#include <algorithm>
#include <cmath>

namespace ph {

double minimum_jerk(double tau) {
  if (tau <= 0.0) return 0.0;
  if (tau >= 1.0) return 1.0;
  const double t3 = tau * tau * tau;
  return t3 * (10.0 + tau * (-15.0 + 6.0 * tau));
}

HandTraits draw_hand_traits(const HandParams& params, StudyRng& rng) {
  return {rng.log_normal(params.speed_median_px_s, params.speed_participant_sigma)};
}

Hand::Hand(const HandParams& params, const HandTraits& traits, Rect area, Vec2 cursor, bool rightward, StudyRng& rng)
    : params_(params), traits_(traits), area_(area), rng_(rng), rightward_(rightward) {
  plan(0.0, cursor);
}

void Hand::plan(double t_s, Vec2 cursor) {
  const double reversal = rng_.uniform(params_.reversal_min_px, params_.reversal_max_px);
  const double x = rightward_ ? area_.x + area_.w + reversal : area_.x - reversal;
  const double half_h = area_.h / 2.0;
  const double row = std::clamp(rng_.normal(0.0, params_.row_sd_px), -half_h + 1.0, half_h - 1.0);
  const double y = area_.y + half_h + row;
  const double speed = rng_.log_normal(traits_.speed_px_s, params_.speed_stroke_sigma);
  const double dwell = rng_.uniform(params_.dwell_min_s, params_.dwell_max_s);
  from_ = strokes_ == 0 ? Vec2{} : from_ + delta_;
  delta_ = Vec2{x, y} - cursor;  // at C/D 1 the cursor would get exactly there
  start_s_ = t_s;
  duration_s_ = std::max(0.05, length(delta_) / speed);
  rest_until_s_ = start_s_ + duration_s_ + dwell;
  rightward_ = !rightward_;
  ++strokes_;
}

Vec2 Hand::position(double t_s, Vec2 cursor) {
  if (t_s >= rest_until_s_) plan(t_s, cursor);
  return from_ + delta_ * minimum_jerk((t_s - start_s_) / duration_s_);
}

}  // namespace ph
