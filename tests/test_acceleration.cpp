// The daemon's own pointer acceleration against the profile libinput documents (docs/METHODS.md,
// "Pointer acceleration"): constants, curve shape, the speed tracker and the pause rule.
#include <gtest/gtest.h>

#include <cmath>

#include "core/engine/acceleration.hpp"
#include "core/engine/pipeline.hpp"

namespace ph {
namespace {

TEST(Acceleration, FlatAtSpeedZeroIsTheIdentity) {
  PointerAcceleration accel;
  for (const Vec2 counts : {Vec2{1, 0}, Vec2{-7, 3}, Vec2{123456, -98765}}) {
    const Vec2 out = accel.apply(counts, 1000);
    EXPECT_EQ(out.x, counts.x);
    EXPECT_EQ(out.y, counts.y);
  }
}

TEST(Acceleration, FlatScalesBySpeedNotResolution) {
  PointerAcceleration faster({AccelProfile::flat, 0.5, 1000.0});
  EXPECT_DOUBLE_EQ(faster.apply({10, -4}, 0).x, 15.0);
  EXPECT_DOUBLE_EQ(faster.apply({10, -4}, 0).y, -6.0);
  // libinput's floor: the factor never goes below 0.005.
  PointerAcceleration slowest({AccelProfile::flat, -1.0, 1000.0});
  EXPECT_DOUBLE_EQ(slowest.apply({1000, 0}, 0).x, 5.0);
  // The resolution does not count: libinput's flat filter for a mouse scales the device's own counts (its touchpad
  // flat filter, and the adaptive profile, normalise them to 1000 dpi).
  PointerAcceleration fine({AccelProfile::flat, 0.0, 2000.0});
  EXPECT_DOUBLE_EQ(fine.apply({10, 0}, 0).x, 10.0);
}

TEST(Acceleration, AdaptiveCurveHasLibinputsShape) {
  const AdaptiveCurve c = AdaptiveCurve::for_speed(0.0);
  EXPECT_DOUBLE_EQ(c.threshold, 0.4);
  EXPECT_DOUBLE_EQ(c.max_factor, 2.0);
  EXPECT_DOUBLE_EQ(c.incline, 1.1);
  EXPECT_DOUBLE_EQ(c.factor(0.0), 0.3);     // very slow motion is slowed down
  EXPECT_DOUBLE_EQ(c.factor(0.035), 0.65);  // ramp 10 v + 0.3
  EXPECT_DOUBLE_EQ(c.factor(0.07), 1.0);    // then 1:1 up to the threshold
  EXPECT_DOUBLE_EQ(c.factor(0.39), 1.0);
  EXPECT_DOUBLE_EQ(c.factor(0.9), 1.0 + 1.1 * 0.5);  // then the incline
  EXPECT_DOUBLE_EQ(c.factor(5.0), 2.0);              // capped
  // The speed setting moves all three, as libinput's does; the threshold never drops below 0.2.
  const AdaptiveCurve fast = AdaptiveCurve::for_speed(1.0);
  EXPECT_DOUBLE_EQ(fast.threshold, 0.2);
  EXPECT_DOUBLE_EQ(fast.max_factor, 3.5);
  EXPECT_DOUBLE_EQ(fast.incline, 1.85);
  const AdaptiveCurve slow = AdaptiveCurve::for_speed(-1.0);
  EXPECT_DOUBLE_EQ(slow.threshold, 0.65);
  EXPECT_DOUBLE_EQ(slow.max_factor, 0.5);
  EXPECT_DOUBLE_EQ(slow.factor(0.3), 0.5);
}

// Simpson's rule over the previous and the current speed, as libinput averages them.
double simpson(const AdaptiveCurve& c, double before, double now) {
  return (c.factor(now) + c.factor(before) + 4.0 * c.factor((now + before) / 2.0)) / 6.0;
}

TEST(Acceleration, AdaptiveUsesTheSpeedSinceTheFrameBefore) {
  const AdaptiveCurve c = AdaptiveCurve::for_speed(0.0);
  PointerAcceleration accel({AccelProfile::adaptive, 0.0, 1000.0});
  // The first frame follows a "pause": its speed is taken over libinput's one-second motion timeout.
  const double v0 = 8.0 / 1'000'001.0 * 1000.0;  // units/ms
  EXPECT_DOUBLE_EQ(accel.apply({8, 0}, 5'000'000).x, 8.0 * simpson(c, 0.0, v0));
  // 8 counts every 8 ms at 125 Hz: 8 / 8001 units per µs.
  const double v = 8.0 / 8001.0 * 1000.0;
  EXPECT_DOUBLE_EQ(accel.apply({8, 0}, 5'008'000).x, 8.0 * simpson(c, v0, v));
  const Vec2 steady = accel.apply({0, 8}, 5'016'000);
  EXPECT_DOUBLE_EQ(steady.y, 8.0 * c.factor(v));
  EXPECT_EQ(steady.x, 0.0);
  EXPECT_NEAR(steady.y / 8.0, 1.0 + 1.1 * (v - 0.4), 1e-12);  // about 1.66 at this hand speed
  // Diagonal motion: the speed is the length of the delta.
  const Vec2 diagonal = accel.apply({6, 8}, 5'024'000);
  const double vd = 10.0 / 8001.0 * 1000.0;
  EXPECT_DOUBLE_EQ(diagonal.x, 6.0 * simpson(c, v, vd));
  EXPECT_DOUBLE_EQ(diagonal.y / diagonal.x, 8.0 / 6.0);
}

TEST(Acceleration, APauseOrABackwardClockStartsOver) {
  const AdaptiveCurve c = AdaptiveCurve::for_speed(0.0);
  PointerAcceleration accel({AccelProfile::adaptive, 0.0, 1000.0});
  accel.apply({8, 0}, 1'000'000);
  accel.apply({8, 0}, 1'008'000);
  const double v = 8.0 / 8001.0 * 1000.0;
  const double after_pause = 8.0 / 1'000'001.0 * 1000.0;
  EXPECT_DOUBLE_EQ(accel.apply({8, 0}, 3'000'000).x, 8.0 * simpson(c, v, after_pause));
  EXPECT_DOUBLE_EQ(accel.apply({8, 0}, 2'000'000).x, 8.0 * simpson(c, after_pause, after_pause));
}

TEST(Acceleration, HigherResolutionIsNormalisedTwiceAsLibinputDoes) {
  // libinput divides the counts by dpi/1000 and, inside the profile, the speed once more.
  const AdaptiveCurve c = AdaptiveCurve::for_speed(0.0);
  PointerAcceleration accel({AccelProfile::adaptive, 0.0, 2000.0});
  accel.apply({16, 0}, 1'000'000);
  accel.apply({16, 0}, 1'008'000);
  const double units = 8.0, v = units / 8001.0 * 1000.0 / 2.0;
  EXPECT_DOUBLE_EQ(accel.apply({16, 0}, 1'016'000).x, units * c.factor(v));
}

TEST(Acceleration, FasterHandMovesTheCursorFartherPerCount) {
  PointerAcceleration slow({AccelProfile::adaptive, 0.0, 1000.0}), fast({AccelProfile::adaptive, 0.0, 1000.0});
  double slow_px = 0.0, fast_px = 0.0;
  for (int i = 0; i < 50; ++i) {
    slow_px += slow.apply({2, 0}, 1'000'000 + i * 8000).x;
    fast_px += fast.apply({20, 0}, 1'000'000 + i * 8000).x / 10.0;
  }
  EXPECT_GT(fast_px, 1.5 * slow_px);
}

TEST(AbsoluteOutput, APositionLandsOnThePixelTheModelIsIn) {
  // The desktop scales the axis range onto its width: libinput (v - min) * w / (max - min + 1), and X
  // loses up to 1/65536 of that before rounding down. Every pixel of a 3840 px desktop at x = -1920 must
  // come out as itself under both.
  PipelineConfig config;
  config.mode = OutputMode::absolute;
  config.desktop = {-1920, 0, 3840, 1080};
  DeviceDescription mouse;
  const DeviceDescription out = output_device(mouse, config);
  const AbsInfo x = out.absinfo.at(ev::kAbsX);
  EXPECT_EQ(x.minimum, -3840);
  EXPECT_EQ(x.maximum, 3839);
  const double range = static_cast<double>(x.maximum) - x.minimum + 1.0;
  for (std::int32_t pixel = -1920; pixel < 1920; ++pixel) {
    const double libinput = (abs_value_of_pixel(pixel) - x.minimum) * 3840.0 / range - 1920.0;
    const double xorg = ((abs_value_of_pixel(pixel) - x.minimum) * 65535.0 / range) * 3840.0 / 65536.0 - 1920.0;
    ASSERT_EQ(std::floor(libinput), pixel);
    ASSERT_EQ(std::floor(xorg), pixel);
  }
}

TEST(AbsoluteOutput, PipelineAcceleratesBeforeTheTextureAndEmitsPixelCentres) {
  PipelineConfig config;
  config.mode = OutputMode::absolute;
  config.desktop = {0, 0, 1920, 1080};
  config.start = Vec2{100.25, 200.75};
  config.acceleration = {AccelProfile::adaptive, 0.0, 1000.0};
  Pipeline pipeline(std::make_shared<const Scene>(), config);
  PointerAcceleration reference(config.acceleration);
  Vec2 expected = *config.start;
  for (int i = 0; i < 40; ++i) {
    Frame in;
    const TimeUs t = 1'000'000 + i * 8000;
    in.events = {{t, ev::kRel, ev::kRelX, 12}, {t, ev::kRel, ev::kRelY, -1}, {t, ev::kSyn, ev::kSynReport, 0}};
    const Frame out = pipeline.process(in);
    expected = expected + reference.apply({12, -1}, t);
    ASSERT_DOUBLE_EQ(pipeline.cursor().position.x, expected.x);
    ASSERT_DOUBLE_EQ(pipeline.cursor().position.y, expected.y);
    ASSERT_EQ(out.events.size(), 3u);
    EXPECT_EQ(out.events[0].value, abs_value_of_pixel(static_cast<std::int32_t>(std::floor(expected.x))));
    EXPECT_EQ(out.events[1].value, abs_value_of_pixel(static_cast<std::int32_t>(std::floor(expected.y))));
  }
  EXPECT_GT(pipeline.cursor().position.x - 100.25, 40 * 12 * 1.3);  // accelerated, not 1:1
}

TEST(AbsoluteOutput, TheModelCanBeMovedAndTheDesktopChanged) {
  PipelineConfig config;
  config.mode = OutputMode::absolute;
  Pipeline pipeline(std::make_shared<const Scene>(), config);
  pipeline.move_cursor_to({300.5, 400.5});
  EXPECT_EQ(pipeline.cursor().position, (Vec2{300.5, 400.5}));
  pipeline.move_cursor_to({5000, -20});  // outside: clamped to the desktop like the real pointer
  EXPECT_LT(pipeline.cursor().position.x, 1920.0);
  EXPECT_GE(pipeline.cursor().position.x, 1919.0);
  EXPECT_EQ(pipeline.cursor().position.y, 0.0);
  pipeline.move_cursor_to({std::nan(""), 3});  // never a NaN in the model
  EXPECT_TRUE(is_finite(pipeline.cursor().position));
  pipeline.set_desktop({0, 0, 1280, 720});
  EXPECT_EQ(pipeline.config().desktop, (Rect{0, 0, 1280, 720}));
  EXPECT_LT(pipeline.cursor().position.x, 1280.0);
  EXPECT_EQ(output_device(DeviceDescription{}, pipeline.config()).absinfo.at(ev::kAbsX).maximum, 2559);
}

}  // namespace
}  // namespace ph
