#include "core/traversal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/fast_math.hpp"
#include "core/method_curvature.hpp"
#include "core/method_depth.hpp"

namespace ph {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// More texel steps than any frame can take across regions of at most 2^14 px a side.
constexpr std::uint64_t kMaxStepsPerFrame = std::uint64_t{1} << 26;

int sign_of(double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); }

// Index of the grid cell a coordinate lies in, taking a coordinate on a cell boundary to belong to the
// cell the motion came from (so a stop exactly on a boundary stays in the texel that was being walked).
std::int32_t cell_behind(double v, int step) { return step > 0 ? -floor_to_int(-v) - 1 : floor_to_int(v); }

// Index of the cell a motion starting at a coordinate moves into.
std::int32_t cell_ahead(double v, int step) { return step < 0 ? -floor_to_int(-v) - 1 : floor_to_int(v); }

// Where a ray enters a region's box, if it does within `limit` of display travel.
struct Entry {
  double t = kInf;
  std::size_t region = 0;
  bool via_x = true;
};

class Walker {
 public:
  Walker(const Scene& scene, CursorState& cursor, Vec2 m, StepObserver* observer, FrameResult& result)
      : scene_(scene),
        m_(m),
        observer_(observer),
        result_(result),
        sx_(sign_of(m.x)),
        sy_(sign_of(m.y)),
        tdx_(m.x != 0.0 ? 1.0 / std::abs(m.x) : kInf),
        tdy_(m.y != 0.0 ? 1.0 / std::abs(m.y) : kInf),
        texel_(cursor.texel),
        from_(cursor.came_from) {
    restart_at(cursor.position);
  }

  // Walks `budget` px of motor travel; returns the end state.
  CursorState run(double budget) {
    budget_ = budget;
    bool first = true;
    while (budget_ > 0.0) {
      const std::optional<std::size_t> owner = scene_.owner(texel_);
      if (owner) {
        // One dispatch per leg: the built-in methods' sample() and cd() then inline into the loop.
        const Method& method = *scene_.regions()[*owner].method;
        switch (method.builtin()) {
          case BuiltinMethod::curvature:
            walk_region(*owner, static_cast<const CurvatureMethod&>(method), first);
            break;
          case BuiltinMethod::depth:
            walk_region(*owner, static_cast<const DepthMethod&>(method), first);
            break;
          case BuiltinMethod::none:
            walk_region(*owner, method, first);
            break;
        }
      } else {
        cross_flat();
      }
      first = false;
    }
    return end_state();
  }

  bool all_unit() const { return all_unit_; }

 private:
  Vec2 position() const { return origin_ + m_ * t_; }

  // Starts a straight leg at p inside (or on the boundary of) the current texel.
  void restart_at(Vec2 p) {
    // Keep the position inside the texel's closed box: rounding must not put it in a neighbour.
    p.x = std::clamp(p.x, static_cast<double>(texel_.x), static_cast<double>(texel_.x) + 1.0);
    p.y = std::clamp(p.y, static_cast<double>(texel_.y), static_cast<double>(texel_.y) + 1.0);
    origin_ = p;
    t_ = 0.0;
    tmx_ = sx_ > 0 ? (texel_.x + 1.0 - p.x) * tdx_ : (sx_ < 0 ? (p.x - texel_.x) * tdx_ : kInf);
    tmy_ = sy_ > 0 ? (texel_.y + 1.0 - p.y) * tdy_ : (sy_ < 0 ? (p.y - texel_.y) * tdy_ : kInf);
  }

  template <typename M>
  TexelSample sample_with(const M& method, Texel t) const {
    const std::optional<std::size_t> owner = scene_.owner(t);
    if (!owner) return method.sample(nullptr, {}, m_);
    const Region& region = scene_.regions()[*owner];
    return method.sample(&region.fields, region.local(t), m_);
  }

