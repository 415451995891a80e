// Gravity wells (core/effects/effect_wells.hpp): on analytic fields whose patterns are circles (a paraboloid's
// contours, a sphere's isophote), motion toward the pattern is faster, away slower, tangential about
// unchanged; nothing happens beyond R (bit for bit); the gain stays within its bounds; snap pulls onto
// the pattern and a push away still escapes; wells layer on a C/D method; no random scene traps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/effects/effect_wells.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_flat.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/traversal.hpp"
#include "core/lab/surfaces.hpp"

namespace ph {
namespace {

constexpr std::int32_t kSize = 128;
constexpr double kCentre = 64.0;  // of the circles, region px
constexpr double kCircle = 30.0;  // radius of the paraboloid's contour

// h = -r² / 64 around the centre: its contour at -kCircle² / 64 is the circle of radius kCircle.
DepthField paraboloid() {
  DepthField d(kSize, kSize);
  for (std::int32_t y = 0; y < kSize; ++y) {
    for (std::int32_t x = 0; x < kSize; ++x) {
      const double dx = x + 0.5 - kCentre;
      const double dy = y + 0.5 - kCentre;
      d.at(x, y) = static_cast<float>(-(dx * dx + dy * dy) / 64.0);
    }
  }
  return d;
}

RegionFields paraboloid_fields() {
  RegionFields f;
  f.depth = paraboloid();
  f.gradient = gradient_from_depth(*f.depth);
  return f;
}

WellsParams circle_contour(double radius_px = 16.0) {
  WellsParams p;
  p.pattern = WellPattern::contours;
  p.contours.levels = {-kCircle * kCircle / 64.0};
  p.radius_px = radius_px;
  return p;
}

// Distance of a region point from the contour circle.
double off_circle(Vec2 local) { return std::abs(std::hypot(local.x - kCentre, local.y - kCentre) - kCircle); }

// The input advance() gives an effect for a cursor at `local` in a region whose corner is `origin`.
EffectInput input_at(Vec2 local, Vec2 motor, Texel origin = {0, 0}) {
  return {motor, kNoTime, {local.x + origin.x, local.y + origin.y}, texel_at(local)};
}

double gain(const Effect& e, Vec2 local, Vec2 motor) {
  EffectState state;
  return length(e.apply(input_at(local, motor), state)) / length(motor);
}

Region region_with(Rect rect, RegionFields fields, MethodPtr method, std::vector<EffectPtr> effects) {
  Region r;
  r.name = "wells";
  r.rect = rect;
  r.fields = std::move(fields);
  r.method = std::move(method);
  r.effects = std::move(effects);
  return r;
}

TEST(Wells, TowardTheContourIsFasterAwaySlowerTangentialAboutUnchanged) {
  const EffectPtr e = make_wells_effect(paraboloid_fields(), kSize, kSize, circle_contour());
  // 8.3 px outside the circle on the +x axis: the pattern lies toward -x.
  const Vec2 p{kCentre + kCircle + 8.3, kCentre + 0.2};
  const double toward = gain(*e, p, {-2.0, 0.0});
  const double away = gain(*e, p, {2.0, 0.0});
  const double tangential = gain(*e, p, {0.0, 2.0});
  EXPECT_GT(toward, 1.3);
  EXPECT_LT(away, 0.7);
  EXPECT_NEAR(tangential, 1.0, 0.05);
  // The pull fades with distance: nearer the pattern, toward is faster.
  double last = e->max_gain() + 1.0;
  for (double d : {1.2, 4.0, 8.0, 12.0, 15.0}) {
    const double g = gain(*e, {kCentre + kCircle + d, kCentre + 0.5}, {-1.0, 0.0});
    EXPECT_LT(g, last) << d;
    EXPECT_GT(g, 1.0) << d;
    last = g;
  }
  // Inside the circle, too: toward is outward there.
  EXPECT_GT(gain(*e, {kCentre + kCircle - 6.0, kCentre + 0.5}, {1.0, 0.0}), 1.3);
  EXPECT_LT(gain(*e, {kCentre + kCircle - 6.0, kCentre + 0.5}, {-1.0, 0.0}), 0.8);
}

TEST(Wells, ASpheresIsophoteIsACircleThatAttracts) {
  const SurfaceSpec sphere{SurfaceKind::sphere, kSize};
  RegionFields fields;
  fields.gradient = surface_gradient_field(sphere);
  WellsParams p;
  p.pattern = WellPattern::isophotes;
  p.isophotes.light = {0.0, 0.0, 1.0};
  const double r = 40.0;
  const double big_r = 3.0 * sphere.half_size();                       // the sphere's radius
  p.isophotes.cos_alpha = std::sqrt(1.0 - (r / big_r) * (r / big_r));  // n·l = cos alpha at radius r
  p.radius_px = 20.0;
  ASSERT_EQ(wells_needs(p).gradient, true);
  ASSERT_EQ(wells_needs(p).depth, false);
  const EffectPtr e = make_wells_effect(fields, kSize, kSize, p);
  for (double angle : {0.3, 1.9, 4.0}) {
    const Vec2 radial{std::cos(angle), std::sin(angle)};
    const Vec2 at = Vec2{kCentre, kCentre} + radial * (r + 7.0);
    EXPECT_GT(gain(*e, at, radial * -1.0), 1.3) << angle;
    EXPECT_LT(gain(*e, at, radial), 0.8) << angle;
  }
  // Far inside and outside: nothing.
  EXPECT_EQ(gain(*e, {kCentre + 0.5, kCentre + 0.5}, {1.0, 0.0}), 1.0);
}

TEST(Wells, BeyondTheRadiusAndOnThePatternTheMotorIsUnchangedBitForBit) {
  const RegionFields fields = paraboloid_fields();
  const EffectPtr e = make_wells_effect(fields, kSize, kSize, circle_contour(8.0));
  const Vec2 motor{0.123456789, -3.3e-3};
  EffectState state;
  for (const Vec2 p : {Vec2{kCentre + 0.5, kCentre + 0.5}, Vec2{2.5, 3.5}, Vec2{kCentre + kCircle + 8.5, kCentre}}) {
    const Vec2 out = e->apply(input_at(p, motor), state);
    EXPECT_EQ(out.x, motor.x);
    EXPECT_EQ(out.y, motor.y);
  }
  // Through advance() on a flat region: the display is the motor itself.
  const Rect rect{300, 200, kSize, kSize};
  const Scene scene({region_with(rect, fields, std::make_shared<FlatMethod>(), {e})});
  CursorState cursor = cursor_at({300.0 + 10.25, 200.0 + 10.75});
  const FrameResult result = advance(scene, cursor, motor);
  EXPECT_EQ(result.display.x, motor.x);
  EXPECT_EQ(result.display.y, motor.y);
  // No level inside the field's range: no pattern anywhere.
  WellsParams none = circle_contour();
  none.contours.levels = {1000.0};
  const EffectPtr empty = make_wells_effect(fields, kSize, kSize, none);
  for (std::int32_t y = 0; y < kSize; y += 7) {
    for (std::int32_t x = 0; x < kSize; x += 7) {
      const Vec2 out = empty->apply(input_at({x + 0.3, y + 0.6}, motor), state);
      EXPECT_TRUE(out == motor);
    }
  }
  EXPECT_EQ(state.owner, nullptr) << "stateless";
  EXPECT_EQ(state.travel_px, 0.0);
}

TEST(Wells, TheGainStaysWithinItsBoundsAndWithoutSnapKeepsTheDirection) {
  const RegionFields fields = paraboloid_fields();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(0.0, kSize - 1e-9);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
  std::uniform_real_distribution<double> log_len(-6.0, 6.0);
  for (const double snap : {0.0, 10.0}) {
    WellsParams p = circle_contour(24.0);
    p.strength = 6.0;
    p.max_gain = 3.0;
    p.min_gain = 0.3;
    p.snap_px = snap;
    p.snap_fraction = 0.15;
    const EffectPtr e = make_wells_effect(fields, kSize, kSize, p);
    EXPECT_DOUBLE_EQ(e->min_gain(), snap > 0.0 ? 0.15 : 0.3);
    EXPECT_DOUBLE_EQ(e->max_gain(), snap > 0.0 ? 3.15 : 3.0);
    for (int i = 0; i < 20000; ++i) {
      const double a = angle(rng);
      const Vec2 motor = Vec2{std::cos(a), std::sin(a)} * std::pow(10.0, log_len(rng));
      EffectState state;
      const Vec2 out = e->apply(input_at({pos(rng), pos(rng)}, motor), state);
      ASSERT_TRUE(is_finite(out));
      const double g = length(out) / length(motor);
      ASSERT_GE(g, e->min_gain() * (1.0 - 1e-12));
      ASSERT_LE(g, e->max_gain() * (1.0 + 1e-12));
      if (snap == 0.0) {
        ASSERT_NEAR((motor.x * out.y - motor.y * out.x) / (length(motor) * length(out)), 0.0, 1e-12);
        ASSERT_GT(motor.x * out.x + motor.y * out.y, 0.0);
      }
    }
  }
}

TEST(Wells, SnapPullsOntoThePatternAndASustainedPushAwayEscapes) {
  const RegionFields fields = paraboloid_fields();
  WellsParams p = circle_contour(16.0);
  p.snap_px = 6.0;
  p.snap_fraction = 0.25;
  const Rect rect{0, 0, kSize, kSize};
  const Scene scene(
      {region_with(rect, fields, std::make_shared<FlatMethod>(), {make_wells_effect(fields, kSize, kSize, p)})});
  // 4.5 px outside the circle, jiggling the hand along it: the cursor ends on the contour.
  CursorState cursor = cursor_at({kCentre + kCircle + 4.5, kCentre + 0.5});
  for (int i = 0; i < 40; ++i) advance(scene, cursor, {0.0, i % 2 == 0 ? 1.0 : -1.0});
  EXPECT_LT(off_circle(cursor.position), 1.0);
  // Beyond snap_px the same jiggle leaves the cursor's distance about where it was.
  cursor = cursor_at({kCentre + kCircle + 9.0, kCentre + 0.5});
  for (int i = 0; i < 40; ++i) advance(scene, cursor, {0.0, i % 2 == 0 ? 1.0 : -1.0});
  EXPECT_NEAR(off_circle(cursor.position), 9.0, 0.5);
  // From on the contour, a steady push straight away: out of the well within R / (min_gain - snap_fraction)
  // of motor travel.
  cursor = cursor_at({kCentre + kCircle + 0.5, kCentre + 0.5});
  double travel = 0.0;
  while (off_circle(cursor.position) < p.radius_px + 1.0) {
    advance(scene, cursor, {0.5, 0.0});
    travel += 0.5;
    ASSERT_LE(travel, (p.radius_px + 1.0) / (p.min_gain - p.snap_fraction) + 1.0);
  }
  // A steady push along the pattern goes along it, and leaves the region too.
  cursor = cursor_at({kCentre + kCircle + 0.5, kCentre + 0.5});
  travel = 0.0;
  while (scene.owner(cursor.texel)) {
    advance(scene, cursor, {0.0, 1.0});
    travel += 1.0;
    ASSERT_LE(travel, kSize / (p.min_gain - p.snap_fraction) + 2.0);
  }
}

TEST(Wells, LayeredOnCurvatureTheRegionWalksTheRescaledMotor) {
  const RegionFields fields = paraboloid_fields();
  WellsParams p = circle_contour(20.0);
  p.snap_px = 5.0;
  const EffectPtr e = make_wells_effect(fields, kSize, kSize, p);
  const auto method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  const Rect rect{200, 100, kSize, kSize};
  const Scene with({region_with(rect, fields, method, {e})});
  const Scene twin({region_with(rect, fields, method, {})});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(0.0, kSize);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
  std::uniform_real_distribution<double> len(0.3, 12.0);
  int rescaled = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec2 start{rect.x + pos(rng), rect.y + pos(rng)};
    const double a = angle(rng);
    const Vec2 motor = Vec2{std::cos(a), std::sin(a)} * len(rng);
    CursorState c1 = cursor_at(start);
    CursorState c2 = cursor_at(start);
    EffectState state;
    const Vec2 scaled = e->apply({motor, kNoTime, c1.position, with.regions()[0].local(c1.texel)}, state);
    const FrameResult r1 = advance(with, c1, motor);
    const FrameResult r2 = advance(twin, c2, scaled);
    ASSERT_EQ(r1.display.x, r2.display.x) << i;
    ASSERT_EQ(r1.display.y, r2.display.y) << i;
    ASSERT_EQ(c1.position.x, c2.position.x);
    ASSERT_EQ(c1.position.y, c2.position.y);
    ASSERT_EQ(r1.steps, r2.steps);
    if (!(scaled == motor)) {
      ++rescaled;
      // C/D is the hand's travel over the display's: the wells' gain divides the method's.
      const double g = length(scaled) / length(motor);
      ASSERT_NEAR(r1.cd_max, r2.cd_max / g, 1e-9 * r1.cd_max);
    }
  }
  EXPECT_GT(rescaled, 300);
}

// A random relief: a few Gaussian bumps and holes on a tilted plane, heights in px.
DepthField random_relief(std::mt19937& rng, std::int32_t w, std::int32_t h) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Bump {
    double x, y, s, a;
  };
  std::vector<Bump> bumps(1 + rng() % 4);
  for (Bump& b : bumps) b = {u(rng) * w, u(rng) * h, 5.0 + u(rng) * 40.0, (u(rng) - 0.5) * 80.0};
  const double tx = (u(rng) - 0.5) * 0.6;
  const double ty = (u(rng) - 0.5) * 0.6;
  DepthField d(w, h);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      double v = tx * x + ty * y;
      for (const Bump& b : bumps) {
        v += b.a * std::exp(-((x - b.x) * (x - b.x) + (y - b.y) * (y - b.y)) / (2.0 * b.s * b.s));
      }
      d.at(x, y) = static_cast<float>(v);
    }
  }
  return d;
}

