// The exact per-texel traversal (docs/METHODS.md, "The traversal") against its invariants and against an
// independent reference integral.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"
#include "tests/split_stroke.hpp"
#include "tests/traversal_regions.hpp"

namespace ph {
namespace {

Scene scene_of(std::vector<Region> regions) { return Scene(std::move(regions)); }

void expect_identity(const Scene& scene, Vec2 start, std::uint64_t seed, int frames) {
  std::mt19937_64 rng(seed);
  CursorState cursor = cursor_at(start);
  Vec2 expected = start;
  for (int i = 0; i < frames; ++i) {
    const Vec2 motor = random_motion(rng);
    const FrameResult out = advance(scene, cursor, motor);
    expected = expected + motor;
    ASSERT_EQ(out.display.x, motor.x) << "frame " << i;
    ASSERT_EQ(out.display.y, motor.y) << "frame " << i;
    ASSERT_EQ(cursor.position.x, expected.x) << "frame " << i;
    ASSERT_EQ(cursor.position.y, expected.y) << "frame " << i;
  }
}

TEST(Traversal, EmptySceneOutputEqualsInputExactly) { expect_identity(Scene{}, {960.5, 540.25}, 1, 100000); }

TEST(Traversal, FlatRegionsOutputEqualsInputExactly) {
  std::vector<Region> regions;
  regions.push_back(gradient_region({0, 0, 800, 600}, {0.0f, 0.0f}));
  regions.push_back(depth_region({300, 200, 900, 700}, [](int, int) { return 42.0f; }));
  regions.push_back(gradient_region({-50, 400, 100, 100}, {0.0f, 0.0f}));
  expect_identity(scene_of(std::move(regions)), {400.0, 300.0}, 2, 100000);
}

// Summed output / summed input along one direction over a constant C/D field.
// cd_tolerance: per-step C/D error allowed by how the field is stored.
void expect_constant_ratio(const Scene& scene, Vec2 start, Vec2 direction, double cd, int frames, std::uint64_t seed,
                           double cd_tolerance = 1e-12) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  // A cursor that was already moving this way, so that its first texel too has a neighbour behind it
  // (with no history the depth method sees no height change in the first texel).
  CursorState cursor = cursor_at(start);
  cursor.came_from = {cursor.texel.x - static_cast<int>(direction.x), cursor.texel.y - static_cast<int>(direction.y)};
  double motor_sum = 0.0;
  Vec2 display_sum;
  for (int i = 0; i < frames; ++i) {
    const double step = u(rng);
    motor_sum += step;
    const FrameResult out = advance(scene, cursor, direction * step);
    display_sum = display_sum + out.display;
    ASSERT_NEAR(out.cd_min, cd, cd_tolerance);
    ASSERT_NEAR(out.cd_max, cd, cd_tolerance);
  }
  const double travelled = display_sum.x * direction.x + display_sum.y * direction.y;
  EXPECT_NEAR(travelled, motor_sum / cd, 1.0);
  EXPECT_NEAR(length(cursor.position - start), motor_sum / cd, 1.0);
  EXPECT_GT(motor_sum, 0.9 * frames);
}

TEST(Traversal, ConstantSlopeCurvatureSumsToInputOverCd) {
  // Uphill along +x at slope 0.5: a = -0.5 / sqrt(1.25) in every texel, delta-beta 0, C/D = 1 - a (k'max - 1).
  const double a = -0.5 / std::sqrt(1.25);
  const double cd = 1.0 - a * 3.0;
  const Scene along_x = scene_of({gradient_region({0, 0, 100000, 3}, {0.5f, 0.0f})});
  expect_constant_ratio(along_x, {1.5, 1.5}, {1.0, 0.0}, cd, 100000, 3);
  // Downhill along -y (the surface rises toward +y).
  const double cd_down = 1.0 - 0.5 / std::sqrt(1.25) * (1.0 - 1.0 / 1.5);
  const Scene along_y = scene_of({gradient_region({0, 0, 3, 160000}, {0.0f, 0.5f})});
  expect_constant_ratio(along_y, {1.5, 159998.5}, {0.0, -1.0}, cd_down, 100000, 4);
}

TEST(Traversal, ConstantSlopeDepthSumsToInputOverCd) {
  // h = 0.05 x: C/D = 1 + 3 * 0.05 in every step.
  const Scene ramp =
      scene_of({depth_region({0, 0, 12000, 3}, [](int x, int) { return 0.05f * static_cast<float>(x); })});
  // Heights are floats: up to 600 px here, so a step's height change is good to about 1e-4 px.
  expect_constant_ratio(ramp, {1.5, 1.5}, {1.0, 0.0}, 1.15, 10000, 5, 3e-4);
}

// Independent reference: enumerate every grid-line crossing of the ray in order, take each interval's
// texel from its midpoint, and integrate C/D x length in long double until the motor budget is spent.
Vec2 reference_end(const Scene& scene, Vec2 p, Vec2 m, double budget) {
  auto sample = [&](const Method& method, Texel t) {
    const auto owner = scene.owner(t);
    if (!owner) return method.sample(nullptr, {}, m);
    const Region& r = scene.regions()[*owner];
    return method.sample(&r.fields, r.local(t), m);
  };
  auto next_crossing = [](double pos, double dir, long k) {
    return dir > 0 ? (std::floor(pos) + k - pos) / dir : dir < 0 ? (pos - (std::ceil(pos) - k)) / -dir : INFINITY;
  };
  long kx = 1, ky = 1;
  long double spent = 0.0L;
  double t0 = 0.0;
  Texel prev = texel_at(p);
  for (;;) {
    const double tx = next_crossing(p.x, m.x, kx), ty = next_crossing(p.y, m.y, ky);
    const double t1 = std::min(tx, ty);
    if (t1 == tx) ++kx;
    if (t1 == ty) ++ky;
    if (t1 <= t0) continue;
    const Vec2 mid = p + m * (0.5 * (t0 + t1));
    const Texel cur = texel_at(mid);
    double cd = 1.0;
    if (const auto owner = scene.owner(cur)) {
      const Method& method = *scene.regions()[*owner].method;
      cd = method.cd(sample(method, prev), sample(method, cur), 1.0, nullptr);
    }
    const long double cost = static_cast<long double>(cd) * (t1 - t0);
    if (spent + cost >= budget) {
      const double t_end = t0 + static_cast<double>((budget - spent) / cd);
      return p + m * t_end;
    }
    spent += cost;
    t0 = t1;
    prev = cur;
  }
}

TEST(Traversal, MatchesReferenceIntegralOnAllTargets) {
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec2 offset{37.0, 53.0};
  int strokes = 0;
  double worst = 0.0;
  for (const TargetSpec& spec : all_targets()) {
    for (bool depth : {false, true}) {
      const Scene scene = scene_of({target_region(spec, offset, depth)});
      for (int k = 0; k < 12; ++k) {
        const double phi = 2.0 * std::numbers::pi * (k + u(rng)) / 12.0;
        const Vec2 m{std::cos(phi), std::sin(phi)};
        // Start anywhere in the target, so that the strokes cross bumps, rims and the flat outside.
        const Vec2 start = offset + Vec2{500.0 * u(rng), 500.0 * u(rng)};
        const Vec2 want = reference_end(scene, start, m, 500.0);
        CursorState cursor = cursor_at(start);
        double left = 500.0;
        while (left > 0.0) {
          const double step = std::min(left, 0.3 + 12.0 * u(rng));
          advance(scene, cursor, m * step);
          left -= step;
        }
        const double error = length(cursor.position - want);
        worst = std::max(worst, error);
        ASSERT_LT(error, 0.01) << spec.name() << (depth ? " depth" : " curvature") << " direction " << phi;
        ++strokes;
      }
    }
  }
  RecordProperty("worst_error_px", std::to_string(worst));
  std::printf("%d strokes of 500 px, worst end-position error %.3g px\n", strokes, worst);
}

TEST(Traversal, SplittingAFrameDoesNotMoveTheEnd) {
  const TargetSpec spec = all_targets()[9];  // bump, gaussian
  const Scene scene = scene_of({target_region(spec, {0, 0}, false)});
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 200; ++trial) {
    const SplitStroke s = split_stroke(scene, rng);
    ASSERT_LT(length(s.whole.position - s.pieces.position), 1e-9);
    ASSERT_EQ(s.whole.texel, s.pieces.texel);
  }
}

