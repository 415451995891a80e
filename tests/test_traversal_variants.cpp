// The traversal variants (core/engine/engine_options.hpp; docs/METHODS.md, "Traversal variants"): the invariants every
// variant keeps, and how far each ends from the exact traversal on the paper's targets (the bounds docs/METHODS.md
// gives).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>

#include "core/engine/direction_lut.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_flat.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"
#include "tests/split_stroke.hpp"
#include "tests/traversal_regions.hpp"

namespace ph {
namespace {

std::vector<EngineOptions> all_variants() { return all_engine_variants(); }

Scene scene_with(std::vector<Region> regions, const EngineOptions& options) {
  Scene scene(std::move(regions));
  scene.set_options(options);
  return scene;
}

TEST(EngineOptions, NamesRoundTrip) {
  for (Traversal t : kAllTraversals) EXPECT_EQ(parse_traversal(name_of(t)), t);
  for (Sampling s : kAllSamplings) EXPECT_EQ(parse_sampling(name_of(s)), s);
  EXPECT_EQ(parse_traversal("unit_steps"), Traversal::unit_steps);
  EXPECT_EQ(parse_sampling("bilinear"), Sampling::bilinear);
  EXPECT_FALSE(parse_traversal("Exact").has_value());
  EXPECT_FALSE(parse_sampling("").has_value());
  EXPECT_EQ(label_of({Traversal::direction_lut, Sampling::nearest, 8}), "direction_lut8");
  EXPECT_EQ(label_of({Traversal::unit_steps, Sampling::bilinear, 16}), "unit_steps+bilinear");
  EXPECT_TRUE(EngineOptions{}.is_default());
  ASSERT_EQ(all_engine_variants().size(), 8u);
  EXPECT_EQ(all_engine_variants()[0], EngineOptions{});
  for (const EngineOptions& o : all_engine_variants()) EXPECT_EQ(validate(o), "") << label_of(o);
  EXPECT_EQ(validate(EngineOptions{}), "");
  EXPECT_NE(validate({Traversal::direction_lut, Sampling::nearest, 12}), "");
  EXPECT_NE(validate({Traversal::direction_lut, Sampling::bilinear, 16}), "");
  Scene scene;
  EXPECT_THROW(scene.set_options({Traversal::exact, Sampling::nearest, 0}), std::invalid_argument);
}

TEST(TraversalVariants, FlatScenesAreExactIdentity) {
  for (const EngineOptions& options : all_variants()) {
    std::vector<Region> regions;
    regions.push_back(gradient_region({0, 0, 800, 600}, {0.0f, 0.0f}));
    regions.push_back(depth_region({300, 200, 900, 700}, [](int, int) { return 42.0f; }));
    regions.push_back(gradient_region({-50, 400, 100, 100}, {0.0f, 0.0f}));
    const Scene scene = scene_with(std::move(regions), options);
    std::mt19937_64 rng(2);
    CursorState cursor = cursor_at({400.0, 300.0});
    Vec2 expected = cursor.position;
    for (int i = 0; i < 20000; ++i) {
      const Vec2 motor = random_motion(rng);
      const FrameResult out = advance(scene, cursor, motor);
      expected = expected + motor;
      ASSERT_EQ(out.display, motor) << label_of(options) << " frame " << i;
      ASSERT_EQ(cursor.position, expected) << label_of(options) << " frame " << i;
    }
  }
}

TEST(TraversalVariants, TinyMotionsOverRegionsAreNotLost) {
  // Lengths whose squares underflow to 0, down to the smallest denormal: the identity holds for them too.
  for (const EngineOptions& options : all_variants()) {
    const Scene scene = scene_with({depth_region({0, 0, 64, 64}, [](int, int) { return 3.0f; })}, options);
    for (const Vec2 motor : {Vec2{1e-165, 0.0}, Vec2{0.0, -1e-200}, Vec2{1e-300, 2e-300}, Vec2{-5e-324, 5e-324}}) {
      CursorState cursor = cursor_at({20.5, 30.5});
      const FrameResult out = advance(scene, cursor, motor);
      EXPECT_EQ(out.display, motor) << label_of(options) << " " << motor.x << "," << motor.y;
      EXPECT_EQ(cursor.position, (Vec2{20.5, 30.5} + motor)) << label_of(options);
    }
  }
}

// Summed display along the motion over a region where C/D is `cd` for every step in direction m.
void expect_ratio(const Scene& scene, Vec2 start, Vec2 m, double cd, double cd_tolerance, const std::string& what) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  CursorState cursor = cursor_at(start);
  // Already moving this way, so that the first texel has a neighbour behind it.
  cursor.came_from = texel_at(start - m);
  double motor_sum = 0.0, travelled = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double step = u(rng);
    motor_sum += step;
    const FrameResult out = advance(scene, cursor, m * step);
    travelled += out.display.x * m.x + out.display.y * m.y;
    ASSERT_NEAR(out.cd_min, cd, cd_tolerance) << what << " frame " << i;
    ASSERT_NEAR(out.cd_max, cd, cd_tolerance) << what << " frame " << i;
  }
  // Every frame's display is its motor travel / cd, so the sums agree to rounding, not just to 1 px.
  EXPECT_NEAR(travelled, motor_sum / cd, 1e-6 * motor_sum + cd_tolerance * motor_sum) << what;
  EXPECT_NEAR(length(cursor.position - start), motor_sum / cd, 1e-6 * motor_sum + cd_tolerance * motor_sum) << what;
}

