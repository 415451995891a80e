// A stroke made as one frame and again as frames of random length, for the tests that a texel walk does not depend
// on how the hand's motion was cut into frames.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/engine/traversal.hpp"

namespace ph {

struct SplitStroke {
  CursorState whole;   // after one frame of 300 px
  CursorState pieces;  // after the same 300 px in frames of 0-5 px each
};

// From a random start within 500 x 500 px, in a random direction; draws from `rng`.
inline SplitStroke split_stroke(const Scene& scene, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec2 start{500.0 * u(rng), 500.0 * u(rng)};
  const double phi = 2.0 * std::numbers::pi * u(rng);
  const Vec2 m{std::cos(phi), std::sin(phi)};
  SplitStroke s{cursor_at(start), cursor_at(start)};
  advance(scene, s.whole, m * 300.0);
  double left = 300.0;
  while (left > 0.0) {
    const double step = std::min(left, 5.0 * u(rng));
    advance(scene, s.pieces, m * step);
    left -= step;
  }
  return s;
}

}  // namespace ph
