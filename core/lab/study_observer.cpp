#include "core/lab/study_observer.hpp"

#include <algorithm>
#include <cmath>

namespace ph {

Observer::Observer(const ObserverParams& params, double weber, Rect area, StudyRng& noise)
    : params_(params), weber_(weber), area_(area), noise_(noise) {}

bool Observer::observe(const PerceptWindow& w) {
  if (decided_ || !(w.seconds > 0.0)) return decided_;
  // Both noises are drawn for every window, so that the stream of numbers does not depend on the texture.
  const double z_hand = noise_.normal();
  const double z_cursor = noise_.normal();
  const double hand_speed = length(w.hand) / w.seconds;
  const double cursor_speed = length(w.cursor) / w.seconds;
  const double seen_hand = hand_speed + weber_ * std::max(hand_speed, params_.knee_px_s) * z_hand;
  const double seen_cursor = cursor_speed + weber_ * std::max(cursor_speed, params_.knee_px_s) * z_cursor;
  if (seen_hand < params_.min_hand_px_s) return false;
  const double centre = area_.x + area_.w / 2.0;
  const bool inside = w.cursor_mid.x >= area_.x && w.cursor_mid.x < area_.x + area_.w && w.cursor_mid.y >= area_.y &&
                      w.cursor_mid.y < area_.y + area_.h;
  if (!inside || w.hand.x == 0.0) return false;
  // +1 in the first half of the area along the motion, -1 in the second.
  const double ahead = (w.cursor_mid.x - centre) * (w.hand.x > 0.0 ? 1.0 : -1.0);
  const double half = ahead < 0.0 ? 1.0 : (ahead > 0.0 ? -1.0 : 0.0);
  // The speed lost, as a fraction of the hand's (< 0: a speed-up). Below the knee the fraction is of the knee's
  // speed, as the noise is: a hand just starting or stopping does not make every wobble a large slowdown.
  const double slowdown = std::clamp((seen_hand - seen_cursor) / std::max(seen_hand, params_.knee_px_s), -1.0, 1.0);
  // A change smaller than one Weber fraction goes unnoticed (the Weber fraction is the just-noticeable
  // difference): without that, the noise's own wobbles would pile up as slowdowns in whichever half comes
  // first in a stroke, a bias toward "bump".
  if (std::abs(slowdown) <= weber_) return false;
  evidence_ += half * (slowdown > 0.0 ? slowdown : params_.speedup_weight * slowdown);
  decided_ = std::abs(evidence_) >= params_.bound;
  return decided_;
}

TargetShape Observer::answer(StudyRng& coin) const {
  if (evidence_ > 0.0) return TargetShape::bump;
  if (evidence_ < 0.0) return TargetShape::hole;
  return coin.uniform() < 0.5 ? TargetShape::bump : TargetShape::hole;
}

}  // namespace ph