TEST(TraversalVariants, ConstantSlopeGivesMotorOverCd) {
  const double s = 1.0 / std::sqrt(2.0);
  for (const EngineOptions& options : all_variants()) {
    const std::string name = label_of(options);
    // The lut's codes are good to (30 - 1) / 65534 = 4.4e-4 with the curvature method's default bounds.
    const double tol = options.traversal == Traversal::direction_lut ? 5e-4 : 1e-12;
    // Curvature: uphill along +x at slope 0.5: C/D = 1 - a (k'max - 1), a = -0.5 / sqrt(1.25).
    const double up = 1.0 + 0.5 / std::sqrt(1.25) * 3.0;
    expect_ratio(scene_with({gradient_region({0, 0, 3000, 5}, {0.5f, 0.0f})}, options), {1.5, 2.5}, {1.0, 0.0}, up, tol,
                 name + " curvature +x");
    // Downhill along -y, and diagonally (a quantised direction for 8 and 16 directions).
    const double down = 1.0 - 0.5 / std::sqrt(1.25) * (1.0 - 1.0 / 1.5);
    expect_ratio(scene_with({gradient_region({0, 0, 5, 3000}, {0.0f, 0.5f})}, options), {2.5, 2998.5}, {0.0, -1.0},
                 down, tol, name + " curvature -y");
    const double t = 0.5 * s + 0.25 * s, diag = 1.0 + t / std::sqrt(1.0 + t * t) * 3.0;
    expect_ratio(scene_with({gradient_region({0, 0, 800, 800}, {0.5f, 0.25f})}, options), {10.5, 10.25}, {s, s}, diag,
                 std::max(tol, 1e-9), name + " curvature diagonal");
    // Depth: h = 0.05 x, C/D = 1 + 3 * 0.05 (float heights: a step's change is good to about 1e-4 px).
    expect_ratio(scene_with({depth_region({0, 0, 3000, 5}, [](int x, int) { return 0.05f * float(x); })}, options),
                 {1.5, 2.5}, {1.0, 0.0}, 1.15, 3e-4, name + " depth +x");
    // Depth on a diagonal: the height change per px along the motion, (h_x + h_y) / sqrt 2, and not per
    // 4-neighbour step of the texel walk ((h_x + h_y) / 2 on average, which made C/D 1.1125 here).
    const double along = (0.05 + 0.025) * s;
    expect_ratio(
        scene_with({depth_region({0, 0, 800, 800}, [](int x, int y) { return 0.05f * float(x) + 0.025f * float(y); })},
                   options),
        {10.5, 10.25}, {s, s}, 1.0 + 3.0 * along, 3e-4, name + " depth diagonal");
  }
}

// End-position distance to the exact traversal (px) after 500 px strokes in frames of 0.3-12.3 px: the
// worst and the mean over 288 strokes per variant and method. Measured (seeded, so deterministic) and
// documented in docs/METHODS.md ("Traversal variants"); the bounds are about 1.5 times the measurement.
// These are distances to the exact walk, not errors against the surface (tests/test_tool_accuracy.cpp).
struct Bound {
  double curvature_worst, curvature_mean, depth_worst, depth_mean;
};
const std::map<std::string, Bound> kEndBounds = {
    {"exact", {1e-9, 1e-9, 1e-9, 1e-9}},         {"exact+bilinear", {69.0, 2.7, 6.6, 0.35}},
    {"unit_steps", {11.5, 0.55, 4.5, 0.28}},     {"unit_steps+bilinear", {36.0, 1.6, 7.7, 0.42}},
    {"frame_midpoint", {26.0, 1.9, 17.0, 1.4}},  {"frame_midpoint+bilinear", {34.0, 2.1, 19.0, 1.4}},
    {"direction_lut8", {97.0, 7.4, 136.0, 9.6}}, {"direction_lut16", {67.0, 4.5, 71.0, 5.6}},
};