class Recorder final : public StepObserver {
 public:
  void on_step(const StepRecord& s) override { steps.push_back(s); }
  std::vector<StepRecord> steps;
};

TEST(Traversal, EnteringARegionFromTheFlatOutsideIsAStep) {
  const Scene scene = scene_of({gradient_region({100, 0, 50, 50}, {0.5f, 0.0f})});
  CursorState cursor = cursor_at({90.25, 10.5});
  Recorder rec;
  advance(scene, cursor, {20.0, 0.0}, &rec);
  ASSERT_FALSE(rec.steps.empty());
  const StepRecord& entry = rec.steps.front();
  EXPECT_EQ(entry.texel, (Texel{100, 10}));
  EXPECT_EQ(entry.came_from, (Texel{99, 10}));
  EXPECT_TRUE(entry.entered);
  EXPECT_DOUBLE_EQ(entry.entry.x, 100.0);
  // Flat (a = 0, theta = 0) to slope 0.5: delta-beta = -atan(0.5) in degrees, clamped kmax = 1: no slowdown.
  const double theta = std::atan(0.5), a = -std::sin(theta);
  EXPECT_DOUBLE_EQ(entry.cd, curvature_cd(CurvatureParams{}, 0.0, 0.0, a, theta, nullptr));
  // The next texel has the same slope as the one it comes from: the full uphill C/D.
  EXPECT_DOUBLE_EQ(rec.steps[1].cd, 1.0 - a * 3.0);
  // 9.75 px of flat travel, then the remaining 10.25 px of motor spent at C/D >= 1.
  EXPECT_GT(cursor.position.x, 100.0);
  EXPECT_LT(cursor.position.x, 110.25);
}

