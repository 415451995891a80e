#include "core/engine/traversal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/engine/direction_lut.hpp"
#include "core/engine/fast_math.hpp"
#include "core/engine/grid_walk.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/pair_math.hpp"
#include "core/engine/traversal_variants.hpp"

namespace ph {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// More texel steps than any frame can take across regions of at most 2^14 px a side.
constexpr std::uint64_t kMaxStepsPerFrame = std::uint64_t{1} << 26;

// Where a ray enters a region's box, if it does within `limit` of display travel.
struct Entry {
  double t = kInf;
  std::size_t region = 0;
  bool via_x = true;
};

// Where a walk leaves the cursor: a CursorState without the effects' state, which the walk does not touch (copying
// that too was a tenth of a typical frame's bookkeeping).
struct EndPlace {
  Vec2 position;
  Texel texel, came_from;
};

// The variants that walk the exact texel sequence (core/engine/engine_options.hpp): nearest is the default
// engine; bilinear samples each texel at the midpoint of the ray's chord through it; lut takes each
// texel's C/D from the region's direction table. Each is its own instantiation, so the default's loop
// has no per-texel branch on the variant.
enum class WalkMode { nearest, bilinear, lut };

template <WalkMode Mode>
class Walker {
 public:
  // The display travel per texel along x and y is 1 / |m|, +inf along an axis the motion does not move along (1 / 0):
  // both in one division.
  Walker(const Scene& scene, CursorState& cursor, Vec2 m, StepObserver* observer, FrameResult& result)
      : Walker(scene, cursor, m, observer, result, kOnes / abs2(Double2{m.x, m.y})) {}

  // Walks `budget` px of motor travel; returns where the cursor ends.
  EndPlace run(double budget) {
    budget_ = budget;
    bool first = true;
    while (budget_ > 0.0) {
      if (steps_ > kMaxStepsPerFrame) {
        budget_ = 0.0;  // unreachable for a valid scene (a ray crosses each region once); never spin
        break;
      }
      const std::optional<std::size_t> owner = scene_.owner(texel_);
      const DirectionLut* lut = nullptr;
      if constexpr (Mode == WalkMode::lut) lut = owner ? scene_.direction_lut(*owner) : nullptr;
      if (lut != nullptr) {
        walk_region_lut(*owner, *lut, first);
      } else if (owner) {
        // One dispatch per leg: the listed methods' sample() and cd() then inline into the loop.
        visit_method(*scene_.regions()[*owner].method, [&](const auto& method) { walk_region(*owner, method, first); });
      } else {
        cross_flat();
      }
      first = false;
    }
    return end_state();
  }

  bool all_unit() const { return all_unit_; }

 private:
  Walker(const Scene& scene, CursorState& cursor, Vec2 m, StepObserver* observer, FrameResult& result,
         Double2 texel_travel)
      : scene_(scene),
        m_(m),
        observer_(observer),
        result_(result),
        sx_(sign_of(m.x)),
        sy_(sign_of(m.y)),
        forward_(Double2{m.x, m.y} > Double2{0.0, 0.0}),
        still_(Double2{m.x, m.y} == Double2{0.0, 0.0}),
        tdx_(texel_travel[0]),
        tdy_(texel_travel[1]),
        texel_(cursor.texel),
        from_(cursor.came_from) {
    restart_at(cursor.position);
  }

  Vec2 position() const { return origin_ + m_ * t_; }

  // Starts a straight leg at p inside (or on the boundary of) the current texel.
  void restart_at(Vec2 p) {
    // Keep the position inside the texel's closed box: rounding must not put it in a neighbour.
    p.x = std::clamp(p.x, static_cast<double>(texel_.x), static_cast<double>(texel_.x) + 1.0);
    p.y = std::clamp(p.y, static_cast<double>(texel_.y), static_cast<double>(texel_.y) + 1.0);
    origin_ = p;
    t_ = 0.0;
    // Both axes at once and without a branch on the signs (random from frame to frame): along each axis the
    // distance to the texel's far side times the travel per texel, or +inf along an axis the motion does not move
    // along.
    const Double2 at{p.x, p.y}, cell{static_cast<double>(texel_.x), static_cast<double>(texel_.y)};
    const Double2 travel = select2(forward_, (cell + kOnes) - at, at - cell) * Double2{tdx_, tdy_};
    const Double2 next = select2(still_, splat(kInf), travel);
    tmx_ = next[0];
    tmy_ = next[1];
  }