TEST(TraversalVariants, EndPositionsStayNearTheExactTraversalOnAllTargets) {
  const Vec2 offset{37.0, 53.0};
  for (bool depth : {false, true}) {
    // Each target's region made once (rasterising a target is a third of the test's time) and copied per variant.
    std::vector<Region> targets;
    std::vector<Scene> exact_scenes;
    for (const TargetSpec& spec : all_targets()) {
      targets.push_back(target_region(spec, offset, depth));
      exact_scenes.push_back(scene_with({targets.back()}, {}));
    }
    for (const EngineOptions& options : all_variants()) {
      const std::string name = label_of(options);
      std::mt19937_64 rng(6);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      double worst = 0.0, sum = 0.0;
      int strokes = 0;
      for (std::size_t i = 0; i < all_targets().size(); ++i) {
        const Scene scene = scene_with({targets[i]}, options);
        const Method& method = *scene.regions()[0].method;
        for (int k = 0; k < 12; ++k) {
          const double phi = 2.0 * std::numbers::pi * (k + u(rng)) / 12.0;
          const Vec2 m{std::cos(phi), std::sin(phi)};
          const Vec2 start = offset + Vec2{500.0 * u(rng), 500.0 * u(rng)};
          CursorState exact = cursor_at(start), variant = cursor_at(start);
          double left = 500.0;
          while (left > 0.0) {
            const double step = std::min(left, 0.3 + 12.0 * u(rng));
            advance(exact_scenes[i], exact, m * step);
            const FrameResult out = advance(scene, variant, m * step);
            ASSERT_GE(out.cd_min, method.cd_lower_bound()) << name;
            ASSERT_LE(out.cd_max, method.cd_upper_bound()) << name;
            left -= step;
          }
          const double error = length(variant.position - exact.position);
          worst = std::max(worst, error);
          sum += error;
          ++strokes;
        }
      }
      const Bound bound = kEndBounds.at(name);
      std::printf("%-24s %-9s worst %8.3f px  mean %8.3f px over %d strokes\n", name.c_str(),
                  depth ? "depth" : "curvature", worst, sum / strokes, strokes);
      EXPECT_LE(worst, depth ? bound.depth_worst : bound.curvature_worst) << name << (depth ? " depth" : " curvature");
      EXPECT_LE(sum / strokes, depth ? bound.depth_mean : bound.curvature_mean)
          << name << (depth ? " depth" : " curvature");
    }
  }
}

TEST(TraversalVariants, TexelWalksDoNotDependOnHowAFrameIsSplit) {
  const TargetSpec spec = all_targets()[9];
  for (const EngineOptions& options : {EngineOptions{Traversal::exact, Sampling::bilinear, 16},
                                       EngineOptions{Traversal::direction_lut, Sampling::nearest, 16}}) {
    for (bool depth : {false, true}) {
      const Scene scene = scene_with({target_region(spec, {0, 0}, depth)}, options);
      std::mt19937_64 rng(8);
      for (int trial = 0; trial < 100; ++trial) {
        const SplitStroke s = split_stroke(scene, rng);
        ASSERT_LT(length(s.whole.position - s.pieces.position), 1e-6) << label_of(options) << " trial " << trial;
      }
    }
  }
}

TEST(TraversalVariants, NoNaNOrInfinityForAnyInput) {
  const Vec2 inputs[] = {{0, 0},         {NAN, 1},    {1, INFINITY},   {-INFINITY, INFINITY}, {1e6, -1e6},
                         {1e300, 1e300}, {1e-300, 0}, {5e-324, 0},     {-3.5, 2.25},          {0.001, -0.0007},
                         {1e6, 0.0},     {0.0, -1e6}, {5e-324, 5e-324}};
  for (const EngineOptions& options : all_variants()) {
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const Scene scene = scene_with(hostile_regions(rng), options);
    CursorState cursor = cursor_at({40.0, 40.0});
    std::uniform_int_distribution<int> pick(0, std::size(inputs) - 1);
    for (int i = 0; i < 30000; ++i) {
      Vec2 motor = inputs[pick(rng)];
      if (i % 3 == 0) motor = random_motion(rng);
      const FrameResult out = advance(scene, cursor, motor);
      ASSERT_TRUE(is_finite(out.display)) << label_of(options) << " " << i;
      ASSERT_TRUE(is_finite(cursor.position)) << label_of(options) << " " << i;
      ASSERT_TRUE(std::isfinite(out.cd_min) && std::isfinite(out.cd_max)) << label_of(options) << " " << i;
      ASSERT_LE(std::abs(cursor.position.x), kWorldLimitPx);
      ASSERT_LE(std::abs(cursor.position.y), kWorldLimitPx);
      if (i % 1000 == 0) cursor = cursor_at({40.0 + u(rng) * 40, 40.0 + u(rng) * 40});
    }
    CursorState still = cursor_at({10.0, 10.0});
    for (Vec2 bad : {Vec2{NAN, 0}, Vec2{0, INFINITY}, Vec2{0, 0}}) {
      EXPECT_EQ(advance(scene, still, bad).display, (Vec2{0, 0})) << label_of(options);
      EXPECT_EQ(still.position, (Vec2{10.0, 10.0})) << label_of(options);
    }
  }
}

