// The ground truth of core/lab/ground_truth against closed forms, its own convergence, and the engine.
#include "core/lab/ground_truth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "core/engine/methods.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"

namespace ph {
namespace {

// An unbounded plane h = g . p: the slope along any direction is constant, so C/D is constant.
class Plane final : public AnalyticSurface {
 public:
  explicit Plane(ExactGradient g) : g_(g) {}
  double height(Vec2 p) const override { return g_.x * p.x + g_.y * p.y; }
  ExactGradient gradient(Vec2) const override { return g_; }
  void breakpoints(Vec2, Vec2, double, double, std::vector<double>&) const override {}

 private:
  ExactGradient g_;
};

// The two methods the truth is checked with, with their default parameters.
const CurvatureMethod kCurvature{CurvatureParams{}};
const DepthMethod kDepth{DepthParams{}};
const Method* const kMethods[] = {&kCurvature, &kDepth};

// The curvature method's C/D for a step from slope t1 to slope t2 along the motion.
double cd_of_slopes(const CurvatureParams& p, double t1, double t2) {
  return curvature_cd(p, -t1 / std::sqrt(1 + t1 * t1), std::atan(t1), -t2 / std::sqrt(1 + t2 * t2), std::atan(t2),
                      nullptr);
}

TEST(GroundTruth, TargetSurfaceIsTheTargetInDoublePrecision) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(0.0, 500.0);
  for (const TargetSpec& spec : all_targets()) {
    const auto surface = make_target_surface(spec);
    for (int i = 0; i < 2000; ++i) {
      const Vec2 p{coord(rng), coord(rng)};
      ASSERT_EQ(surface->height(p), target_height(spec, p)) << spec.name();
      const ExactGradient g = surface->gradient(p);
      const Gradient want = target_gradient(spec, p);
      ASSERT_EQ(static_cast<float>(g.x), want.x) << spec.name();
      ASSERT_EQ(static_cast<float>(g.y), want.y) << spec.name();
    }
  }
}

TEST(GroundTruth, PlaneGivesConstantCdAndDisplayIsMotorOverCd) {
  const Plane plane({0.3, -0.2});
  for (const Method* method : kMethods) {
    const TruthModel model{&plane, method};
    for (double angle_deg : {0.0, 30.0, 90.0, 200.0, 333.0}) {
      const double a = angle_deg * std::acos(-1.0) / 180.0;
      const Vec2 m{std::cos(a), std::sin(a)};
      const double t = 0.3 * m.x - 0.2 * m.y;
      const double cd = method == &kCurvature ? cd_of_slopes(kCurvature.params(), t, t)
                                              : depth_cd(kDepth.params(), 0.0, t, 1.0, nullptr);
      EXPECT_NEAR(truth_cd(model, {10, 20}, m), cd, 1e-12);
      for (double motor : {0.37, 5.0, 123.4}) {
        EXPECT_NEAR(truth_display_distance(model, {10, 20}, m, motor), motor / cd, 1e-9) << angle_deg;
        EXPECT_NEAR(truth_motor_travel(model, {10, 20}, m, motor), motor * cd, 1e-9 * cd) << angle_deg;
      }
    }
  }
}

// Along a diameter of the linear (cone) target the slope is +s uphill, -s downhill, 0 outside; the pair (p - m, p)
// changes at the rims and the apex and 1 px after each: a piecewise constant C/D with a closed-form integral.
TEST(GroundTruth, ConeAlongADiameterMatchesTheClosedForm) {
  for (double height : {0.25, 1.0}) {
    for (double radius : {100.0, 200.0}) {
      const TargetSpec spec{TargetShape::bump, TargetProfile::linear, height, radius};
      const auto surface = make_target_surface(spec);
      const TruthModel model{surface.get(), &kCurvature};
      const CurvatureParams& p = kCurvature.params();
      const double s = height * spec.relief_px / radius;
      const double c = spec.size / 2.0;
      const Vec2 start{c - radius - 10.0, c};
      const double d = 2 * radius + 20.0;
      const double motor = 10.0 + cd_of_slopes(p, 0, s) + (radius - 1) * cd_of_slopes(p, s, s) +
                           cd_of_slopes(p, s, -s) + (radius - 1) * cd_of_slopes(p, -s, -s) + cd_of_slopes(p, -s, 0) +
                           9.0;
      EXPECT_NEAR(truth_motor_travel(model, start, {1, 0}, d), motor, 1e-9 * motor) << spec.name();
      EXPECT_NEAR(truth_display_distance(model, start, {1, 0}, motor), d, 1e-8) << spec.name();
      // The same the other way, starting on the far side.
      EXPECT_NEAR(truth_display_distance(model, {c + radius + 10.0, c}, {-1, 0}, motor), d, 1e-8) << spec.name();
    }
  }
}

TEST(GroundTruth, FlatOutsideIsTheIdentity) {
  const auto surface = make_target_surface(TargetSpec{TargetShape::hole, TargetProfile::gaussian, 1.0, 200.0});
  for (const Method* method : kMethods) {
    const TruthModel model{surface.get(), method};
    // Along the top edge, 50 px from the rim: C/D is exactly 1.
    const Vec2 p{0.0, 0.0};
    const Vec2 end = truth_advance(model, p, {400.0, 0.0});
    EXPECT_NEAR(end.x, 400.0, 1e-9);
    EXPECT_EQ(end.y, 0.0);
    EXPECT_EQ(truth_cd(model, {30, 30}, {0, 1}), 1.0);
  }
}

TEST(GroundTruth, HalvingTheToleranceChangesTheAnswerByLessThanIt) {
  std::vector<std::unique_ptr<AnalyticSurface>> surfaces;
  for (const TargetSpec& spec : all_targets()) surfaces.push_back(make_target_surface(spec));
  surfaces.push_back(make_interrogation_surface({SurfaceKind::sphere, 512}));
  surfaces.push_back(make_interrogation_surface({SurfaceKind::monkey_saddle, 512}));
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    for (const Method* method : kMethods) {
      SCOPED_TRACE(testing::Message() << "surface " << i << " method " << method->name());
      const TruthModel model{surfaces[i].get(), method};
      const Vec2 m{std::cos(0.3), std::sin(0.3)};
      const double coarse = truth_display_distance(model, {20.3, 170.1}, m, 450.0, {1e-9, 1e-9});
      const double fine = truth_display_distance(model, {20.3, 170.1}, m, 450.0, {5e-10, 1e-9});
      EXPECT_LT(std::abs(coarse - fine), 1e-9);
      // The answer is consistent with the integral it inverts.
      EXPECT_NEAR(truth_motor_travel(model, {20.3, 170.1}, m, fine), 450.0, 1e-8);
    }
  }
}