  template <typename M>
  double step_cd(const Region& region, const M& method, const TexelSample& from, const TexelSample& to, bool entered) {
    double cd;
    if (observer_ == nullptr) {
      cd = method.cd(from, to, 1.0, nullptr);
    } else {
      StepRecord record;
      cd = method.cd(from, to, 1.0, &record.detail);
      record.entry = position();
      record.texel = texel_;
      record.came_from = from_;
      record.entered = entered;
      record.cd = cd;
      record.region = &region;
      observer_->on_step(record);
    }
    all_unit_ = all_unit_ && cd == 1.0;
    result_.cd_min = std::min(result_.cd_min, cd);
    result_.cd_max = std::max(result_.cd_max, cd);
    if (entered) ++result_.steps;
    return cd;
  }

  // Walks texel by texel while the texels belong to `index`. M is the method's concrete type for the
  // built-in methods (calls inline), or Method itself (virtual calls) for any other.
  template <typename M>
  void walk_region(std::size_t index, const M& method, bool first_leg) {
    const Region& region = scene_.regions()[index];
    TexelSample s_from = sample_with(method, from_);
    TexelSample s_cur = method.sample(&region.fields, region.local(texel_), m_);
    double cd = step_cd(region, method, s_from, s_cur, !first_leg);
    const bool topmost = index + 1 == scene_.regions().size();
    for (;;) {
      const double t_next = std::min(tmx_, tmy_);
      const double cost = cd * (t_next - t_);
      if (cost >= budget_) {
        t_ += budget_ / cd;
        budget_ = 0.0;
        return;
      }
      budget_ -= cost;
      t_ = t_next;
      if (++steps_ > kMaxStepsPerFrame) {
        budget_ = 0.0;  // unreachable for a valid scene (a ray crosses each region once); never spin
        return;
      }
      from_ = texel_;
      if (tmx_ <= tmy_) {
        texel_.x += sx_;
        tmx_ += tdx_;
      } else {
        texel_.y += sy_;
        tmy_ += tdy_;
      }
      if (!region.rect.contains(texel_) || (!topmost && scene_.owner(texel_) != index)) {
        restart_at(position());
        return;  // another region or the flat outside takes over
      }
      s_from = s_cur;
      s_cur = method.sample(&region.fields, region.local(texel_), m_);
      cd = step_cd(region, method, s_from, s_cur, true);
    }
  }

  // The display-travel interval [t0, t1) in which the ray is within a box's range on one axis. Which
  // side of the range the ray starts on is read from the current texel, not the position, so that
  // rounding on a boundary can never re-enter a region the walk has just left.
  static bool slab(double p, std::int32_t lo, std::int32_t hi, int step, double td, std::int32_t cell, double& t0,
                   double& t1) {
    t0 = -kInf;
    t1 = kInf;
    if (step == 0) return cell >= lo && cell < hi;
    if (step > 0) {
      if (cell >= hi) return false;
      t1 = (hi - p) * td;
      if (cell < lo) t0 = (lo - p) * td;
    } else {
      if (cell < lo) return false;
      t1 = (p - lo) * td;
      if (cell >= hi) t0 = (p - hi) * td;
    }
    return true;
  }