// Halves every frame's motor displacement.
class Half final : public Effect {
 public:
  std::string_view name() const override { return "half"; }
  Vec2 apply(const EffectInput& in, EffectState&) const override { return in.motor * 0.5; }
  double min_gain() const override { return 0.5; }
  double max_gain() const override { return 0.5; }
  std::size_t bytes() const override { return 0; }
};

TEST(TraversalVariants, EffectsActBeforeEveryVariant) {
  for (const EngineOptions& options : all_variants()) {
    Region region = gradient_region({0, 0, 400, 400}, {0.0f, 0.0f});
    region.effects.push_back(std::make_shared<Half>());
    const Scene scene = scene_with({std::move(region)}, options);
    CursorState cursor = cursor_at({200.5, 200.5});
    const FrameResult out = advance(scene, cursor, {3.0, -4.0});
    EXPECT_EQ(out.display, (Vec2{1.5, -2.0})) << label_of(options);
    EXPECT_EQ(out.cd_max, 2.0) << label_of(options);  // the hand's travel over the display's
  }
}

TEST(TraversalVariants, DirectionTablesExistOnlyWhenSelected) {
  std::vector<Region> regions;
  regions.push_back(gradient_region({0, 0, 50, 40}, {0.5f, 0.0f}));
  regions.push_back(depth_region({100, 0, 30, 20}, [](int x, int) { return float(x); }));
  Region flat;
  flat.name = "flat";
  flat.rect = {0, 100, 70, 70};
  flat.method = std::make_shared<FlatMethod>();
  regions.push_back(std::move(flat));
  Scene scene(std::move(regions));
  const std::size_t base = scene.bytes();
  EXPECT_EQ(scene.lut_bytes(), 0u);
  EXPECT_EQ(scene.direction_lut(0), nullptr);
  for (Traversal t : {Traversal::exact, Traversal::unit_steps, Traversal::frame_midpoint}) {
    scene.set_options({t, Sampling::bilinear, 16});
    EXPECT_EQ(scene.lut_bytes(), 0u) << name_of(t);
  }
  scene.set_options({Traversal::direction_lut, Sampling::nearest, 16});
  EXPECT_EQ(scene.lut_bytes(), (50u * 40u + 30u * 20u) * 16u * 2u);  // int16 per texel and direction
  EXPECT_EQ(scene.bytes(), base + scene.lut_bytes());
  ASSERT_NE(scene.direction_lut(0), nullptr);
  ASSERT_NE(scene.direction_lut(1), nullptr);
  EXPECT_EQ(scene.direction_lut(2), nullptr);  // the flat method has no table: the exact walk handles it
  scene.set_options({Traversal::direction_lut, Sampling::nearest, 8});
  EXPECT_EQ(scene.lut_bytes(), (50u * 40u + 30u * 20u) * 8u * 2u);
  scene.set_options({});
  EXPECT_EQ(scene.lut_bytes(), 0u);
  EXPECT_EQ(scene.bytes(), base);
}

TEST(DirectionLut, QuantisesDirectionsAndCodesCdAroundOne) {
  DirectionLut lut(2, 1, 16, 0.2, 30.0);
  EXPECT_EQ(lut.direction_index({1.0, 0.0}), 0);
  EXPECT_EQ(lut.direction_index({0.0, 1.0}), 4);
  EXPECT_EQ(lut.direction_index({-1.0, 0.0}), 8);
  EXPECT_EQ(lut.direction_index({0.0, -1.0}), 12);
  EXPECT_EQ(lut.direction_index({std::cos(0.1), std::sin(-0.1)}), 0);
  EXPECT_EQ(lut.direction(4), (Vec2{0.0, 1.0}));
  for (double cd : {1.0, 0.2, 30.0, 0.5, 1.0001, 7.3}) {
    lut.set(3, {1, 0}, cd);
    EXPECT_NEAR(lut.cd(3, {1, 0}), cd, 29.0 / 65534 + 1e-15) << cd;
  }
  lut.set(3, {1, 0}, 1.0);
  EXPECT_EQ(lut.cd(3, {1, 0}), 1.0);
  lut.set(3, {1, 0}, 1e9);
  EXPECT_EQ(lut.cd(3, {1, 0}), 30.0);
  lut.set(3, {1, 0}, NAN);
  EXPECT_EQ(lut.cd(3, {1, 0}), 1.0);
}