WellsParams random_params(std::mt19937& rng, const DepthField& depth) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  WellsParams p;
  p.pattern = rng() % 2 == 0 ? WellPattern::isophotes : WellPattern::contours;
  p.isophotes.light = {u(rng) - 0.5, u(rng) - 0.5, 0.2 + u(rng)};
  p.isophotes.cos_alpha = 0.6 + 0.4 * u(rng);
  p.isophotes.rule = rng() % 2 == 0 ? PatternRule::crossing : PatternRule::band;
  p.isophotes.tol = 0.05 * u(rng);
  p.contours.rule = rng() % 2 == 0 ? PatternRule::crossing : PatternRule::band;
  p.contours.tol = 2.0 * u(rng);
  if (rng() % 2 == 0) {
    p.contours.count = static_cast<std::int32_t>(rng() % 16);
  } else {
    const auto [lo, hi] = std::minmax_element(depth.values.begin(), depth.values.end());
    for (int k = 0; k < 1 + static_cast<int>(rng() % 6); ++k) p.contours.levels.push_back(*lo + (*hi - *lo) * u(rng));
  }
  p.radius_px = kWellsMinRadiusPx + u(rng) * 63.0;
  p.strength = u(rng) * kWellsMaxStrength;
  p.max_gain = 1.0 + u(rng) * (kWellsMaxGainLimit - 1.0);
  p.min_gain = kWellsMinGainLimit + u(rng) * (1.0 - kWellsMinGainLimit);
  p.snap_px = rng() % 2 == 0 ? 0.0 : u(rng) * p.radius_px;
  p.snap_fraction = u(rng) * p.min_gain / 2.0;
  return p;
}