// Where the texel entered has no neighbour behind in its own region, the step pairs it with the texel the walk came
// from, in the region it came from (the walk samples that texel only for such steps).
TEST(Traversal, CurvatureStepIntoARegionPairsWithTheRegionItCameFrom) {
  std::vector<Region> regions;
  regions.push_back(gradient_region({0, 0, 100, 50}, {1.0f, 0.0f}));
  regions.push_back(gradient_region({100, 0, 100, 50}, {0.5f, 0.0f}));
  const Scene scene = scene_of(std::move(regions));
  CursorState cursor = cursor_at({98.5, 10.5});
  Recorder rec;
  advance(scene, cursor, {20.0, 0.0}, &rec);
  const auto entry = std::find_if(rec.steps.begin(), rec.steps.end(), [](const StepRecord& s) {
    return s.texel == Texel{100, 10};
  });
  ASSERT_NE(entry, rec.steps.end());
  EXPECT_EQ(entry->came_from, (Texel{99, 10}));
  // Slope 1 behind, 0.5 here: delta-beta > 0 and kmax at its upper limit (to fast_atan's accuracy). Paired with
  // the flat outside's sample instead (a1 = theta1 = 0), delta-beta < 0 and the step would get C/D 1.
  const double theta1 = std::atan(1.0), theta2 = std::atan(0.5);
  EXPECT_NEAR(entry->cd, curvature_cd(CurvatureParams{}, -std::sin(theta1), theta1, -std::sin(theta2), theta2, nullptr),
              1e-6);
  EXPECT_GT(entry->cd, 10.0);
}

TEST(Traversal, DepthStepIntoARegionPairsWithTheRegionItCameFrom) {
  std::vector<Region> regions;
  regions.push_back(depth_region({0, 0, 100, 50}, [](int, int) { return 5.0f; }));
  regions.push_back(depth_region({100, 0, 100, 50}, [](int, int) { return 5.2f; }));
  const Scene scene = scene_of(std::move(regions));
  CursorState cursor = cursor_at({90.5, 10.5});
  Recorder rec;
  advance(scene, cursor, {20.0, 0.0}, &rec);
  const auto entry = std::find_if(rec.steps.begin(), rec.steps.end(), [](const StepRecord& s) {
    return s.texel == Texel{100, 10};
  });
  ASSERT_NE(entry, rec.steps.end());
  // A height change of 0.2 px over the 1 px step from the last texel of the first region (not 5.2 from the flat).
  EXPECT_DOUBLE_EQ(entry->cd, depth_cd(DepthParams{}, 5.0, static_cast<double>(5.2f), 1.0, nullptr));
  EXPECT_LT(entry->cd, DepthParams{}.kmax);
}