  // Midpoint of the chord of the current line through a texel's box (the texel's centre when the line
  // misses the box: a history texel from another direction). For Sampling::bilinear: a function of the
  // texel and the line only, so splitting a frame does not change what a texel samples.
  Vec2 chord_mid(Texel box) const {
    const Vec2 lo{static_cast<double>(box.x), static_cast<double>(box.y)};
    const RaySpan chord = ray_box(origin_, m_, lo, lo + Vec2{1.0, 1.0}, -kInf, kInf);
    if (chord.hits()) return origin_ + m_ * (0.5 * (chord.t0 + chord.t1));
    return {box.x + 0.5, box.y + 0.5};
  }

  // Sample of the texel the walk is in (nearest: its value; bilinear: at its chord's midpoint). Once per step,
  // forced inline: out of line, the sample goes through memory (the curvature method's pair of normals made
  // GCC leave it out).
  template <typename M>
  PH_ALWAYS_INLINE TexelSample sample_here(const Region& region, const M& method, Vec2 m) {
    if constexpr (Mode == WalkMode::bilinear) {
      // The current texel's chord from the walk's own boundary distances: no division.
      const double t_in = std::max(sx_ != 0 ? tmx_ - tdx_ : -kInf, sy_ != 0 ? tmy_ - tdy_ : -kInf);
      const Vec2 at = origin_ + m_ * (0.5 * (t_in + std::min(tmx_, tmy_)));
      const Vec2 gap = at - sample_point_;
      step_px_ = std::max(fast_length(gap.x, gap.y), 1e-3);  // depth: the distance the height changes over
      sample_point_ = at;
      return method.sample_at(&region.fields, region.local(texel_), at - corner(region), m_);
    } else {
      return method.sample(&region.fields, region.local(texel_), m);
    }
  }

  // Sample of the texel the walk came from, at the start of a leg.
  template <typename M>
  TexelSample sample_from(const M& method) {
    if constexpr (Mode == WalkMode::bilinear) {
      sample_point_ = chord_mid(from_);
      return sample_owner(scene_, method, from_, m_, &sample_point_);
    } else {
      return sample_owner(scene_, method, from_, m_);
    }
  }

  // The C/D of a step, shown to the observer if there is one (`observed`; step_through has then written the
  // members it reads).
  template <typename M>
  PH_ALWAYS_INLINE double step_cd(const Region& region, const M& method, const TexelSample& from, const TexelSample& to,
                                  bool entered, bool observed) {
    const double step_px = Mode == WalkMode::bilinear ? step_px_ : 1.0;
    if (!observed) [[likely]]
      return method.cd(from, to, step_px, nullptr);
    StepDetail detail;
    const double cd = method.cd(from, to, step_px, &detail);
    observe_step(cd, detail, entered, region);
    return cd;
  }

  void observe_step(double cd, const StepDetail& detail, bool entered, const Region& region) {
    StepRecord record;
    record.detail = detail;
    record.entry = position();
    record.texel = texel_;
    record.came_from = from_;
    record.entered = entered;
    record.cd = cd;
    record.region = &region;
    observer_->on_step(record);
  }