// No trap: every frame moves the cursor along the push by at least min_gain() of its motor travel (snap
// takes at most snap_fraction, which validate() keeps within min_gain / 2), so a push in direction m
// leaves a w x h region within (w |m_x| + h |m_y|) / min_gain() of motor travel, plus a frame or two.
TEST(Wells, NoRandomSceneTrapsASustainedPush) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const auto w = static_cast<std::int32_t>(20 + rng() % 140);
    const auto h = static_cast<std::int32_t>(20 + rng() % 140);
    RegionFields fields;
    fields.depth = random_relief(rng, w, h);
    fields.gradient = gradient_from_depth(*fields.depth);
    const WellsParams p = random_params(rng, *fields.depth);
    ASSERT_EQ(validate(p), "");
    const EffectPtr e = make_wells_effect(fields, w, h, p);
    ASSERT_GT(e->min_gain(), 0.0);
    const Rect rect{static_cast<std::int32_t>(rng() % 500), static_cast<std::int32_t>(rng() % 500), w, h};
    const Scene scene({region_with(rect, fields, std::make_shared<FlatMethod>(), {e})});
    for (int push = 0; push < 8; ++push) {
      const double a = 2.0 * std::numbers::pi * u(rng);
      const Vec2 dir{std::cos(a), std::sin(a)};
      CursorState cursor = cursor_at({rect.x + u(rng) * w, rect.y + u(rng) * h});
      const double extent = w * std::abs(dir.x) + h * std::abs(dir.y);
      const double bound = extent / e->min_gain() + 2.0 * 4.0;
      double travel = 0.0;
      while (scene.owner(cursor.texel)) {
        const double step = 0.2 + 3.8 * u(rng);
        const FrameResult r = advance(scene, cursor, dir * step);
        travel += step;
        ASSERT_TRUE(is_finite(cursor.position) && is_finite(r.display));
        ASSERT_GE(length(r.display), step * e->min_gain() * (1.0 - 1e-9));
        ASSERT_LE(length(r.display), step * e->max_gain() * (1.0 + 1e-9));
        ASSERT_LE(travel, bound) << "trapped: trial " << trial << " push " << push;
      }
    }
  }
}

