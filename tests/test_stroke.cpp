// Strokes of the hand (core/lab/stroke): constant motor steps until the cursor reaches the end, and no further.
#include "core/lab/stroke.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <vector>

#include "core/engine/method_curvature.hpp"

namespace ph {
namespace {

// A slope along +x over [x0, x0 + w) x [0, 10): uphill, so C/D > 1 on it.
Region slope(std::int32_t x0, std::int32_t w, float gx) {
  Region r;
  r.name = "slope";
  r.rect = {x0, 0, w, 10};
  r.fields.gradient = GradientField(w, 10, Gradient{gx, 0.0f});
  r.method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  return r;
}

TEST(Stroke, AnyStepStopsAtTheEnd) {
  std::vector<Region> regions;
  regions.push_back(slope(20, 40, 0.5f));
  const Scene scene(std::move(regions));
  for (const double step : {0.3, 1.0, 7.0, 55.5, 1e3, 8e6, 1e60, 1e66, 1e300}) {  // beyond 1e7 a frame walks 1e7
    SCOPED_TRACE(step);
    StrokeSpec spec;
    spec.from = {0.25, 5.5};
    spec.to = {80.75, 5.5};
    spec.motor_step_px = step;
    std::size_t last_frame = 0, rows = 0;
    double furthest = 0.0;
    const StrokeResult r = run_stroke(scene, spec, [&](std::size_t frame, const StepRecord& s) {
      EXPECT_GE(frame, last_frame);
      last_frame = frame;
      furthest = std::max(furthest, s.entry.x);
      ++rows;
    });
    EXPECT_TRUE(r.reached);
    EXPECT_NEAR(r.end.position.x, 80.75, 1e-6);
    EXPECT_LE(r.end.position.x, 80.75);
    EXPECT_EQ(r.end.position.y, 5.5);
    EXPECT_EQ(r.end.texel.x, 80);
    EXPECT_LE(furthest, 80.75);
    EXPECT_LT(last_frame, r.frames);
    EXPECT_GE(rows, 40u);  // every texel of the slope (the flat outside is crossed in one jump, unreported)
    EXPECT_GT(r.cd_max, 1.0);
  }
}

TEST(Stroke, WhatLiesPastTheEndIsNotMet) {
  // A flat stretch, then a slope that starts exactly where the stroke ends: one huge frame must not count it.
  std::vector<Region> regions;
  regions.push_back(slope(100, 50, 1.0f));
  const Scene scene(std::move(regions));
  StrokeSpec spec;
  spec.from = {0.0, 5.5};
  spec.to = {100.0, 5.5};
  spec.motor_step_px = 1e6;
  std::size_t rows = 0;
  const StrokeResult r = run_stroke(scene, spec, [&](std::size_t, const StepRecord&) { ++rows; });
  EXPECT_EQ(r.frames, 1u);
  EXPECT_EQ(r.cd_min, 1.0);
  EXPECT_EQ(r.cd_max, 1.0);
  EXPECT_NEAR(r.end.position.x, 100.0, 1e-6);
  EXPECT_LE(r.end.position.x, 100.0);
  EXPECT_EQ(r.end.texel.x, 99);
  EXPECT_EQ(rows, 0u);  // no texel of the slope
}

// The motor travel a stroke took: its length on the flat, C/D times its length on a uniform slope, whatever the step.
TEST(Stroke, MotorTravelIsTheIntegralOfTheCd) {
  std::vector<Region> regions;
  regions.push_back(slope(0, 100, 0.5f));
  const Scene scene(std::move(regions));
  CursorState probe = cursor_at({10.5, 5.5});
  const double cd = advance(scene, probe, {1.0, 0.0}).cd_max;  // the slope's C/D, uniform inside it
  ASSERT_GT(cd, 1.0);
  for (const double step : {0.7, 3.0, 50.0}) {
    SCOPED_TRACE(step);
    const StrokeResult on_slope = run_stroke(scene, {{20.25, 5.5}, {80.25, 5.5}, step, 10'000});
    // The stroke stops 1e-9 x its length short of `to` (see run_stroke), so the travel is short by as much x C/D.
    EXPECT_NEAR(on_slope.motor_px, 60.0 * cd, 1e-6);
    const StrokeResult flat = run_stroke(Scene{}, {{20.25, 5.5}, {80.25, 5.5}, step, 10'000});
    EXPECT_NEAR(flat.motor_px, 60.0, 1e-6);
  }
}

TEST(Stroke, BadStrokes) {
  const Scene scene;
  StrokeSpec spec;
  spec.from = spec.to = {3.0, 4.0};
  EXPECT_THROW(run_stroke(scene, spec), std::invalid_argument);
  spec.to = {5.0, 4.0};
  spec.motor_step_px = 0.0;
  EXPECT_THROW(run_stroke(scene, spec), std::invalid_argument);
  spec.motor_step_px = NAN;
  EXPECT_THROW(run_stroke(scene, spec), std::invalid_argument);
  spec.motor_step_px = 0.75;
  for (const double rate : {-1.0, double(NAN), double(INFINITY)}) {
    spec.rate_hz = rate;
    EXPECT_THROW(run_stroke(scene, spec), std::invalid_argument) << rate;
  }
  spec.rate_hz = 1e-300;  // frames far apart in time: still a stroke
  EXPECT_EQ(run_stroke(scene, spec).frames, 3u);
  spec.rate_hz = 0.0;
  const StrokeResult r = run_stroke(scene, spec);
  EXPECT_EQ(r.frames, 3u);  // 0.75, 0.75, then the 0.5 left
  EXPECT_NEAR(r.end.position.x, 5.0, 1e-8);
}

}  // namespace
}  // namespace ph
