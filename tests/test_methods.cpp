// Eq. 1-3 of the curvature paper and the depth method, checked against hand-computed values.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "core/engine/fast_math.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"

namespace ph {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The projected normal of a texel whose surface rises at `theta_deg` along the motion: a = -sin(theta).
double a_of(double theta_deg) { return -std::sin(theta_deg * kDeg); }

double cd_for(const CurvatureParams& p, double theta1_deg, double theta2_deg, StepDetail* d = nullptr) {
  return curvature_cd(p, a_of(theta1_deg), theta1_deg * kDeg, a_of(theta2_deg), theta2_deg * kDeg, d);
}

TEST(Projection, EqualsMinusSineOfSlopeAngleOnRandomNormalsAndDirections) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 100000; ++i) {
    double nx = u(rng), ny = u(rng), nz = std::abs(u(rng)) + 1e-3;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    const Normal n{static_cast<float>(nx / len), static_cast<float>(ny / len), static_cast<float>(nz / len)};
    const double phi = u(rng) * std::numbers::pi;
    const Vec2 m{std::cos(phi), std::sin(phi)};
    // Slope along m of the surface with this normal: dh/dm = -(n . m) / n_z; positive uphill.
    const double dh_dm = -(n.x * m.x + n.y * m.y) / static_cast<double>(n.z);
    const double theta = std::atan(dh_dm);
    ASSERT_NEAR(projected_normal_x(n, m), -std::sin(theta), 1e-9) << "normal " << n.x << "," << n.y << "," << n.z;
    // And the curvature method's per-texel sample agrees with both.
    const CurvatureMethod method{CurvatureParams{}};
    RegionFields fields;
    fields.gradient = GradientField(1, 1, gradient_from_normal(n));
    const TexelSample s = method.sample(&fields, {0, 0}, m);
    // The gradient is stored as float: the slope along m is good to a few float ulps of |g|.
    const Gradient g = fields.gradient->at(0, 0);
    const double tolerance = 1e-6 * (1.0 + std::hypot(g.x, g.y));
    ASSERT_NEAR(s.v0, -std::sin(theta), tolerance);
    ASSERT_NEAR(s.v1, dh_dm, tolerance);  // the slope along m, tan(theta)
  }
}

TEST(Projection, DegenerateNormalGivesZero) {
  EXPECT_EQ(projected_normal_x({0.0f, 0.0f, 0.0f}, {1.0, 0.0}), 0.0);
  EXPECT_EQ(projected_normal_x({0.0f, 1.0f, 0.0f}, {1.0, 0.0}), 0.0);  // normal across the plane of motion
}

TEST(CurvatureCd, UphillWithoutChangeIsEq2WithKmaxPrime) {
  StepDetail d;
  // 30 degrees uphill on both texels: cos(alpha) = -0.5, delta-beta = 0, kmax = 4: CD = 1 + 0.5 * 3.
  EXPECT_NEAR(cd_for(CurvatureParams{}, 30, 30, &d), 2.5, 1e-12);
  EXPECT_NEAR(d.cos_alpha, -0.5, 1e-12);
  EXPECT_NEAR(d.delta_beta_deg, 0.0, 1e-12);
  EXPECT_NEAR(d.kmax, 4.0, 1e-12);
  EXPECT_NEAR(d.kmin, 1.5, 1e-12);
  EXPECT_TRUE(std::isnan(d.dh));
}

TEST(CurvatureCd, DownhillWithoutChangeIsEq2WithKminPrime) {
  // cos(alpha) = 0.5, kmin = 1.5: CD = 1 - 0.5 * (1 - 1/1.5) = 5/6.
  EXPECT_NEAR(cd_for(CurvatureParams{}, -30, -30), 5.0 / 6.0, 1e-12);
}

TEST(CurvatureCd, CosAlphaZeroIsOne) {
  StepDetail d;
  // Symmetric ridge: the two projected normals cancel; delta-beta is large but Eq. 2 gives 1.
  EXPECT_EQ(cd_for(CurvatureParams{}, -30, 30, &d), 1.0);
  EXPECT_NEAR(d.cos_alpha, 0.0, 1e-15);
  EXPECT_NEAR(d.delta_beta_deg, -60.0, 1e-9);
  EXPECT_EQ(cd_for(CurvatureParams{}, 0, 0), 1.0);  // flat
}

TEST(CurvatureCd, KmaxClampsAtUpperLimit) {
  StepDetail d;
  // theta 20 -> 10 degrees: delta-beta = +10 (printed sign), kmax = 4 * 11 = 44 -> 30.
  const double cd = cd_for(CurvatureParams{}, 20, 10, &d);
  EXPECT_NEAR(d.delta_beta_deg, 10.0, 1e-9);
  EXPECT_EQ(d.kmax, 30.0);
  const double cos_alpha = -(std::sin(20 * kDeg) + std::sin(10 * kDeg)) / 2;  // -0.2578...
  EXPECT_NEAR(cd, 1.0 - cos_alpha * 29.0, 1e-12);
  EXPECT_NEAR(cd, 8.477191, 1e-6);
}

