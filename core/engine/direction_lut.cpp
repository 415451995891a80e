#include "core/engine/direction_lut.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "core/engine/grid_walk.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/scene.hpp"

namespace ph {

namespace {

constexpr double kCodeMax = std::numeric_limits<std::int16_t>::max();           // 32767
constexpr double kCodeMin = -double{std::numeric_limits<std::int16_t>::min()};  // 32768

}  // namespace

DirectionLut::DirectionLut(std::int32_t width, std::int32_t height, int directions, double cd_lo, double cd_hi)
    : width_(width),
      height_(height),
      directions_(directions),
      lo_(cd_lo),
      hi_(cd_hi),
      up_(cd_hi > 1.0 ? (cd_hi - 1.0) / kCodeMax : 1.0),
      down_(cd_lo < 1.0 ? (1.0 - cd_lo) / kCodeMin : 1.0),
      codes_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * static_cast<std::size_t>(directions),
             0) {}

int DirectionLut::direction_index(Vec2 m, int directions) {
  const double turns = std::atan2(m.y, m.x) / (2.0 * std::numbers::pi);  // [-0.5, 0.5]
  const long k = std::lround(turns * directions);
  return static_cast<int>(((k % directions) + directions) % directions);
}

Vec2 DirectionLut::direction(int k) const {
  const double angle = 2.0 * std::numbers::pi * k / directions_;
  // Exact axes and diagonals: cos(pi / 2) is 6e-17, which would make a vertical direction lean.
  const double c = std::cos(angle), s = std::sin(angle);
  return {std::abs(c) < 1e-12 ? 0.0 : c, std::abs(s) < 1e-12 ? 0.0 : s};
}

void DirectionLut::set(int k, Texel local, double cd) {
  cd = std::clamp(std::isfinite(cd) ? cd : 1.0, lo_, hi_);
  const double q = cd >= 1.0 ? std::round((cd - 1.0) / up_) : -std::round((1.0 - cd) / down_);
  codes_[plane_offset(k) + static_cast<std::size_t>(local.y) * width_ + local.x] =
      static_cast<std::int16_t>(std::clamp(q, -kCodeMin, kCodeMax));
}

namespace {

// M: the method's concrete type, so that sample() and cd() inline. Each entry reads its texel as the nearest walk
// does (the method's leg for the direction, worked out once per direction) and samples the texel behind only where
// cd() reads it (a region's border, for the methods that read along the motion): a sample per entry, not two.
template <typename M>
DirectionLut build_with(const Scene& scene, const Region& region, const M& method, int directions) {
  const std::int32_t w = region.rect.w, h = region.rect.h;
  DirectionLut lut(w, h, directions, method.cd_lower_bound(), method.cd_upper_bound());
  for (int k = 0; k < directions; ++k) {
    const Vec2 m = lut.direction(k);
    // The neighbour behind: the texel holding (centre - m), centre at +0.5.
    const std::int32_t dx = static_cast<std::int32_t>(std::floor(0.5 - m.x));
    const std::int32_t dy = static_cast<std::int32_t>(std::floor(0.5 - m.y));
    const double step_px = std::hypot(dx, dy);
    // The texel behind p: from the region's own fields inside it, from whatever lies there beyond its edge.
    const auto sample_behind = [&](Texel p) {
      const Texel nb{p.x + dx, p.y + dy};
      if (nb.x >= 0 && nb.x < w && nb.y >= 0 && nb.y < h) return method.sample(&region.fields, nb, m);
      return sample_owner(scene, method, nb + corner_texel(region), m);
    };
    const auto fill = [&](const auto& sample_here) {
      for (std::int32_t y = 0; y < h; ++y) {
        for (std::int32_t x = 0; x < w; ++x) {
          const TexelSample here = sample_here(Texel{x, y});
          const TexelSample from = cd_reads_from(method, here) ? sample_behind({x, y}) : TexelSample{};
          lut.set(k, {x, y}, method.cd(from, here, step_px, nullptr));
        }
      }
    };
    if constexpr (requires { method.leg(&region.fields, m).sample(Texel{}); }) {
      const auto leg = method.leg(&region.fields, m);
      fill([&](Texel p) PH_ALWAYS_INLINE { return leg.sample(p); });
    } else {
      fill([&](Texel p) { return method.sample(&region.fields, p, m); });
    }
  }
  return lut;
}

}  // namespace

DirectionLut build_direction_lut(const Scene& scene, std::size_t index, int directions) {
  const Region& region = scene.regions()[index];
  return visit_method(*region.method,
                      [&](const auto& method) { return build_with(scene, region, method, directions); });
}

}  // namespace ph
