// The relief the interrogation benchmarks share: a 1920 x 1080 height field (px) of three Gaussian
// bumps/holes (35-60 px) and an 8 px ripple: every curvature class, many closed and open contours.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/engine/field.hpp"

namespace ph::bench {

inline constexpr std::int32_t kReliefWidth = 1920;
inline constexpr std::int32_t kReliefHeight = 1080;

inline const DepthField& relief_depth() {
  static const DepthField d = [] {
    DepthField f(kReliefWidth, kReliefHeight);
    for (std::int32_t y = 0; y < kReliefHeight; ++y) {
      for (std::int32_t x = 0; x < kReliefWidth; ++x) {
        auto bump = [&](double cx, double cy, double s, double a) {
          const double dx = x - cx;
          const double dy = y - cy;
          return a * std::exp(-(dx * dx + dy * dy) / (2.0 * s * s));
        };
        const double ripple = 8.0 * std::sin(x / 53.0) * std::cos(y / 41.0);
        f.at(x, y) =
            static_cast<float>(bump(480, 400, 150, 60) + bump(1300, 600, 220, 45) + bump(900, 250, 90, -35) + ripple);
      }
    }
    return f;
  }();
  return d;
}

// Its gradient, as a normal map's would be.
inline const GradientField& relief_gradient() {
  static const GradientField g = gradient_from_depth(relief_depth());
  return g;
}

}  // namespace ph::bench
