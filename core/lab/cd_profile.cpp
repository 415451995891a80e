#include "core/lab/cd_profile.hpp"

#include <algorithm>

#include "core/engine/grid_walk.hpp"

namespace ph {

std::vector<CdSegment> cd_segments(const std::vector<StepRecord>& steps, Vec2 origin, Vec2 m, double end_s) {
  std::vector<CdSegment> out;
  auto along = [&](Vec2 p) { return (p.x - origin.x) * m.x + (p.y - origin.y) * m.y; };
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const StepRecord& step = steps[i];
    if (step.region == nullptr) continue;
    const double a = i == 0 ? 0.0 : along(step.entry);
    const double b = i + 1 < steps.size() ? along(steps[i + 1].entry) : end_s;
    if (!(b > a)) continue;
    const Rect& r = step.region->rect;
    const Vec2 lo{static_cast<double>(r.x), static_cast<double>(r.y)};
    const Vec2 hi{static_cast<double>(r.x) + r.w, static_cast<double>(r.y) + r.h};
    const RaySpan span = ray_box(origin, m, lo, hi, a, b);
    if (!(span.t1 > span.t0)) continue;
    out.push_back({span.t0, span.t1, step.cd});
  }
  return out;
}

double cd_at(const std::vector<CdSegment>& segments, double s) {
  const auto it =
      std::upper_bound(segments.begin(), segments.end(), s, [](double v, const CdSegment& g) { return v < g.s0; });
  if (it == segments.begin()) return 1.0;
  const CdSegment& g = *(it - 1);
  return s < g.s1 ? g.cd : 1.0;
}

}  // namespace ph
