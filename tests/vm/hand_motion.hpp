// Hand-like mouse motion for the checks against a real X server: aimed strokes with a minimum-jerk
// speed profile (bell-shaped, as arm movements are), slightly curved, of varying length and duration,
// with short pauses between them; one frame of device counts every 8 ms (a 125 Hz mouse).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph::e2e {

inline constexpr int kFramePeriodUs = 8000;  // 125 Hz

// One frame's counts; {0, 0} is a frame in a pause (nothing is sent then, but time passes).
struct Counts {
  std::int32_t dx = 0, dy = 0;
  bool any() const { return dx != 0 || dy != 0; }
};

// Minimum-jerk position along a stroke at phase t in [0, 1]: 10t^3 - 15t^4 + 6t^5.
inline double minimum_jerk(double t) { return t * t * t * (10.0 + t * (-15.0 + 6.0 * t)); }

// The counts of a stroke of `frames` frames that moves the hand by `displacement` counts, bending
// sideways by `bend` times its length at the middle. The counts add up to the rounded displacement.
inline std::vector<Counts> stroke_counts(Vec2 displacement, int frames, double bend) {
  std::vector<Counts> counts;
  const double len = length(displacement);
  const Vec2 side = len > 0 ? Vec2{-displacement.y / len, displacement.x / len} : Vec2{};
  double sent_x = 0, sent_y = 0;
  for (int i = 1; i <= frames; ++i) {
    const double t = static_cast<double>(i) / frames;
    const Vec2 at = displacement * minimum_jerk(t) + side * (bend * len * std::sin(M_PI * t));
    const double x = std::round(at.x), y = std::round(at.y);
    counts.push_back({static_cast<std::int32_t>(x - sent_x), static_cast<std::int32_t>(y - sent_y)});
    sent_x = x;
    sent_y = y;
  }
  return counts;
}

// Endless hand-like motion: each stroke aims from where the cursor is now at a random point of `area`
// (at least 60 px away), taking Fitts-like time for its length times a random factor (slow and quick
// strokes), then pauses 0 to 12 frames. Deterministic for a seed.
class HandMotion {
 public:
  HandMotion(Rect area, std::uint32_t seed) : area_(area), random_(seed) {}

  // The next frame's counts; `cursor` is where the cursor is now (aims the next stroke at its start).
  Counts next(Vec2 cursor) {
    if (pending_.empty()) plan(cursor);
    const Counts c = pending_.back();
    pending_.pop_back();
    return c;
  }

 private:
  void plan(Vec2 cursor) {
    std::uniform_real_distribution<double> ux(area_.x, area_.x + area_.w), uy(area_.y, area_.y + area_.h);
    Vec2 target;
    do {
      target = {ux(random_), uy(random_)};
    } while (length(target - cursor) < 60.0);
    const double distance = length(target - cursor);
    const double seconds =
        (0.15 + 0.12 * std::log2(distance / 20.0 + 1.0)) * std::uniform_real_distribution<double>(0.6, 1.8)(random_);
    const int frames = std::max(4, static_cast<int>(std::lround(seconds * 1e6 / kFramePeriodUs)));
    const double bend = std::uniform_real_distribution<double>(-0.12, 0.12)(random_);
    const int pause = std::uniform_int_distribution<int>(0, 12)(random_);
    std::vector<Counts> stroke = stroke_counts(target - cursor, frames, bend);
    pending_.assign(static_cast<std::size_t>(pause), Counts{});
    pending_.insert(pending_.end(), stroke.rbegin(), stroke.rend());  // popped from the back
  }

  Rect area_;
  std::mt19937 random_;
  std::vector<Counts> pending_;  // the rest of the stroke and its pause, last frame first
};

// Out-and-back strokes in random directions, `strokes` of them: each is followed, after a pause, by its
// mirror image, so that the hand comes back to where it started. The cursor comes back too whatever an
// acceleration profile made of the strokes, so a long stream stays clear of the desktop's edges.
// Independent of the cursor: the same frames for every run. Deterministic for a seed.
inline std::vector<Counts> out_and_back(int strokes, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::vector<Counts> frames;
  for (int i = 0; i < strokes; ++i) {
    const double angle = std::uniform_real_distribution<double>(0.0, 2.0 * M_PI)(random);
    const double distance = std::uniform_real_distribution<double>(80.0, 450.0)(random);
    const double seconds =
        (0.15 + 0.12 * std::log2(distance / 20.0 + 1.0)) * std::uniform_real_distribution<double>(0.6, 1.8)(random);
    const int count = std::max(4, static_cast<int>(std::lround(seconds * 1e6 / kFramePeriodUs)));
    const double bend = std::uniform_real_distribution<double>(-0.12, 0.12)(random);
    const std::vector<Counts> out =
        stroke_counts({distance * std::cos(angle), distance * std::sin(angle)}, count, bend);
    for (int back = 0; back < 2; ++back) {
      for (const Counts& c : out) frames.push_back(back == 0 ? c : Counts{-c.dx, -c.dy});
      frames.insert(frames.end(), static_cast<std::size_t>(std::uniform_int_distribution<int>(2, 12)(random)),
                    Counts{});
    }
  }
  return frames;
}

}  // namespace ph::e2e
