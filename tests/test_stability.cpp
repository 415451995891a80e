// The stability suite's pieces (core/lab/failure_modes, stability, map_storage, cd_profile) and the properties
// it must find on the real engine: the same motion at 125 and 1000 Hz ends in the same place, a height jump with flat
// normals is invisible to curvature and seen by depth, no mode gives a NaN or traps a stroke.
#include "core/lab/stability.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/engine/methods.hpp"
#include "core/lab/cd_profile.hpp"
#include "core/lab/failure_modes.hpp"
#include "core/lab/map_storage.hpp"

namespace ph {
namespace {

const CaseGeometry kSmall{64, 40.0, {0.37}};

std::vector<MethodPtr> varying_methods() {
  std::vector<MethodPtr> out;
  const MethodRegistry registry = builtin_methods();
  for (const auto& entry : registry.entries()) {
    MethodPtr m = entry->make(entry->defaults());
    if (m->cd_lower_bound() != 1.0 || m->cd_upper_bound() != 1.0) out.push_back(m);
  }
  return out;
}

MethodPtr method_named(const std::string& name) { return make_default_method(builtin_methods(), name); }

StabilityRow measure(const std::string& mode, double severity, const MethodPtr& method,
                     const EngineOptions& engine = {}, const std::vector<double>& angles = {0.0, 45.0}) {
  std::vector<StabilityCase> cases;
  std::vector<CaseTruth> truths;
  StabilitySettings settings;
  settings.offsets = 2;
  for (double a : angles) {
    cases.push_back(make_case(mode, severity, a, kSmall));
    truths.push_back(case_truth(cases.back(), *method, settings));
  }
  return measure_stability(cases, truths, method, engine, settings);
}

TEST(StabilityMetrics, JitterIsTheRmsChangeOfLnCdPerPx) {
  double sum2 = 0.0;
  EXPECT_EQ(add_log_cd_jitter([](double) { return 2.5; }, 10.0, sum2), 9u);
  EXPECT_EQ(sum2, 0.0);
  // C/D alternating 1, 2 from one px to the next: every change is ln 2.
  sum2 = 0.0;
  const std::size_t n =
      add_log_cd_jitter([](double s) { return static_cast<int>(s) % 2 == 0 ? 1.0 : 2.0; }, 10.0, sum2);
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(n)), std::log(2.0), 1e-12);
}

TEST(StabilityMetrics, ContrastIsThePeakNearTheFeatureAgainstItsSurroundings) {
  const auto flat = [](double) { return 1.7; };
  EXPECT_NEAR(feature_contrast(flat, 50.0, 100.0, 3.0, 20.0), 1.0, 1e-12);
  // A 1 px peak of 4 on a C/D of 2 at the feature: a factor 2.
  const auto peak = [](double s) { return s >= 50.0 && s < 51.0 ? 4.0 : 2.0; };
  EXPECT_NEAR(feature_contrast(peak, 50.5, 100.0, 3.0, 20.0), 2.0, 1e-12);
  // A dip counts as much as a peak; one 10 px away does not count.
  const auto dip = [](double s) { return s >= 50.0 && s < 51.0 ? 0.5 : 1.0; };
  EXPECT_NEAR(feature_contrast(dip, 50.5, 100.0, 3.0, 20.0), 2.0, 1e-12);
  EXPECT_NEAR(feature_contrast(peak, 40.5, 100.0, 3.0, 20.0), 1.0, 1e-12);
}

TEST(StabilityMetrics, CdAtReadsSegmentsAndOneBetweenThem) {
  const std::vector<CdSegment> segments = {{0.0, 1.0, 2.0}, {1.0, 2.5, 3.0}, {4.0, 5.0, 0.5}};
  EXPECT_EQ(cd_at(segments, -0.1), 1.0);
  EXPECT_EQ(cd_at(segments, 0.5), 2.0);
  EXPECT_EQ(cd_at(segments, 1.0), 3.0);
  EXPECT_EQ(cd_at(segments, 3.0), 1.0);
  EXPECT_EQ(cd_at(segments, 4.5), 0.5);
  EXPECT_EQ(cd_at(segments, 5.0), 1.0);
}

TEST(MapStorage, SobelGivesAPlanesSlopeAndQuantisationStaysWithinACode) {
  DepthField plane(16, 16);
  for (std::int32_t y = 0; y < 16; ++y) {
    for (std::int32_t x = 0; x < 16; ++x) plane.at(x, y) = static_cast<float>(0.3 * x - 0.7 * y);
  }
  const Gradient g = gradient_from_normal(sobel_normals(plane).at(7, 9));
  EXPECT_NEAR(g.x, 0.3, 1e-5);
  EXPECT_NEAR(g.y, -0.7, 1e-5);
  const DepthField d8 = stored_depth(plane, 255);
  const double range = 0.3 * 15 + 0.7 * 15;
  for (std::size_t i = 0; i < plane.values.size(); ++i) {
    EXPECT_NEAR(d8.values[i], plane.values[i], 0.5 * range / 255.0 + 1e-4);
  }
  EXPECT_NE(d8.values, plane.values);  // 8 bits do change a plane this steep
}