  Entry next_entry(Vec2 p, double limit) const {
    Entry best;
    const auto& regions = scene_.regions();
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const Rect& r = regions[i].rect;
      double x0, x1, y0, y1;
      if (!slab(p.x, r.x, r.x + r.w, sx_, tdx_, texel_.x, x0, x1)) continue;
      if (!slab(p.y, r.y, r.y + r.h, sy_, tdy_, texel_.y, y0, y1)) continue;
      const double t_in = std::max({x0, y0, 0.0});
      const double t_out = std::min(x1, y1);
      if (t_in < t_out && t_in <= limit && t_in < best.t) best = {t_in, i, x0 >= y0};
    }
    return best;
  }

  // On the flat outside C/D is 1: jump straight to the next region the ray enters, or to the end.
  void cross_flat() {
    const Vec2 p = position();
    const Entry entry = next_entry(p, budget_);
    if (entry.t > 0.0) {
      result_.cd_min = std::min(result_.cd_min, 1.0);
      result_.cd_max = std::max(result_.cd_max, 1.0);
    }
    if (entry.t > budget_ || entry.t == kInf) {
      t_ += budget_;
      budget_ = 0.0;
      // An axis the motion does not move along keeps its texel row or column.
      const Vec2 end = position();
      if (sx_ != 0) texel_.x = cell_behind(end.x, sx_);
      if (sy_ != 0) texel_.y = cell_behind(end.y, sy_);
      from_ = texel_;
      return;
    }
    budget_ -= entry.t;
    t_ += entry.t;
    const Vec2 at = position();
    const Rect& r = scene_.regions()[entry.region].rect;
    Texel in{cell_ahead(at.x, sx_), cell_ahead(at.y, sy_)};
    if (sx_ == 0) in.x = texel_.x;
    if (sy_ == 0) in.y = texel_.y;
    in.x = std::clamp(in.x, r.x, r.x + r.w - 1);
    in.y = std::clamp(in.y, r.y, r.y + r.h - 1);
    from_ = entry.via_x ? Texel{in.x - sx_, in.y} : Texel{in.x, in.y - sy_};
    texel_ = in;
    restart_at(at);
  }

  CursorState end_state() const {
    Vec2 p = position();
    p.x = std::clamp(p.x, static_cast<double>(texel_.x), static_cast<double>(texel_.x) + 1.0);
    p.y = std::clamp(p.y, static_cast<double>(texel_.y), static_cast<double>(texel_.y) + 1.0);
    return {p, texel_, from_, {}};
  }

  const Scene& scene_;
  const Vec2 m_;
  StepObserver* const observer_;
  FrameResult& result_;
  const int sx_, sy_;
  const double tdx_, tdy_;  // display travel per texel along x and y
  Texel texel_, from_;
  Vec2 origin_;                     // start of the current straight leg
  double t_ = 0.0;                  // display travel since origin_
  double tmx_ = kInf, tmy_ = kInf;  // display travel from origin_ to the next x / y texel boundary
  double budget_ = 0.0;             // motor travel left in the frame
  bool all_unit_ = true;
  std::uint64_t steps_ = 0;
};

}  // namespace

// True when the segment from the cursor by `motor` cannot touch any region: its bounding box misses
// every region's closed box (a few compares per region), and it stays well inside the world.
bool crosses_only_flat(const Scene& scene, const CursorState& cursor, Vec2 motor) {
  constexpr double kFar = kWorldLimitPx / 2;
  const Vec2 p = cursor.position;
  const Vec2 end = p + motor;
  if (!(std::abs(end.x) < kFar && std::abs(end.y) < kFar && std::abs(p.x) < kFar && std::abs(p.y) < kFar)) return false;
  const double x0 = std::min(p.x, end.x), x1 = std::max(p.x, end.x);
  const double y0 = std::min(p.y, end.y), y1 = std::max(p.y, end.y);
  for (const Region& region : scene.regions()) {
    const Rect& r = region.rect;
    if (x1 >= r.x && x0 <= static_cast<double>(r.x) + r.w && y1 >= r.y && y0 <= static_cast<double>(r.y) + r.h) {
      return false;
    }
  }
  return true;
}

double clamp_to_world(double v) { return std::isfinite(v) ? std::clamp(v, -kWorldLimitPx, kWorldLimitPx) : 0.0; }

CursorState cursor_at(Vec2 position) {
  position = {clamp_to_world(position.x), clamp_to_world(position.y)};
  const Texel t = texel_at(position);
  return {position, t, t, {}};
}