// Three regions side by side, one overlapping the next: curvature on a random normal map; the hybrid on a wavy surface
// with a cliff (marked discontinuities) over part of it; depth on random heights right of the hybrid.
Scene lut_reference_scene() {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Region> regions;
  Region curvature = gradient_region({0, 0, 40, 30}, {});
  for (Gradient& g : curvature.fields.gradient->values) g = {u(rng), u(rng)};
  regions.push_back(std::move(curvature));
  Region hybrid;
  hybrid.name = "hybrid";
  hybrid.rect = {30, 10, 40, 30};
  hybrid.fields.gradient = GradientField(40, 30, Gradient{});
  hybrid.fields.depth = DepthField(40, 30, 0.0f);
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 40; ++x) {
      const double wave = 3.0 * std::sin(0.3 * x) * std::cos(0.2 * y);
      hybrid.fields.depth->at(x, y) = static_cast<float>(wave + (x >= 20 ? 8.0 : 0.0));
      hybrid.fields.gradient->at(x, y) = {static_cast<float>(0.9 * std::cos(0.3 * x) * std::cos(0.2 * y)),
                                          static_cast<float>(-0.6 * std::sin(0.3 * x) * std::sin(0.2 * y))};
    }
  }
  hybrid.method = std::make_shared<HybridMethod>(HybridParams{});
  regions.push_back(std::move(hybrid));
  regions.push_back(depth_region({70, 12, 20, 20}, [](int x, int y) { return float((x * 7 + y * 13) % 5); }));
  return Scene(std::move(regions));
}

// The table's entry for texel p and direction k is the method's C/D of entering p from the texel behind it, each read
// through the method's virtual interface: from the region's own fields inside it, from whatever lies there beyond
// its edge (another region, or the flat outside).
TEST(DirectionLut, EachEntryIsTheMethodsCdFromTheTexelBehind) {
  Scene scene = lut_reference_scene();
  ASSERT_TRUE(scene.regions()[1].fields.discontinuity);
  const std::vector<std::uint8_t>& marks = scene.regions()[1].fields.discontinuity->values;
  ASSERT_GT(std::count_if(marks.begin(), marks.end(), [](std::uint8_t mark) { return mark != 0; }), 0);
  for (int directions : {8, 16}) {
    scene.set_options({Traversal::direction_lut, Sampling::nearest, directions});
    for (std::size_t i = 0; i < scene.regions().size(); ++i) {
      const Region& region = scene.regions()[i];
      const Method& method = *region.method;
      const DirectionLut* lut = scene.direction_lut(i);
      ASSERT_NE(lut, nullptr);
      DirectionLut expected(region.rect.w, region.rect.h, directions, method.cd_lower_bound(), method.cd_upper_bound());
      int differ = 0;
      for (int k = 0; k < directions; ++k) {
        const Vec2 m = lut->direction(k);
        const int dx = static_cast<int>(std::floor(0.5 - m.x)), dy = static_cast<int>(std::floor(0.5 - m.y));
        for (int y = 0; y < region.rect.h; ++y) {
          for (int x = 0; x < region.rect.w; ++x) {
            const Texel behind{x + dx, y + dy};
            TexelSample from;
            if (behind.x >= 0 && behind.x < region.rect.w && behind.y >= 0 && behind.y < region.rect.h) {
              from = method.sample(&region.fields, behind, m);
            } else {
              const Texel screen{region.rect.x + behind.x, region.rect.y + behind.y};
              const std::optional<std::size_t> owner = scene.owner(screen);
              from = owner ? method.sample(&scene.regions()[*owner].fields, scene.regions()[*owner].local(screen), m)
                           : method.sample(nullptr, {}, m);
            }
            const TexelSample here = method.sample(&region.fields, {x, y}, m);
            expected.set(k, {x, y}, method.cd(from, here, std::hypot(dx, dy), nullptr));
            if (lut->cd(k, {x, y}) != expected.cd(k, {x, y})) ++differ;
          }
        }
      }
      EXPECT_EQ(differ, 0) << region.name << ", " << directions << " directions";
    }
  }
}

}  // namespace
}  // namespace ph