TEST(FailureModes, EveryModeBuildsMapsThatMatchItsExactSurface) {
  for (const FailureMode& mode : failure_modes()) {
    for (double severity : mode.severities) {
      SCOPED_TRACE(mode.name + " " + std::to_string(severity));
      const StabilityCase c = make_case(mode.name, severity, 30.0, kSmall);
      ASSERT_FALSE(c.maps.empty());
      for (const CaseMap& map : c.maps) {
        ASSERT_EQ(map.normals.width, map.rect.w);
        ASSERT_EQ(map.depth.height, map.rect.h);
        for (const Normal& n : map.normals.values) ASSERT_TRUE(std::isfinite(n.x) && n.z > 0.0f);
        for (float h : map.depth.values) ASSERT_TRUE(std::isfinite(h));
      }
      // The top region's float depth equals the surface at a texel centre (the stored maps differ by a code).
      const CaseMap& top = c.maps.back();
      const Vec2 centre{top.rect.x + top.rect.w / 2 + 0.5, top.rect.y + top.rect.h / 2 + 0.5};
      const double h = c.surface->height(centre);
      const double stored = top.depth.at(top.rect.w / 2, top.rect.h / 2);
      EXPECT_NEAR(stored, h, 1e-3 * (1.0 + std::abs(h)) + (mode.name == "quantised" || mode.name == "fbm" ? 1.0 : 0.0));
      EXPECT_EQ(c.strokes.features.empty(), !mode.has_features);
    }
  }
  EXPECT_THROW(make_case("no-such-mode", 1.0, 0.0, kSmall), std::invalid_argument);
}

// The exact walk integrates the C/D field exactly, whatever the frames: the report rate must not matter.
TEST(StabilityProperties, ReportRateDoesNotMoveTheCursorOnAnyMode) {
  for (const MethodPtr& method : varying_methods()) {
    for (const FailureMode& mode : failure_modes()) {
      SCOPED_TRACE(std::string(method->name()) + " " + mode.name);
      const StabilityRow r = measure(mode.name, mode.small_severities.back(), method);
      EXPECT_LT(r.rate_px, 1e-9);
      EXPECT_EQ(r.faults, 0u);
    }
  }
}

// The cheaper traversals are not frame-independent: the metric must see that, or it measures nothing.
TEST(StabilityProperties, ReportRateMattersForUnitSteps) {
  const StabilityRow r = measure("cone", 45.0, method_named("depth"), {Traversal::unit_steps, Sampling::nearest, 16});
  EXPECT_GT(r.rate_px, 1e-3);
}

// The failure the curvature paper names: a C-1 step whose normals are flat on both sides.
TEST(StabilityProperties, AJumpWithFlatNormalsIsInvisibleToCurvatureAndSeenByDepth) {
  for (double height : {1.0, 8.0}) {
    const StabilityRow curvature = measure("jump", height, method_named("curvature"));
    const StabilityRow depth = measure("jump", height, method_named("depth"));
    EXPECT_EQ(curvature.contrast, 1.0);
    EXPECT_EQ(curvature.contrast_truth, 1.0);
    EXPECT_EQ(curvature.jitter_rms, 0.0);
    EXPECT_GT(depth.contrast, 3.0);  // C/D 4 (the depth method's kmax) at the step, 1 around it
    EXPECT_EQ(depth.contrast_truth, 4.0);
    // The hybrid finds the jump in its depth map and takes depth's C/D there.
    EXPECT_GT(measure("jump", height, method_named("hybrid")).contrast, 3.0);
  }
}

// Two overlapping regions holding the same surface: the seam is no feature for curvature, and at most a faint
// one for depth (its upwind difference across the seam, measured 1.16 at 45 degrees).
TEST(StabilityProperties, TheSeamOfOverlappingRegionsWithOneSurfaceIsFaint) {
  const StabilityRow curvature = measure("overlap", 0.0, method_named("curvature"));
  EXPECT_NEAR(curvature.contrast, 1.0, 1e-9);
  EXPECT_NEAR(curvature.cd_err_rms, 0.0, 1e-6);
  const StabilityRow depth = measure("overlap", 0.0, method_named("depth"));
  EXPECT_LT(depth.contrast, 1.25);
  EXPECT_NEAR(depth.contrast_truth, 1.0, 1e-9);
  EXPECT_GT(measure("overlap", 4.0, method_named("depth")).contrast, 2.0);
}

// Noise on the normals reaches curvature's C/D and not depth's, whose depth map is clean; fewer bits cost both.
TEST(StabilityProperties, NoiseAndQuantisationGainsGoWhereTheyShould) {
  for (const MethodPtr& method : {method_named("curvature"), method_named("depth")}) {
    SCOPED_TRACE(std::string(method->name()));
    const StabilityRow clean = measure("normal-noise", 0.0, method);
    const StabilityRow noisy = measure("normal-noise", 0.05, method);
    if (method->needs().gradient) {
      EXPECT_GT(noisy.cd_err_rms, 5.0 * clean.cd_err_rms);
      EXPECT_GT(noisy.jitter_rms, 3.0 * clean.jitter_rms);
    } else {
      EXPECT_EQ(noisy.cd_err_rms, clean.cd_err_rms);
    }
    EXPECT_GT(measure("quantised", 6.0, method).cd_err_rms, measure("quantised", 32.0, method).cd_err_rms);
  }
}

// Every engine variant on the modes most likely to trap a walk: never a NaN, a C/D out of bounds or a stroke
// that does not end.
TEST(StabilityProperties, NoVariantFaultsOnTheHarshestModes) {
  for (const MethodPtr& method : varying_methods()) {
    for (const EngineOptions& engine : all_engine_variants()) {
      for (const char* mode : {"grazing", "thin", "fbm", "jump"}) {
        SCOPED_TRACE(std::string(method->name()) + " " + label_of(engine) + " " + mode);
        const FailureMode& m = *std::find_if(failure_modes().begin(), failure_modes().end(),
                                             [&](const FailureMode& f) { return f.name == mode; });
        const StabilityRow r = measure(mode, m.severities.back(), method, engine, {45.0});
        EXPECT_EQ(r.faults, 0u);
        EXPECT_TRUE(std::isfinite(r.cd_err_rms) && std::isfinite(r.travel_sens_pct) && std::isfinite(r.jitter_rms));
      }
    }
  }
}

}  // namespace
}  // namespace ph
