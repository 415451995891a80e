#include "core/engine/variant_choice.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>

namespace ph {

namespace {

constexpr double kMaxSamples = 20000.0;
constexpr int kDirections = 8;

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

// 1 / C/D of entering texel `t` along `m` from the texel behind it (as the direction tables take it), or a
// negative value where the texel behind lies outside the region.
double inverse_cd(const Region& region, Texel t, Vec2 m) {
  const std::int32_t dx = static_cast<std::int32_t>(std::floor(0.5 - m.x));
  const std::int32_t dy = static_cast<std::int32_t>(std::floor(0.5 - m.y));
  const Texel from{t.x + dx, t.y + dy};
  if (from.x < 0 || from.y < 0 || from.x >= region.rect.w || from.y >= region.rect.h) return -1.0;
  const Method& method = *region.method;
  const TexelSample a = method.sample(&region.fields, from, m);
  const TexelSample b = method.sample(&region.fields, t, m);
  const double cd = method.cd(a, b, std::hypot(dx, dy), nullptr);
  return std::isfinite(cd) && cd > 0.0 ? 1.0 / cd : -1.0;
}

// The largest |1/CD(p) - 1/CD(p + s m)| over the sampled texels p, directions m and distances s <= L/2.
double midpoint_spread(const Region& region, double frame_px) {
  const std::int32_t w = region.rect.w, h = region.rect.h;
  const double texels = static_cast<double>(w) * h;
  const auto stride = static_cast<std::int32_t>(std::max(1.0, std::ceil(std::sqrt(texels / kMaxSamples))));
  const double half = frame_px / 2.0;
  const std::array<double, 3> distances{1.0, half / 2.0, half};
  double spread = 0.0;
  for (int k = 0; k < kDirections; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / kDirections;
    const Vec2 m{std::cos(angle), std::sin(angle)};
    for (std::int32_t y = stride / 2; y < h; y += stride) {
      for (std::int32_t x = stride / 2; x < w; x += stride) {
        const double u = inverse_cd(region, {x, y}, m);
        if (u < 0.0) continue;
        for (const double s : distances) {
          const Texel q{static_cast<std::int32_t>(std::floor(x + 0.5 + s * m.x)),
                        static_cast<std::int32_t>(std::floor(y + 0.5 + s * m.y))};
          if (q.x < 0 || q.y < 0 || q.x >= w || q.y >= h) continue;
          const double v = inverse_cd(region, q, m);
          if (v >= 0.0) spread = std::max(spread, std::abs(u - v));
        }
      }
    }
  }
  return spread;
}

// The largest |1/CD - 1| over the region's edge texels, entered along each of the 8 directions: a frame that
// crosses the border has the flat outside (C/D 1) on the other side, which its midpoint's C/D also stands for.
double border_spread(const Region& region) {
  const std::int32_t w = region.rect.w, h = region.rect.h;
  double spread = 0.0;
  auto at = [&](std::int32_t x, std::int32_t y) {
    for (int k = 0; k < kDirections; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / kDirections;
      const double u = inverse_cd(region, {x, y}, {std::cos(angle), std::sin(angle)});
      if (u >= 0.0) spread = std::max(spread, std::abs(u - 1.0));
    }
  };
  for (std::int32_t x = 0; x < w; ++x) {
    at(x, 0);
    at(x, h - 1);
  }
  for (std::int32_t y = 0; y < h; ++y) {
    at(0, y);
    at(w - 1, y);
  }
  return spread;
}

}  // namespace

VariantChoice choose_variant(const Region& region, const VariantBudget& budget) {
  VariantChoice choice;
  EngineOptions midpoint;
  midpoint.traversal = Traversal::frame_midpoint;
  const Method& method = *region.method;
  if (method.cd_lower_bound() == 1.0 && method.cd_upper_bound() == 1.0) {
    choice.options = midpoint;
    choice.reason = "frame_midpoint: the method's C/D is 1 throughout, every variant is exact";
    return choice;
  }
  choice.midpoint_error_px =
      budget.frame_px * std::max(midpoint_spread(region, budget.frame_px), border_spread(region));
  const std::string estimate = "frame_midpoint would be off by up to " + number(choice.midpoint_error_px) +
                               " px over a " + number(budget.frame_px) + " px frame";
  if (choice.midpoint_error_px <= budget.accuracy_px) {
    choice.options = midpoint;
    choice.reason = "frame_midpoint: " + estimate + ", within accuracy_px " + number(budget.accuracy_px);
  } else {
    choice.options = EngineOptions{};
    choice.reason = "exact: " + estimate + ", more than accuracy_px " + number(budget.accuracy_px);
  }
  return choice;
}

}  // namespace ph