TEST(Traversal, TopmostRegionGoverns) {
  // Two overlapping regions of different slope; the later one lies on top.
  std::vector<Region> regions;
  regions.push_back(gradient_region({0, 0, 400, 100}, {0.5f, 0.0f}));
  regions.push_back(gradient_region({100, 0, 100, 100}, {1.0f, 0.0f}));
  const Scene scene = scene_of(std::move(regions));
  CursorState cursor = cursor_at({120.5, 50.5});
  const FrameResult out = advance(scene, cursor, {10.0, 0.0});
  const double a = -1.0 / std::sqrt(2.0);
  EXPECT_DOUBLE_EQ(out.cd_min, 1.0 - a * 3.0);
  EXPECT_DOUBLE_EQ(out.cd_max, 1.0 - a * 3.0);
  EXPECT_EQ(scene.owner({150, 50}), 1u);
  EXPECT_EQ(scene.owner({250, 50}), 0u);
  EXPECT_FALSE(scene.owner({450, 50}).has_value());
}

// A walk through a region that a later one overlaps looks up each texel's owner; one through a region nothing
// overlaps does not need to (Scene::covered).
TEST(Traversal, AWalkThroughACoveredRegionHandsOverToTheRegionAbove) {
  std::vector<Region> regions;
  regions.push_back(gradient_region({0, 0, 400, 100}, {0.5f, 0.0f}));
  regions.push_back(gradient_region({100, 40, 100, 20}, {1.0f, 0.0f}));
  regions.push_back(gradient_region({600, 0, 50, 50}, {1.0f, 0.0f}));
  const Scene scene = scene_of(std::move(regions));
  EXPECT_TRUE(scene.covered(0));
  EXPECT_FALSE(scene.covered(1));
  EXPECT_FALSE(scene.covered(2));
  CursorState cursor = cursor_at({50.5, 50.5});
  Recorder rec;
  advance(scene, cursor, {600.0, 0.0}, &rec);  // uphill all the way: it ends near x = 273
  ASSERT_GT(cursor.position.x, 250.0);
  int on_top = 0;
  for (const StepRecord& step : rec.steps) {
    const bool inside_top = step.texel.x >= 100 && step.texel.x < 200;
    EXPECT_EQ(step.region, inside_top ? &scene.regions()[1] : &scene.regions()[0]) << "texel x " << step.texel.x;
    on_top += inside_top ? 1 : 0;
  }
  EXPECT_EQ(on_top, 100);
}

TEST(Scene, EveryFieldMustMatchTheRegion) {
  Region region = gradient_region({0, 0, 10, 10}, {0.5f, 0.0f});
  region.fields.depth = DepthField(9, 10);  // not read by the curvature method, but the walk indexes every field alike
  std::vector<Region> regions;
  regions.push_back(std::move(region));
  EXPECT_THROW(scene_of(std::move(regions)), std::invalid_argument);
}

TEST(Traversal, FlatOutsideIsCrossedInOneJump) {
  // A 10^6 px flick across a small region far away costs as many steps as the region is wide.
  const Scene scene = scene_of({gradient_region({500000, 0, 20, 20}, {0.5f, 0.0f})});
  CursorState cursor = cursor_at({0.5, 10.5});
  const FrameResult out = advance(scene, cursor, {1e6, 0.0});
  EXPECT_LE(out.steps, 21u);
  EXPECT_GT(out.cd_max, 1.0);
  EXPECT_GT(cursor.position.x, 500020.0);
  EXPECT_LT(cursor.position.x, 1e6);
}