  // Walks texel by texel while the texels belong to `index`. M is the method's concrete type for the
  // listed methods (calls inline), or Method itself (virtual calls) for any other.
  template <typename M>
  void walk_region(std::size_t index, const M& method, bool first_leg) {
    const Region& region = scene_.regions()[index];
    if constexpr (Mode == WalkMode::nearest && requires { method.leg(&region.fields, m_).sample(Texel{}); }) {
      // A method that works out once per leg what its nearest reading needs of the direction (offsets,
      // weights, the field): each step is then only the reading.
      const auto leg = method.leg(&region.fields, m_);
      // The texel the walk came from is sampled only where cd() pairs with it (a region's border, for the
      // methods that read along the motion): otherwise that sample was a sixth of a typical frame's work.
      // Inside the leg it is the texel before, whose owner is this region, so its sample is what the leg's
      // was (sample_owner reads it through the same method and fields).
      step_through<false>(index, first_leg,
                          [&](bool entered, FieldTexel at, const auto& from, bool observed) PH_ALWAYS_INLINE {
                            const TexelSample here = leg.sample(at);
                            TexelSample previous{};
                            if (cd_reads_from(method, here)) [[unlikely]]
                              previous = sample_owner(scene_, method, from() + corner_texel(region), m_);
                            return step_cd(region, method, previous, here, entered, observed);
                          });
    } else {
      TexelSample previous = sample_from(method);
      // A copy the compiler can keep in registers: what a method derives from the direction is then computed
      // once per leg, not per step (m_ could alias the walk's stores).
      const Vec2 m = m_;
      // Inlined, so that the samples stay in registers: an out-of-line call per step cost the depth method a
      // fifth of its typical frame.
      step_through<true>(index, first_leg,
                         [&, m](bool entered, FieldTexel, const auto&, bool observed) PH_ALWAYS_INLINE {
                           const TexelSample here = sample_here(region, method, m);
                           const double cd = step_cd(region, method, previous, here, entered, observed);
                           previous = here;
                           return cd;
                         });
    }
  }

  // The same with each texel's C/D from a direction table.
  void walk_region_lut(std::size_t index, const DirectionLut& lut, bool first_leg) {
    lut_k_ = lut.direction_index(m_);  // per table: regions may quantise into different numbers of directions
    const Region& region = scene_.regions()[index];
    step_through<true>(index, first_leg, [&](bool entered, FieldTexel, const auto&, bool) PH_ALWAYS_INLINE {
      return lut_cd(region, lut, entered);
    });
  }

  // C/D of the current texel from a direction table, shown to the observer as step_cd does.
  double lut_cd(const Region& region, const DirectionLut& lut, bool entered) {
    const double cd = lut.cd(lut_k_, region.local(texel_));
    if (observer_ != nullptr) observe_step(cd, empty_step_detail(), entered, region);
    return cd;
  }

  // The texel-stepping loop: spends the budget texel by texel while the texels belong to region `index`,
  // each at the C/D that cd_here(entered, at, from, observed) gives for the texel the walk is in (`at`: its place in
  // the region's fields; `from()`: the texel before it, region-local). It is called once per texel, in order, so it may
  // keep the previous texel's sample. The walk's state is kept in locals and written back to the members where the loop
  // ends: the stores of the bookkeeping through result_ may alias the members, so GCC kept every member in memory, a
  // load and a store each per step. A step only moves the field index, one boundary distance and the count of steps
  // left along its axis to the region's edge; the texel, the one before it and whether the neighbours behind lie in the
  // region follow from the counts. With Members, cd_here reads the members (the texel, the boundary distances), and
  // they are written before each call; otherwise only for an observer.
  template <bool Members, typename CdHere>
  PH_ALWAYS_INLINE void step_through(std::size_t index, bool first_leg, CdHere&& cd_here) {
    // Two copies of the loop, chosen once per leg: the one without an observer does not ask for one on every step.
    if (observer_ != nullptr) [[unlikely]] {
      step_through_observed<Members, true>(index, first_leg, cd_here);
    } else {
      step_through_observed<Members, false>(index, first_leg, cd_here);
    }
  }

