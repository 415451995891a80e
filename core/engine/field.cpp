#include "core/engine/field.hpp"

#include <algorithm>
#include <cmath>

#include "core/engine/row_bands.hpp"

namespace ph {

Normal normal_from_gradient(Gradient g) {
  const double nx = -static_cast<double>(g.x);
  const double ny = -static_cast<double>(g.y);
  const double len = std::sqrt(nx * nx + ny * ny + 1.0);
  return {static_cast<float>(nx / len), static_cast<float>(ny / len), static_cast<float>(1.0 / len)};
}

Gradient clamped_gradient(Normal n) {
  const Gradient g = gradient_from_normal(n);
  return Gradient{std::clamp(g.x, -kMaxSlope, kMaxSlope), std::clamp(g.y, -kMaxSlope, kMaxSlope)};
}

GradientField gradient_from_normals(const NormalImage& normals) {
  GradientField gradient(normals.width, normals.height);
  std::transform(normals.values.begin(), normals.values.end(), gradient.values.begin(), clamped_gradient);
  return gradient;
}

GradientField gradient_from_depth(const DepthField& depth, unsigned threads) {
  const std::int32_t w = depth.width;
  const std::int32_t h = depth.height;
  GradientField out(w, h);
  // Central difference inside, one-sided at the border; a 1-texel axis has no slope along it. Clamped to
  // +-kMaxSlope as slopes from normals are: a depth map of huge values (a float image may hold 1e38)
  // would otherwise give slopes of 1e38 or inf.
  auto diff = [](float lo, float hi, std::int32_t span) {
    if (span <= 0 || hi == lo) return 0.0f;
    const double d = (static_cast<double>(hi) - static_cast<double>(lo)) / span;
    return static_cast<float>(std::clamp(d, -static_cast<double>(kMaxSlope), static_cast<double>(kMaxSlope)));
  };
  for_row_bands_on_threads(h, threads, [&](RowRange rows) {
    for (std::int32_t y = rows.begin; y < rows.end; ++y) {
      const std::int32_t y0 = y > 0 ? y - 1 : y;
      const std::int32_t y1 = y + 1 < h ? y + 1 : y;
      for (std::int32_t x = 0; x < w; ++x) {
        const std::int32_t x0 = x > 0 ? x - 1 : x;
        const std::int32_t x1 = x + 1 < w ? x + 1 : x;
        out.at(x, y) = {diff(depth.at(x0, y), depth.at(x1, y), x1 - x0),
                        diff(depth.at(x, y0), depth.at(x, y1), y1 - y0)};
      }
    }
  });
  return out;
}

}  // namespace ph