// The engine's exact traversal integrates a C/D that is constant per texel, from samples at texel centres; the
// truth integrates the continuous C/D. Along a texel row the two pairs coincide at texel centres, so they differ
// by the midpoint rule's error inside each texel and near the rims: a few px over a whole stroke.
TEST(GroundTruth, EngineOnAFloatFieldStaysCloseToTheTruth) {
  constexpr double kBoundPx = 2.0;  // measured worst case over the 24 targets and both methods: 1.32 px
  double worst = 0.0;
  for (const TargetSpec& spec : all_targets()) {
    const auto surface = make_target_surface(spec);
    for (const Method* method : kMethods) {
      Region region;
      region.name = spec.name();
      region.rect = {0, 0, spec.size, spec.size};
      if (method == &kCurvature) {
        region.fields.gradient = target_gradient_field(spec);
        region.method = std::make_shared<CurvatureMethod>(CurvatureParams{});
      } else {
        region.fields.depth = target_depth_field(spec);
        region.method = std::make_shared<DepthMethod>(DepthParams{});
      }
      std::vector<Region> regions;
      regions.push_back(std::move(region));
      const Scene scene(std::move(regions));
      const TruthModel model{surface.get(), method};
      const Vec2 start{20.0, spec.size / 2.0 + 0.5};  // along the centres of a texel row
      CursorState cursor = cursor_at(start);
      Vec2 truth = start;
      for (int frame = 0; frame < 460; ++frame) {
        advance(scene, cursor, {1.0, 0.0});
        truth = truth_advance(model, truth, {1.0, 0.0});
      }
      const double error = length(cursor.position - truth);
      worst = std::max(worst, error);
      EXPECT_LT(error, kBoundPx) << spec.name() << " " << method->name();
    }
  }
  RecordProperty("worst_end_error_px", std::to_string(worst));
}

// A plane of slope `slope` along x with a height jump `jump` at x = 0 (flat normals would be slope 0), declared as
// its breakpoint.
class SteppedPlane final : public AnalyticSurface {
 public:
  // desktop_left: x < 0 lies outside every region (the plane is a region's relief from x = 0 on).
  SteppedPlane(double slope, double jump, bool desktop_left = false)
      : slope_(slope), jump_(jump), desktop_left_(desktop_left) {}
  bool outside_regions(Vec2 p) const override { return desktop_left_ && p.x < 0.0; }
  double height(Vec2 p) const override { return slope_ * p.x + (p.x >= 0.0 ? jump_ : 0.0); }
  ExactGradient gradient(Vec2) const override { return {slope_, 0.0}; }
  void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const override {
    if (m.x == 0.0) return;
    const double u = -p0.x / m.x;
    if (u > u0 && u < u1) out.push_back(u);
  }

 private:
  double slope_, jump_;
  bool desktop_left_;
};

// The hybrid's exact input: where the surface steps between the point 1 px behind and the point by more than
// discontinuity_px beyond its slopes, depth's C/D of the pair's whole height change (as on a discontinuity texel);
// elsewhere, a steep slope included, curvature's.
TEST(GroundTruth, HybridTakesDepthsCdAcrossAStepOnly) {
  const HybridMethod hybrid{HybridParams{}};
  const double threshold = hybrid.params().discontinuity_px;
  const DepthParams& depth = kDepth.params();
  for (double slope : {0.0, 0.3, 3.0}) {
    for (double jump : {0.0, 0.4, 2.0, -5.0}) {
      const SteppedPlane surface(slope, jump);
      const TruthModel model{&surface, &hybrid};
      for (double x : {-3.0, -0.5, 0.25, 0.5, 0.99, 1.01, 4.0}) {
        const bool across = x > 0.0 && x < 1.0;  // the pair (x - 1, x) straddles the jump
        const double want = across && std::abs(jump) > threshold ? depth_cd(depth, 0.0, slope + jump, 1.0, nullptr)
                                                                 : cd_of_slopes(kCurvature.params(), slope, slope);
        EXPECT_NEAR(truth_cd(model, {x, 7.0}, {1.0, 0.0}), want, 1e-9)
            << "slope " << slope << ", jump " << jump << ", x " << x;
        // Without a depth map, or where the step is against the desktop, there is no step to find.
        const double curvature = cd_of_slopes(kCurvature.params(), slope, slope);
        EXPECT_NEAR(truth_cd({&surface, &hybrid, false}, {x, 7.0}, {1.0, 0.0}), curvature, 1e-9);
        const SteppedPlane region_from_zero(slope, jump, true);
        EXPECT_NEAR(truth_cd({&region_from_zero, &hybrid}, {x, 7.0}, {1.0, 0.0}), curvature, 1e-9);
      }
    }
  }
}

}  // namespace
}  // namespace ph