TEST(Wells, AreDeterministic) {
  const RegionFields fields = paraboloid_fields();
  WellsParams p = circle_contour(20.0);
  p.snap_px = 4.0;
  const EffectPtr a = make_wells_effect(fields, kSize, kSize, p);
  const EffectPtr b = make_wells_effect(fields, kSize, kSize, p);
  const auto& fa = static_cast<const WellsEffect&>(*a).field();
  const auto& fb = static_cast<const WellsEffect&>(*b).field();
  ASSERT_EQ(fa.offsets.values.size(), fb.offsets.values.size());
  for (std::size_t i = 0; i < fa.offsets.values.size(); ++i) {
    ASSERT_EQ(fa.offsets.values[i].dx, fb.offsets.values[i].dx);
    ASSERT_EQ(fa.offsets.values[i].dy, fb.offsets.values[i].dy);
  }
  const Rect rect{10, 10, kSize, kSize};
  const Scene sa({region_with(rect, fields, std::make_shared<FlatMethod>(), {a})});
  const Scene sb({region_with(rect, fields, std::make_shared<FlatMethod>(), {b})});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-3.0, 3.0);
  CursorState ca = cursor_at({80.3, 70.1});
  CursorState cb = ca;
  for (int i = 0; i < 5000; ++i) {
    const Vec2 m{d(rng), d(rng)};
    advance(sa, ca, m, TimeUs{i * 1000});
    advance(sb, cb, m, TimeUs{i * 1000});
    ASSERT_EQ(ca.position.x, cb.position.x);
    ASSERT_EQ(ca.position.y, cb.position.y);
    if (!sa.owner(ca.texel)) ca = cb = cursor_at({80.3, 70.1});
  }
}

