// The C/D the engine applied along a straight line, segment by segment, from the steps it reports
// (core/engine/traversal.hpp, StepObserver): what the accuracy and stability commands compare with the ground truth.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "core/engine/geometry.hpp"
#include "core/engine/traversal.hpp"

namespace ph {

// Display stretch [s0, s1] of the line origin + s m at one C/D.
struct CdSegment {
  double s0 = 0.0;
  double s1 = 0.0;
  double cd = 1.0;
};

// The stretches a run of steps along the line from `origin` in the unit direction m applied their C/D to: each
// step's from its entry (the origin for the first) to the next step's entry, the last to s = end_s, each clipped to
// its step's region; steps on the flat outside and empty stretches are left out (the flat outside is C/D 1).
// Sorted by s when the steps are in order. Exact for the texel walks and unit steps, whose entries are where their
// C/D starts (a frame_midpoint step's entry is the frame's middle: that traversal needs frame-by-frame use).
std::vector<CdSegment> cd_segments(const std::vector<StepRecord>& steps, Vec2 origin, Vec2 m, double end_s);

// The C/D at s of sorted, disjoint segments (1 where none lies).
double cd_at(const std::vector<CdSegment>& segments, double s);

// Length-weighted RMS and maximum of a relative C/D error.
struct CdError {
  double sum_w = 0.0, sum_we2 = 0.0, max = 0.0;
  void add(double rel, double w) {
    sum_w += w;
    sum_we2 += w * rel * rel;
    if (w > 1e-6) max = std::max(max, std::abs(rel));
  }
  double rms() const { return sum_w > 0.0 ? std::sqrt(sum_we2 / sum_w) : 0.0; }
};

}  // namespace ph