TEST(Traversal, NoNaNOrInfinityForAnyInput) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const Scene scene = scene_of(hostile_regions(rng));
  const Vec2 inputs[] = {{0, 0},         {NAN, 1},    {1, INFINITY}, {-INFINITY, INFINITY}, {1e6, -1e6},
                         {1e300, 1e300}, {1e-300, 0}, {5e-324, 0},   {-3.5, 2.25},          {0.001, -0.0007}};
  CursorState cursor = cursor_at({40.0, 40.0});
  std::uniform_int_distribution<int> pick(0, std::size(inputs) - 1);
  for (int i = 0; i < 200000; ++i) {
    Vec2 motor = inputs[pick(rng)];
    if (i % 3 == 0) motor = random_motion(rng);
    const FrameResult out = advance(scene, cursor, motor);
    ASSERT_TRUE(is_finite(out.display)) << i;
    ASSERT_TRUE(is_finite(cursor.position)) << i;
    ASSERT_TRUE(std::isfinite(out.cd_min) && std::isfinite(out.cd_max)) << i;
    ASSERT_LE(std::abs(cursor.position.x), kWorldLimitPx);
    if (i % 1000 == 0) cursor = cursor_at({40.0 + u(rng) * 40, 40.0 + u(rng) * 40});  // come back to the texture
  }
  // Non-finite and zero motions do not move the cursor.
  CursorState still = cursor_at({10.0, 10.0});
  for (Vec2 bad : {Vec2{NAN, 0}, Vec2{0, INFINITY}, Vec2{0, 0}}) {
    const FrameResult out = advance(scene, still, bad);
    EXPECT_EQ(out.display, (Vec2{0, 0}));
    EXPECT_EQ(still.position, (Vec2{10.0, 10.0}));
  }
}

TEST(Traversal, SubPixelMotionAccumulates) {
  const Scene scene = scene_of({gradient_region({0, 0, 100, 10}, {0.5f, 0.0f})});
  CursorState cursor = cursor_at({10.5, 5.5});
  for (int i = 0; i < 100000; ++i) advance(scene, cursor, {1e-4, 0.0});
  const double cd = 1.0 + 0.5 / std::sqrt(1.25) * 3.0;
  EXPECT_NEAR(cursor.position.x - 10.5, 10.0 / cd, 1e-6);
}

TEST(Cursor, WorldLimitKeepsTexelIndicesValid) {
  CursorState c = cursor_at({1e300, -1e300});
  EXPECT_EQ(c.position.x, kWorldLimitPx);
  EXPECT_EQ(c.position.y, -kWorldLimitPx);
  for (int i = 0; i < 300; ++i) advance(Scene{}, c, {kMaxMotorPx, kMaxMotorPx});
  EXPECT_LE(c.position.x, kWorldLimitPx);
  EXPECT_EQ(c.texel, texel_at(c.position));
}

}  // namespace
}  // namespace ph

namespace ph {
namespace {

// A method outside core/engine/methods.hpp's list (no tag), so the traversal reaches it through the virtual
// interface only. Its C/D is `base` + `to_weight` x the entered texel's height + `from_weight` x the height of
// the texel it was entered from, with the heights of the region's depth field (0 outside every region).
class PluginMethod final : public Method {
 public:
  PluginMethod(double base, double to_weight, double from_weight, double lo, double hi)
      : base_(base), to_weight_(to_weight), from_weight_(from_weight), lo_(lo), hi_(hi) {}
  std::string_view name() const override { return "plug-in"; }
  FieldNeeds needs() const override { return {.gradient = false, .depth = true}; }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2) const override {
    if (fields == nullptr || !fields->depth) return {0.0, 0.0};
    return {fields->depth->at(local.x, local.y), 0.0};
  }
  double cd(const TexelSample& from, const TexelSample& to, double, StepDetail* detail) const override {
    ++calls;
    if (detail != nullptr) *detail = empty_step_detail();
    return base_ + to_weight_ * to.v0 + from_weight_ * from.v0;
  }
  double cd_lower_bound() const override { return lo_; }
  double cd_upper_bound() const override { return hi_; }
  mutable std::size_t calls = 0;

