#include "core/engine/traversal_variants.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/engine/fast_math.hpp"
#include "core/engine/grid_walk.hpp"
#include "core/engine/methods.hpp"

namespace ph {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Unit steps inside regions of at most 2^14 px a side: far fewer than this per frame; never spin.
constexpr std::uint64_t kMaxUnitSteps = std::uint64_t{1} << 26;

// What `method` reads at texel t (nearest) or at point p inside t (bilinear).
template <typename M>
TexelSample probe(const Scene& scene, const M& method, Texel t, Vec2 p, Vec2 m, Sampling sampling) {
  return sampling == Sampling::bilinear ? sample_owner(scene, method, t, m, &p) : sample_owner(scene, method, t, m);
}

// Display travel from p along m to where the ray first touches a region's closed box; kInf for none.
double next_region(const Scene& scene, Vec2 p, Vec2 m) {
  double best = kInf;
  for (const Region& region : scene.regions()) {
    const Rect& r = region.rect;
    const Vec2 hi{static_cast<double>(r.x) + r.w, static_cast<double>(r.y) + r.h};
    const RaySpan span = ray_box(p, m, corner(region), hi, 0.0, kInf);
    if (span.hits()) best = std::min(best, span.t0);
  }
  return best;
}

// Keeps the frame's C/D range and counts a step inside a region.
void note_cd(FrameResult& result, bool& all_unit, double cd, bool in_region) {
  all_unit = all_unit && cd == 1.0;
  result.cd_min = std::min(result.cd_min, cd);
  result.cd_max = std::max(result.cd_max, cd);
  if (in_region) ++result.steps;
}

void report(StepObserver* observer, Vec2 at, Texel texel, Texel from, double cd, const StepDetail& detail,
            const Region* region) {
  if (observer == nullptr) return;
  StepRecord record;
  record.entry = at;
  record.texel = texel;
  record.came_from = from;
  record.entered = texel != from;
  record.cd = cd;
  record.detail = detail;
  record.region = region;
  observer->on_step(record);
}

// End state at p after moving along (sx, sy): an axis the motion does not move along keeps its texel.
CursorState end_at(const CursorState& cursor, Vec2 p, int sx, int sy, Texel came_from) {
  Texel t = cursor.texel;
  if (sx != 0) t.x = cell_behind(p.x, sx);
  if (sy != 0) t.y = cell_behind(p.y, sy);
  return {p, t, came_from, {}};
}

}  // namespace

CursorState walk_unit_steps(const Scene& scene, const CursorState& cursor, Vec2 m, double d, Sampling sampling,
                            StepObserver* observer, FrameResult& result, bool& all_unit) {
  const int sx = sign_of(m.x), sy = sign_of(m.y);
  auto texel_ahead = [&](Vec2 p) {
    return Texel{sx != 0 ? cell_ahead(p.x, sx) : cursor.texel.x, sy != 0 ? cell_ahead(p.y, sy) : cursor.texel.y};
  };
  const Vec2 origin = cursor.position;
  double t = 0.0;  // display travel from origin: steps add whole pixels, so positions do not drift
  double budget = d;
  Texel prev = cursor.came_from, cur = cursor.texel;
  // The previous step's sample, kept while the method reading it stays the same.
  const Method* cached_method = nullptr;
  TexelSample cached{};
  for (std::uint64_t steps = 0; budget > 0.0 && steps < kMaxUnitSteps; ++steps) {
    const Vec2 p = origin + m * t;
    cur = texel_ahead(p);
    const std::optional<std::size_t> owner = scene.owner(cur);
    if (!owner && !scene.owner(prev)) {
      // Flat to flat: C/D 1 up to the next region (at least one step, so a ray along an edge moves on).
      const double jump = std::max(1.0, next_region(scene, p, m));
      note_cd(result, all_unit, 1.0, false);
      cached_method = nullptr;
      if (jump >= budget) {
        t += budget;
        budget = 0.0;
        break;
      }
      t += jump;
      budget -= jump;
      const Vec2 q = origin + m * t;
      prev = {sx != 0 ? cell_behind(q.x, sx) : cur.x, sy != 0 ? cell_behind(q.y, sy) : cur.y};
      continue;
    }
    double cd = 1.0;
    StepDetail detail = empty_step_detail();
    const Region* region = nullptr;
    if (owner) {
      region = &scene.regions()[*owner];
      const Method& method = *region->method;
      cd = visit_method(method, [&](const auto& mth) {
        // The previous step's reading; bilinear: the point 1 px behind, in whatever texel it lies.
        const Texel behind = sampling == Sampling::bilinear ? texel_at(p - m) : prev;
        const TexelSample from = cached_method == &method ? cached : probe(scene, mth, behind, p - m, m, sampling);
        const TexelSample to = probe(scene, mth, cur, p, m, sampling);
        cached = to;
        return mth.cd(from, to, 1.0, observer != nullptr ? &detail : nullptr);
      });
      cached_method = &method;
    } else {
      cached_method = nullptr;  // leaving a region: the flat outside's C/D is 1
    }
    note_cd(result, all_unit, cd, owner.has_value());
    report(observer, p, cur, prev, cd, detail, region);
    if (cd >= budget) {
      t += budget / cd;  // the last, partial step
      budget = 0.0;
      break;
    }
    budget -= cd;
    t += 1.0;
    prev = cur;
  }
  const Vec2 end = origin + m * t;
  CursorState state = end_at(cursor, end, sx, sy, cur);
  // The next frame's first step pairs its texel with the texel of this frame's last step.
  if (state.came_from == state.texel) state.came_from = prev;
  return state;
}

CursorState walk_frame_midpoint(const Scene& scene, const CursorState& cursor, Vec2 m, double d, Sampling sampling,
                                StepObserver* observer, FrameResult& result, bool& all_unit) {
  const Vec2 p = cursor.position;
  const Vec2 mid = p + m * (0.5 * d);  // where the frame's middle would be at C/D 1
  const Vec2 behind = mid - m;
  const Texel at = texel_at(mid), from = texel_at(behind);
  const std::optional<std::size_t> owner = scene.owner(at);
  double cd = 1.0;
  StepDetail detail = empty_step_detail();
  const Region* region = nullptr;
  if (owner) {
    region = &scene.regions()[*owner];
    cd = visit_method(*region->method, [&](const auto& mth) {
      return mth.cd(probe(scene, mth, from, behind, m, sampling), probe(scene, mth, at, mid, m, sampling), 1.0,
                    observer != nullptr ? &detail : nullptr);
    });
  }
  note_cd(result, all_unit, cd, owner.has_value());
  report(observer, mid, at, from, cd, detail, region);
  const Vec2 end = p + m * (d / cd);
  const CursorState state = end_at(cursor, end, sign_of(m.x), sign_of(m.y), {});
  return {state.position, state.texel, state.texel, {}};
}

}  // namespace ph