namespace {

// Runs the effects of the region under the cursor on the frame's motor displacement; returns the
// factor by which they changed its length (1 when none acted).
double apply_effects(const Scene& scene, CursorState& cursor, Vec2& motor, TimeUs time) {
  const std::optional<std::size_t> owner = scene.owner(cursor.texel);
  if (!owner) return 1.0;
  const Region& region = scene.regions()[*owner];
  if (region.effects.empty()) return 1.0;
  const double before = fast_length(motor.x, motor.y);
  for (const EffectPtr& effect : region.effects) {
    if (cursor.effect.owner != effect.get()) cursor.effect = EffectState{true, 0.0, kNoTime, effect.get()};
    const EffectInput in{motor, time, cursor.position, region.local(cursor.texel)};
    const Vec2 out = effect->apply(in, cursor.effect);
    // The promise of every effect, kept here too: finite, and never more than its bounds allow.
    const double length = fast_length(out.x, out.y);
    if (is_finite(out) && length <= before * effect->max_gain() * (1.0 + 1e-12) &&
        length >= before * effect->min_gain() * (1.0 - 1e-12)) {
      motor = out;
    }
  }
  const double after = fast_length(motor.x, motor.y);
  return before > 0.0 ? after / before : 1.0;
}

// The traversal proper: walks `motor` (finite, not zero) through the texels from the cursor.
FrameResult walk(const Scene& scene, CursorState& cursor, Vec2 motor, StepObserver* observer) {
  FrameResult result;
  if (crosses_only_flat(scene, cursor, motor)) {
    // C/D is 1 all the way: the display moves by the motor displacement itself, with no walk at all.
    const Vec2 end = cursor.position + motor;
    if (motor.x != 0.0) cursor.texel.x = cell_behind(end.x, motor.x > 0.0 ? 1 : -1);
    if (motor.y != 0.0) cursor.texel.y = cell_behind(end.y, motor.y > 0.0 ? 1 : -1);
    cursor.came_from = cursor.texel;
    cursor.position = end;
    result.display = motor;
    return result;
  }
  double d = fast_length(motor.x, motor.y);
  // Divide rather than multiply by 1/d: for a denormal d, 1/d overflows and the walk would never advance.
  const Vec2 m{motor.x / d, motor.y / d};
  if (!is_finite(m)) return result;
  if (d > kMaxMotorPx) {
    d = kMaxMotorPx;
    motor = m * d;
  }
  result.cd_min = kInf;
  result.cd_max = -kInf;
  Walker walker(scene, cursor, m, observer, result);
  const Vec2 start = cursor.position;
  CursorState end = walker.run(d);
  if (walker.all_unit()) {
    // C/D was 1 everywhere: the display moves by the motor displacement itself, with no rounding.
    end.position = start + motor;
  }
  if (std::abs(end.position.x) > kWorldLimitPx || std::abs(end.position.y) > kWorldLimitPx ||
      !is_finite(end.position)) {
    end = cursor_at(end.position);
  }
  if (result.cd_min > result.cd_max) result.cd_min = result.cd_max = 1.0;
  result.display = walker.all_unit() && end.position == start + motor ? motor : end.position - start;
  end.effect = cursor.effect;
  cursor = end;
  return result;
}

}  // namespace

FrameResult advance(const Scene& scene, CursorState& cursor, Vec2 motor, TimeUs time, StepObserver* observer) {
  if (!is_finite(motor) || (motor.x == 0.0 && motor.y == 0.0)) return {};
  const double gain = scene.has_effects() ? apply_effects(scene, cursor, motor, time) : 1.0;
  if (motor.x == 0.0 && motor.y == 0.0) return {};
  FrameResult result = walk(scene, cursor, motor, observer);
  if (gain != 1.0) {
    // The hand's motor travel was the frame's; the effects let only `gain` of it reach the walk.
    result.cd_min /= gain;
    result.cd_max /= gain;
  }
  return result;
}

}  // namespace ph