TEST(Wells, ReloadingOtherLevelsMovesTheWells) {
  const RegionFields fields = paraboloid_fields();
  const EffectPtr at30 = make_wells_effect(fields, kSize, kSize, circle_contour());
  WellsParams p = circle_contour();
  p.contours.levels = {-40.0 * 40.0 / 64.0};
  const EffectPtr at40 = make_wells_effect(fields, kSize, kSize, p);
  const Vec2 at{kCentre + 35.5, kCentre + 0.5};  // between the two circles
  EXPECT_GT(gain(*at30, at, {-1.0, 0.0}), 1.2);  // toward r = 30
  EXPECT_LT(gain(*at40, at, {-1.0, 0.0}), 0.8);  // away from r = 40
  EXPECT_EQ(at30->bytes(), sizeof(PatternOffset) * kSize * kSize);
}

TEST(Wells, ValidateNamesTheParameterAndItsRange) {
  EXPECT_EQ(validate(WellsParams{}), "");
  auto message = [](auto change) {
    WellsParams p;
    change(p);
    return validate(p);
  };
  EXPECT_EQ(message([](WellsParams& p) { p.radius_px = 0.5; }), "wells radius_px must be in [1, 1024] (got 0.5)");
  EXPECT_EQ(message([](WellsParams& p) { p.strength = std::numeric_limits<double>::quiet_NaN(); }),
            "wells strength must be in [0, 10] (got nan)");
  EXPECT_EQ(message([](WellsParams& p) { p.max_gain = 0.9; }), "wells max_gain must be in [1, 4] (got 0.9)");
  EXPECT_EQ(message([](WellsParams& p) { p.min_gain = 0.05; }), "wells min_gain must be in [0.1, 1] (got 0.05)");
  EXPECT_EQ(message([](WellsParams& p) { p.snap_px = 17.0; }), "wells snap_px must be in [0, 16] (got 17)");
  EXPECT_EQ(message([](WellsParams& p) { p.snap_fraction = 0.3; }),
            "wells snap_fraction must be in [0, 0.25] (got 0.3)");
  EXPECT_NE(message([](WellsParams& p) { p.isophotes.cos_alpha = 1.5; }).find("cos_alpha"), std::string::npos);
  EXPECT_NE(message([](WellsParams& p) { p.isophotes.light = {0, 0, 0}; }).find("light"), std::string::npos);
  EXPECT_EQ(message([](WellsParams& p) { p.isophotes.light = {1e300, 1e300, 1e300}; }), "");  // finite, non-zero
  EXPECT_NE(message([](WellsParams& p) {
              p.contours.levels = {1.0, std::numeric_limits<double>::infinity()};
            }).find("levels"),
            std::string::npos);
  EXPECT_NE(message([](WellsParams& p) { p.contours.count = -1; }).find("count"), std::string::npos);
  EXPECT_NE(message([](WellsParams& p) { p.contours.tol = -1; }).find("contour tolerance"), std::string::npos);
  WellsParams bad;
  bad.max_gain = 5.0;
  EXPECT_THROW(make_wells_effect(paraboloid_fields(), kSize, kSize, bad), std::invalid_argument);
}

TEST(Wells, NeedTheFieldTheirPatternReads) {
  WellsParams contours = circle_contour();
  EXPECT_TRUE(wells_needs(contours).depth);
  EXPECT_FALSE(wells_needs(contours).gradient);
  RegionFields gradient_only;
  gradient_only.gradient = gradient_from_depth(paraboloid());
  EXPECT_THROW(make_wells_effect(gradient_only, kSize, kSize, contours), std::invalid_argument);
  RegionFields depth_only;
  depth_only.depth = paraboloid();
  EXPECT_THROW(make_wells_effect(depth_only, kSize, kSize, WellsParams{}), std::invalid_argument);
  EXPECT_THROW(make_wells_effect(depth_only, kSize + 1, kSize, contours), std::invalid_argument);
  EXPECT_NO_THROW(make_wells_effect(depth_only, kSize, kSize, contours));
}

}  // namespace
}  // namespace ph
