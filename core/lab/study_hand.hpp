// The simulated participant's hand (docs/STUDY.md, "The hand"): horizontal strokes back and forth across the
// study's area, as the curvature paper's participants were told to move, each stroke a minimum-jerk movement
// (Flash and Hogan 1985) from where the cursor is to a reversal point near the far side, with its speed, its
// reversal point and its row drawn afresh. The hand plans from the cursor it sees and does not correct during
// a stroke, so a cursor the texture slowed or sped up starts the next stroke from where it got to.
#pragma once

#include <cstdint>

#include "core/engine/geometry.hpp"
#include "core/lab/study_random.hpp"

namespace ph {

// How the population moves; fixed choices, never fitted (docs/STUDY.md lists them with their reasons).
struct HandParams {
  double speed_median_px_s = 350.0;      // a participant's typical mean stroke speed (motor px/s)
  double speed_participant_sigma = 0.3;  // spread of that over participants (sd of its log)
  double speed_stroke_sigma = 0.15;      // spread of one stroke's mean speed around the participant's (sd of log)
  double row_sd_px = 60.0;               // spread of a stroke's row around the area's middle
  double reversal_min_px = -30.0;        // reversal point past the far side (< 0: short of it) ...
  double reversal_max_px = 20.0;         // ... uniform between these
  double dwell_min_s = 0.05;             // rest at a reversal, uniform between these
  double dwell_max_s = 0.2;
};

// One participant's way of moving, drawn once.
struct HandTraits {
  double speed_px_s = 350.0;
};
HandTraits draw_hand_traits(const HandParams& params, StudyRng& rng);

class Hand {
 public:
  // The first stroke starts at time 0 from `cursor`, to the right side of `area` when `rightward`, else the left.
  Hand(const HandParams& params, const HandTraits& traits, Rect area, Vec2 cursor, bool rightward, StudyRng& rng);

  // Where the hand is at time `t_s` (motor px from where it started; times must not decrease). When the
  // stroke under way and its rest have ended, the next stroke is planned from `cursor`, the cursor the
  // participant sees now.
  Vec2 position(double t_s, Vec2 cursor);

  int strokes() const { return strokes_; }

 private:
  void plan(double t_s, Vec2 cursor);

  HandParams params_;
  HandTraits traits_;
  Rect area_;
  StudyRng& rng_;
  bool rightward_;
  Vec2 from_;  // hand position where the current stroke starts
  Vec2 delta_;
  double start_s_ = 0.0, duration_s_ = 1.0, rest_until_s_ = 1.0;
  int strokes_ = 0;
};

// Minimum-jerk position along a stroke, 0 at tau <= 0 and 1 at tau >= 1: 10 tau^3 - 15 tau^4 + 6 tau^5.
double minimum_jerk(double tau);

}  // namespace ph