  template <bool Members, bool Observed, typename CdHere>
  PH_ALWAYS_INLINE void step_through_observed(std::size_t index, bool first_leg, CdHere& cd_here) {
    const Region& region = scene_.regions()[index];
    const bool covered = scene_.covered(index);
    constexpr bool observed = Observed;
    const Texel corner = corner_texel(region), start = region.local(texel_), start_from = region.local(from_);
    // Every field of the region is rect.w texels wide: a step along y moves the index by a row.
    std::ptrdiff_t at = static_cast<std::ptrdiff_t>(start.y) * region.rect.w + start.x;
    const std::ptrdiff_t row_step = static_cast<std::ptrdiff_t>(sy_) * region.rect.w;
    double t = t_, tmx = tmx_, tmy = tmy_, budget = budget_;
    // The x- and y-steps the walk can take before it leaves the region's box (it starts inside), and how many
    // may be left at most for the neighbour behind along that axis to be inside too (not on the first column
    // or row the motion meets; any number along an axis the motion does not move along).
    std::int32_t x_left = steps_inside(start.x, region.rect.w, sx_);
    std::int32_t y_left = steps_inside(start.y, region.rect.h, sy_);
    const std::int32_t x_first = x_left, y_first = y_left;
    const std::int32_t x_behind = sx_ != 0 ? region.rect.w - 2 : std::numeric_limits<std::int32_t>::max();
    const std::int32_t y_behind = sy_ != 0 ? region.rect.h - 2 : std::numeric_limits<std::int32_t>::max();
    double cd_lo = kInf, cd_hi = -kInf;
    std::uint64_t steps = 0;
    bool last_along_x = false;
    const auto local = [&]() PH_ALWAYS_INLINE {
      return Texel{start.x + sx_ * (x_first - x_left), start.y + sy_ * (y_first - y_left)};
    };
    const auto from = [&]() PH_ALWAYS_INLINE {
      if (steps == 0) return start_from;
      const Texel here = local();
      return last_along_x ? Texel{here.x - sx_, here.y} : Texel{here.x, here.y - sy_};
    };
    const auto write_back = [&]() PH_ALWAYS_INLINE {
      const Texel here = local();
      texel_ = here + corner;
      if (steps == 0) {
        from_ = start_from + corner;
      } else {
        // from() by arithmetic: the axis of the leg's last step is random. (The same in from() itself, which
        // cd_here may call in the loop, made the curvature walk's flicks slower.)
        const std::int32_t along_x = static_cast<std::int32_t>(last_along_x);
        from_ = Texel{here.x - sx_ * along_x, here.y - sy_ * (1 - along_x)} + corner;
      }
      t_ = t;
      tmx_ = tmx;
      tmy_ = tmy;
    };
    const auto evaluate = [&](bool entered) PH_ALWAYS_INLINE {
      if (Members || observed) write_back();
      const FieldTexel here{static_cast<std::size_t>(at), x_left <= x_behind && y_left <= y_behind};
      const double cd = cd_here(entered, here, from, observed);
      cd_lo = std::min(cd_lo, cd);
      cd_hi = std::max(cd_hi, cd);
      return cd;
    };
    double cd = evaluate(!first_leg);
    bool left = false;
    for (;;) {
      const double t_next = std::min(tmx, tmy);
      const double cost = cd * (t_next - t);
      if (cost >= budget) {
        t += budget / cd;
        budget = 0.0;
        break;
      }
      budget -= cost;
      t = t_next;
      ++steps;
      last_along_x = tmx <= tmy;
      if (last_along_x) {
        at += sx_;
        tmx += tdx_;
        left = --x_left < 0;
      } else {
        at += row_step;
        tmy += tdy_;
        left = --y_left < 0;
      }
      if (left || (covered && scene_.owner(local() + corner) != index)) [[unlikely]] {
        left = true;  // another region or the flat outside takes over
        break;
      }
      cd = evaluate(true);
    }
    write_back();
    budget_ = budget;
    steps_ += steps;
    // Every C/D was 1 exactly when the least and the largest were (the methods' C/D is never NaN).
    all_unit_ = all_unit_ && cd_lo >= 1.0 && cd_hi <= 1.0;
    result_.cd_min = std::min(result_.cd_min, cd_lo);
    result_.cd_max = std::max(result_.cd_max, cd_hi);
    // Every texel of the leg but its first was entered, and the first too unless the frame started in it.
    result_.steps += static_cast<std::uint32_t>(steps - (left ? 1 : 0)) + (first_leg ? 0 : 1);
    if (left) restart_at(position());
  }