 private:
  double base_, to_weight_, from_weight_, lo_, hi_;
};

Region plugin_region(Rect rect, std::shared_ptr<const PluginMethod> method, float (*height)(int x, int y)) {
  Region r = depth_region(rect, height);
  r.name = "plug-in";
  r.method = std::move(method);
  return r;
}

TEST(Traversal, PluginMethodThroughTheVirtualInterface) {
  {
    SCOPED_TRACE("constant C/D 2 halves the display travel, exactly");
    auto two = std::make_shared<const PluginMethod>(2.0, 0.0, 0.0, 2.0, 2.0);
    ASSERT_EQ(two->tag(), nullptr);  // not in core/engine/methods.hpp's list
    const Scene scene = scene_of({plugin_region({0, 0, 1000, 1000}, two, [](int, int) { return 0.0f; })});
    // Dyadic starts and motions along the axes and the diagonal: every half is exact.
    const Vec2 motions[] = {{10.0, 0.0}, {0.0, -7.25}, {-3.5, 0.0}, {6.0, 6.0}, {-0.125, 0.0625}, {300.0, -200.0}};
    CursorState cursor = cursor_at({400.5, 600.25});
    Vec2 expected = cursor.position;
    for (const Vec2 motor : motions) {
      const FrameResult out = advance(scene, cursor, motor);
      EXPECT_EQ(out.display.x, motor.x / 2.0) << motor.x << "," << motor.y;
      EXPECT_EQ(out.display.y, motor.y / 2.0) << motor.x << "," << motor.y;
      EXPECT_EQ(out.cd_min, 2.0);
      EXPECT_EQ(out.cd_max, 2.0);
      expected = expected + motor * 0.5;
    }
    EXPECT_EQ(cursor.position.x, expected.x);
    EXPECT_EQ(cursor.position.y, expected.y);
    // Along an axis, a whole stroke of random frames: the display travel is the motor travel / 2.
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0.0, 3.0);
    const Scene strip = scene_of({plugin_region({0, 499, 8000, 3}, two, [](int, int) { return 0.0f; })});
    CursorState walker = cursor_at({10.5, 500.5});
    double motor_sum = 0.0, display_sum = 0.0;
    for (int i = 0; i < 5000; ++i) {
      const double step = u(rng);
      motor_sum += step;
      display_sum += advance(strip, walker, {step, 0.0}).display.x;
    }
    EXPECT_NEAR(display_sum, motor_sum / 2.0, 1e-9);
    EXPECT_NEAR(walker.position.x - 10.5, motor_sum / 2.0, 1e-9);
    EXPECT_EQ(walker.position.y, 500.5);
    EXPECT_GT(two->calls, 3000u);  // per texel, through the virtual cd()
  }
  {
    SCOPED_TRACE("C/D from the texel and its predecessor: the independent integral");
    // Heights 0..4 in a pattern; C/D = 0.5 + 0.3 h(to) + 0.1 h(from), in [0.5, 2.1]. Outside: flat, C/D 1.
    auto varying = std::make_shared<const PluginMethod>(0.5, 0.3, 0.1, 0.5, 2.1);
    auto pattern = [](int x, int y) { return static_cast<float>((x * 7 + y * 3) % 5); };
    const Vec2 offset{40.0, 30.0};
    const Scene scene = scene_of({plugin_region({40, 30, 200, 150}, varying, pattern)});
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double worst = 0.0;
    for (int k = 0; k < 48; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + u(rng)) / 48.0;
      const Vec2 m{std::cos(phi), std::sin(phi)};
      // Starts inside and around the region: strokes enter, cross and leave it.
      const Vec2 start = offset + Vec2{-20.0 + 240.0 * u(rng), -20.0 + 190.0 * u(rng)};
      const double budget = 150.0;
      const Vec2 want = reference_end(scene, start, m, budget);
      CursorState cursor = cursor_at(start);
      double left = budget;
      while (left > 0.0) {
        const double step = std::min(left, 0.2 + 9.0 * u(rng));
        advance(scene, cursor, m * step);
        left -= step;
      }
      const double error = length(cursor.position - want);
      worst = std::max(worst, error);
      ASSERT_LT(error, 1e-6) << "direction " << phi << " from " << start.x << "," << start.y;
    }
    // The reference really did see C/D other than 1 and 2: a stroke over the region ends short of or beyond
    // where a flat one would.
    const Vec2 start = offset + Vec2{10.5, 70.5};
    const Vec2 end = reference_end(scene, start, {1.0, 0.0}, 100.0);
    EXPECT_GT(std::abs(end.x - start.x - 100.0), 1.0);
    RecordProperty("worst_error_px", std::to_string(worst));
  }
}

}  // namespace
}  // namespace ph