TEST(CurvatureCd, KmaxClampsAtLowerLimit) {
  StepDetail d;
  // theta 10 -> 11 degrees: delta-beta = -1, kmax = 4 * 0 = 0 -> 1: uphill without slowdown.
  EXPECT_NEAR(cd_for(CurvatureParams{}, 10, 11, &d), 1.0, 1e-12);
  EXPECT_EQ(d.kmax, 1.0);
}

TEST(CurvatureCd, KminClampsAtUpperLimit) {
  StepDetail d;
  // theta -20 -> -10: delta-beta = -10, kmin = 1.5 * 11 = 16.5 -> 5.
  const double cd = cd_for(CurvatureParams{}, -20, -10, &d);
  EXPECT_EQ(d.kmin, 5.0);
  const double cos_alpha = (std::sin(20 * kDeg) + std::sin(10 * kDeg)) / 2;
  EXPECT_NEAR(cd, 1.0 - cos_alpha * 0.8, 1e-12);
  EXPECT_NEAR(cd, 0.793733, 1e-6);
}

TEST(CurvatureCd, KminClampsAtLowerLimit) {
  StepDetail d;
  // theta -10 -> -11: delta-beta = +1, kmin = 1.5 * 0 -> 1: downhill without speed-up.
  EXPECT_NEAR(cd_for(CurvatureParams{}, -10, -11, &d), 1.0, 1e-12);
  EXPECT_EQ(d.kmin, 1.0);
}

TEST(CurvatureCd, DeltaBetaSignReversesEq3) {
  CurvatureParams prose;
  prose.delta_beta_sign = -1.0;
  StepDetail d;
  // The step that clamped kmax to 30 with the printed sign now clamps it to 1.
  EXPECT_NEAR(cd_for(prose, 20, 10, &d), 1.0, 1e-12);
  EXPECT_NEAR(d.delta_beta_deg, -10.0, 1e-9);
  EXPECT_EQ(d.kmax, 1.0);
  // And the one that gave kmax = 1 now gives kmax = 4 * 2 = 8.
  const double cd = cd_for(prose, 10, 11, &d);
  EXPECT_NEAR(d.kmax, 8.0, 1e-9);
  EXPECT_NEAR(cd, 1.0 + (std::sin(10 * kDeg) + std::sin(11 * kDeg)) / 2 * 7.0, 1e-12);
}

TEST(CurvatureCd, ConfiguredLimitsApply) {
  CurvatureParams p;
  p.kmax_prime = 2.0;
  p.kmax_hi = 3.0;
  p.kmin_prime = 2.0;
  p.kmin_hi = 2.5;
  EXPECT_NEAR(cd_for(p, 30, 30), 1.0 + 0.5 * 1.0, 1e-12);                                              // kmax = 2
  EXPECT_NEAR(cd_for(p, 20, 10), 1.0 + (std::sin(20 * kDeg) + std::sin(10 * kDeg)) / 2 * 2.0, 1e-12);  // 3
  EXPECT_NEAR(cd_for(p, -20, -10), 1.0 - (std::sin(20 * kDeg) + std::sin(10 * kDeg)) / 2 * (1 - 1 / 2.5), 1e-12);
}

TEST(CurvatureCd, StaysWithinBoundsOnRandomInput) {
  const CurvatureMethod method{CurvatureParams{}};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-89.9, 89.9);
  for (int i = 0; i < 100000; ++i) {
    const double cd = cd_for(method.params(), angle(rng), angle(rng));
    ASSERT_GE(cd, method.cd_lower_bound());
    ASSERT_LE(cd, method.cd_upper_bound());
  }
}

TEST(CurvatureParams, InvalidValuesAreRefusedWithTheirName) {
  CurvatureParams p;
  p.kmax_hi = 0.5;
  EXPECT_NE(validate(p).find("kmax"), std::string::npos);
  p = {};
  p.delta_beta_sign = 0.0;
  EXPECT_NE(validate(p).find("delta_beta_sign"), std::string::npos);
  p = {};
  p.kmin_prime = std::nan("");
  EXPECT_THROW(CurvatureMethod{p}, std::invalid_argument);
  EXPECT_EQ(validate(CurvatureParams{}), "");
}