  // How many steps along one axis stay inside [0, size) from `cell` (inside it), moving by `step`.
  static std::int32_t steps_inside(std::int32_t cell, std::int32_t size, int step) {
    // Arithmetic, not a select: GCC made a branch of the select, and the sign of the motion is random.
    const std::int32_t forward = static_cast<std::int32_t>(step > 0);
    const std::int32_t moving = cell + forward * (size - 1 - 2 * cell);
    return step == 0 ? std::numeric_limits<std::int32_t>::max() : moving;
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

  EndPlace end_state() const {
    Vec2 p = position();
    p.x = std::clamp(p.x, static_cast<double>(texel_.x), static_cast<double>(texel_.x) + 1.0);
    p.y = std::clamp(p.y, static_cast<double>(texel_.y), static_cast<double>(texel_.y) + 1.0);
    return {p, texel_, from_};
  }

  const Scene& scene_;
  const Vec2 m_;
  StepObserver* const observer_;
  FrameResult& result_;
  const int sx_, sy_;
  const Mask2 forward_, still_;  // per axis: the motion's sign is positive; it is zero
  const double tdx_, tdy_;       // display travel per texel along x and y
  Texel texel_, from_;
  Vec2 origin_;                     // start of the current straight leg
  double t_ = 0.0;                  // display travel since origin_
  double tmx_ = kInf, tmy_ = kInf;  // display travel from origin_ to the next x / y texel boundary
  double budget_ = 0.0;             // motor travel left in the frame
  bool all_unit_ = true;
  std::uint64_t steps_ = 0;
  int lut_k_ = 0;         // lut: the frame's direction quantised for the current region's table
  double step_px_ = 1.0;  // bilinear: distance between the last two sample points
  Vec2 sample_point_;     // bilinear: where the last sample was taken (screen px)
};

}  // namespace

// True when the segment from the cursor by `motor` cannot touch any region: its bounding box misses
// every region's closed box (a few compares per region), and it stays well inside the world.
PH_ALWAYS_INLINE inline bool crosses_only_flat(const Scene& scene, const CursorState& cursor, Vec2 motor) {
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
  // Scene allows at most kMaxEffectsPerRegion effects; the bound is kept here too.
  const std::size_t count = std::min(region.effects.size(), kMaxEffectsPerRegion);
  for (std::size_t i = 0; i < count; ++i) {
    const Effect& effect = *region.effects[i];
    EffectState& state = cursor.effects[i];
    if (state.owner != &effect) state = EffectState{true, 0.0, kNoTime, &effect};
    const double given = fast_length(motor.x, motor.y);
    const Vec2 out = effect.apply({motor, time, cursor.position, region.local(cursor.texel)}, state);
    // The promise of every effect, kept here too: finite, and within its bounds of the motor it was given.
    const double length = fast_length(out.x, out.y);
    if (is_finite(out) && length <= given * effect.max_gain() * (1.0 + 1e-12) &&
        length >= given * effect.min_gain() * (1.0 - 1e-12)) {
      motor = out;
    }
  }
  const double after = fast_length(motor.x, motor.y);
  return before > 0.0 ? after / before : 1.0;
}

// The same out of line, for the frames the effects moved off every region (advance() has it inline).
PH_NO_SLP [[gnu::noinline]] FrameResult flat_frame_after_effects(CursorState& cursor, Vec2 motor) {
  return flat_frame(cursor, motor);
}

template <WalkMode Mode>
CursorState walk_texels(const Scene& scene, CursorState& cursor, Vec2 m, double d, StepObserver* observer,
                        FrameResult& result, bool& all_unit) {
  Walker<Mode> walker(scene, cursor, m, observer, result);
  const EndPlace end = walker.run(d);
  all_unit = walker.all_unit();
  return {end.position, end.texel, end.came_from, {}};
}

[[gnu::noinline]] CursorState walk_variant(const Scene& scene, const EngineOptions& options, CursorState& cursor,
                                           Vec2 m, double d, StepObserver* observer, FrameResult& result,
                                           bool& all_unit) {
  switch (options.traversal) {
    case Traversal::exact:
      return options.sampling == Sampling::bilinear
                 ? walk_texels<WalkMode::bilinear>(scene, cursor, m, d, observer, result, all_unit)
                 : walk_texels<WalkMode::nearest>(scene, cursor, m, d, observer, result, all_unit);
    case Traversal::direction_lut:
      return walk_texels<WalkMode::lut>(scene, cursor, m, d, observer, result, all_unit);
    case Traversal::unit_steps:
      return walk_unit_steps(scene, cursor, m, d, options.sampling, observer, result, all_unit);
    case Traversal::frame_midpoint:
      return walk_frame_midpoint(scene, cursor, m, d, options.sampling, observer, result, all_unit);
  }
  return walk_texels<WalkMode::nearest>(scene, cursor, m, d, observer, result, all_unit);
}

// The traversal proper: walks `motor` (finite, not zero) through the texels from the cursor.
FrameResult walk(const Scene& scene, CursorState& cursor, Vec2 motor, StepObserver* observer) {
  FrameResult result;
  double d = fast_length(motor.x, motor.y);
  // Divide rather than multiply by 1/d: for a denormal d, 1/d overflows and the walk would never advance.
  const Double2 direction = Double2{motor.x, motor.y} / splat(d);
  const Vec2 m{direction[0], direction[1]};
  if (!is_finite(m)) return result;
  if (d > kMaxMotorPx) {
    d = kMaxMotorPx;
    motor = m * d;
  }
  result.cd_min = kInf;
  result.cd_max = -kInf;
  const Vec2 start = cursor.position;
  bool all_unit = true;
  EndPlace end;
  const EngineOptions& options = scene.frame_options(cursor.texel);  // the region the frame starts in
  if (options.is_default()) [[likely]] {
    Walker<WalkMode::nearest> walker(scene, cursor, m, observer, result);
    end = walker.run(d);
    all_unit = walker.all_unit();
  } else {
    // One branch per frame, out of line.
    const CursorState variant_end = walk_variant(scene, options, cursor, m, d, observer, result, all_unit);
    end = {variant_end.position, variant_end.texel, variant_end.came_from};
  }
  if (all_unit) {
    // C/D was 1 everywhere: the display moves by the motor displacement itself, with no rounding.
    end.position = start + motor;
  }
  if (std::abs(end.position.x) > kWorldLimitPx || std::abs(end.position.y) > kWorldLimitPx ||
      !is_finite(end.position)) {
    const CursorState clamped = cursor_at(end.position);
    end = {clamped.position, clamped.texel, clamped.came_from};
  }
  if (result.cd_min > result.cd_max) result.cd_min = result.cd_max = 1.0;
  result.display = all_unit && end.position == start + motor ? motor : end.position - start;
  // Field by field, leaving the effects' state.
  cursor.position = end.position;
  cursor.texel = end.texel;
  cursor.came_from = end.came_from;
  return result;
}

// Everything else, out of line: the walk's set-up (a large stack frame, saved registers) would otherwise be
// paid by the flat frames too.
[[gnu::noinline]] FrameResult advance_through_regions(const Scene& scene, CursorState& cursor, Vec2 motor, TimeUs time,
                                                      StepObserver* observer) {
  const double gain = scene.has_effects() ? apply_effects(scene, cursor, motor, time) : 1.0;
  if (motor.x == 0.0 && motor.y == 0.0) return {};
  // advance() has found that this frame meets a region; the effects may have moved it off every region.
  FrameResult result = scene.has_effects() && crosses_only_flat(scene, cursor, motor)
                           ? flat_frame_after_effects(cursor, motor)
                           : walk(scene, cursor, motor, observer);
  if (gain != 1.0) {
    // The hand's motor travel was the frame's; the effects let only `gain` of it reach the walk.
    result.cd_min /= gain;
    result.cd_max /= gain;
  }
  return result;
}

}  // namespace

// Without SLP vectorisation, as flat_frame, which is inline here: a flat frame near a region then makes no call.
PH_NO_SLP FrameResult advance_near_regions(const Scene& scene, CursorState& cursor, Vec2 motor, TimeUs time,
                                           StepObserver* observer) {
  if (!is_finite(motor) || (motor.x == 0.0 && motor.y == 0.0)) return {};
  // A frame that starts in a region meets it (the cursor lies in its texel's closed box): the box test of every
  // region is only for the frames that start outside them all.
  if (!scene.has_effects() && !scene.owner(cursor.texel) && crosses_only_flat(scene, cursor, motor)) {
    return flat_frame(cursor, motor);
  }
  return advance_through_regions(scene, cursor, motor, time, observer);
}

}  // namespace ph
