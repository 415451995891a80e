#include "core/engine/acceleration.hpp"

#include <algorithm>
#include <cmath>

namespace ph {

namespace {

// libinput's constants (filter-mouse.c); the speed setting moves them as libinput does.
constexpr double kDefaultThreshold = 0.4;  // units/ms
constexpr double kMinimumThreshold = 0.2;  // units/ms
constexpr double kDefaultMaxFactor = 2.0;
constexpr double kDefaultIncline = 1.1;
constexpr double kSlowSpeed = 0.07;  // units/ms: below it the motion is slowed down to at most 30 %
// A frame more than this after the one before starts a new motion; its speed is taken over this time.
constexpr TimeUs kMotionTimeoutUs = 1'000'000;

}  // namespace

std::string_view accel_profile_name(AccelProfile profile) {
  return profile == AccelProfile::adaptive ? "adaptive" : "flat";
}

AdaptiveCurve AdaptiveCurve::for_speed(double speed) {
  return {std::max(kMinimumThreshold, kDefaultThreshold - 0.25 * speed), kDefaultMaxFactor + 1.5 * speed,
          kDefaultIncline + 0.75 * speed};
}

double AdaptiveCurve::factor(double units_per_ms) const {
  double f = 1.0;
  if (units_per_ms < kSlowSpeed) {
    f = 10.0 * units_per_ms + 0.3;
  } else if (units_per_ms >= threshold) {
    f = incline * (units_per_ms - threshold) + 1.0;
  }
  return std::min(max_factor, f);
}

PointerAcceleration::PointerAcceleration(const AccelSettings& settings)
    : settings_(settings),
      curve_(AdaptiveCurve::for_speed(settings.speed)),
      flat_factor_(std::max(0.005, 1.0 + settings.speed)) {}

// libinput with a mouse's two trackers: the speed is this frame's delta over the time since the frame
// before (+1 µs); after a pause, over the pause's limit. The factor is the profile averaged between the
// previous speed and this one by Simpson's rule, which smooths a sudden change of speed.
double PointerAcceleration::adaptive_factor(Vec2 units, TimeUs time) {
  const bool paused = !have_last_ || time < last_time_ || time - last_time_ > kMotionTimeoutUs;
  const double elapsed_us = paused ? kMotionTimeoutUs + 1.0 : static_cast<double>(time - last_time_) + 1.0;
  double velocity = length(units) / elapsed_us;  // units/µs
  if (!std::isfinite(velocity)) velocity = 0.0;
  have_last_ = true;
  last_time_ = time;
  // libinput scales the speed by the resolution once more inside the profile (filter-mouse.c).
  const double to_ms = 1000.0 * kNormalDpi / settings_.dpi;
  const double now = velocity * to_ms, before = last_velocity_ * to_ms;
  last_velocity_ = velocity;
  return (curve_.factor(now) + curve_.factor(before) + 4.0 * curve_.factor((now + before) / 2.0)) / 6.0;
}

}  // namespace ph