TEST(DepthCd, LinearInDepthChangeWithinLimits) {
  const DepthParams p;  // gain 3, kmax 4, kmin 1.5
  StepDetail d;
  EXPECT_NEAR(depth_cd(p, 10.0, 10.5, 1.0, &d), 2.5, 1e-12);
  EXPECT_NEAR(d.dh, 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(d.cos_alpha));
  EXPECT_NEAR(depth_cd(p, 0.0, -0.1, 1.0, nullptr), 0.7, 1e-12);
  EXPECT_EQ(depth_cd(p, 0.0, 5.0, 1.0, nullptr), 4.0);                // kmax
  EXPECT_NEAR(depth_cd(p, 0.0, -5.0, 1.0, nullptr), 1 / 1.5, 1e-12);  // 1 / kmin
  EXPECT_NEAR(depth_cd(p, 0.0, 0.5, 2.0, nullptr), 1.75, 1e-12);      // per px travelled
  EXPECT_EQ(depth_cd(p, 3.0, 3.0, 1.0, nullptr), 1.0);
}

TEST(DepthCd, NonFiniteHeightsNeverGiveNaN) {
  const DepthParams p;
  EXPECT_TRUE(std::isfinite(depth_cd(p, 0.0, std::nan(""), 1.0, nullptr)));
  EXPECT_TRUE(std::isfinite(depth_cd(p, 0.0, INFINITY, 1.0, nullptr)));
  EXPECT_TRUE(std::isfinite(depth_cd(p, INFINITY, INFINITY, 1.0, nullptr)));
}

TEST(DepthParams, InvalidValuesAreRefused) {
  DepthParams p;
  p.kmin = 0.5;
  EXPECT_NE(validate(p).find("kmin"), std::string::npos);
  EXPECT_THROW(DepthMethod{p}, std::invalid_argument);
}

}  // namespace
}  // namespace ph

namespace ph {
namespace {

TEST(FastMath, AtanIsFloatAccurateEverywhere) {
  double worst = 0.0;
  for (double x = -50.0; x <= 50.0; x += 1e-4) worst = std::max(worst, std::abs(fast_atan(x) - std::atan(x)));
  for (double x : {0.0, -0.0, 1e-300, 1e6, -1e12, 1e300, HUGE_VAL, -HUGE_VAL}) {
    worst = std::max(worst, std::abs(fast_atan(x) - std::atan(x)));
  }
  EXPECT_LT(worst, 2e-7);
  // In degrees, as Eq. 3 uses it: an error of 1e-5 degrees changes k'max (1 + delta-beta) by 4e-5.
  EXPECT_LT(worst * 180.0 / std::numbers::pi, 1.2e-5);
  EXPECT_EQ(fast_atan(0.0), 0.0);
}

// fast_atan reads a small argument without the reduction's |x| and sign; the engine's results must not change by
// it, so it gives the bits of the reduced form (with base 0 and r = |x|, the sign restored last) everywhere there.
TEST(FastMath, AtanOfASmallArgumentIsTheReducedFormToTheBit) {
  auto reduced = [](double x) {
    const double r = std::abs(x), z = r * r;
    const double poly = (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1);
    const double result = 0.0 + (poly * z * r + r);
    return x < 0.0 ? -result : result;
  };
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  const double edge = 0.4142135623730950;  // tan(pi/8), where the reduction starts
  std::vector<double> xs = {0.0, -0.0, 5e-324, -5e-324, 1e-300, -1e-160, edge, -edge, std::nextafter(edge, 0.0)};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(-edge, edge);
  for (int i = 0; i < 200000; ++i) xs.push_back(uniform(rng));
  for (int e = -1074; e <= -2; ++e) xs.push_back(std::ldexp(-1.0, e));  // every binade down to the subnormals
  int differ = 0;
  for (double x : xs) differ += same(fast_atan(x), reduced(x)) ? 0 : 1;
  EXPECT_EQ(differ, 0);
}

TEST(FastMath, RoundHalfAwayIsStdRoundToTheBit) {
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> values = {0.0,
                                -0.0,
                                0.5,
                                -0.5,
                                1.5,
                                -1.5,
                                2.5,
                                -2.5,
                                0.49999999999999994,
                                -0.49999999999999994,
                                4503599627370495.5,
                                -4503599627370495.5,
                                4503599627370496.0,
                                9007199254740993.0,
                                1e300,
                                -1e300,
                                5e-324,
                                -5e-324,
                                inf,
                                -inf};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-60, 60);
  for (int i = 0; i < 200000; ++i) values.push_back(std::ldexp(unit(rng), exponent(rng)));
  for (int k = -2000; k <= 2000; ++k) {
    values.push_back(k + 0.5);
    values.push_back(std::nextafter(k + 0.5, 0.0));
    values.push_back(std::nextafter(k + 0.5, k + 1.0));
  }
  for (double v : values) ASSERT_TRUE(same(round_half_away(v), std::round(v))) << std::setprecision(17) << v;
  EXPECT_TRUE(std::isnan(round_half_away(nan)));
}

TEST(FastMath, FloorToIntMatchesFloor) {
  for (double v : {0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 1e9 + 0.5, -1e9 - 0.5, 2.9999999, -2.0000001, 1e-300, -1e-300}) {
    EXPECT_EQ(floor_to_int(v), static_cast<std::int32_t>(std::floor(v))) << v;
  }
}

}  // namespace
}  // namespace ph
