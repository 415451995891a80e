// Pointer acceleration done by the daemon, before the C/D ratio (docs/METHODS.md, "Pointer acceleration").
// With absolute output the desktop applies no acceleration to the virtual device, so the daemon applies
// the profile the desktop would have applied to the mouse: libinput's adaptive profile for mice of at
// least 1000 dpi (its default everywhere) or its flat profile, with libinput's `speed` setting in
// [-1, 1]. Pure: the frame's time is passed in.
#pragma once

#include <string_view>

#include "core/engine/geometry.hpp"

namespace ph {

enum class AccelProfile { flat, adaptive };

struct AccelSettings {
  AccelProfile profile = AccelProfile::flat;
  double speed = 0.0;   // [-1, 1], libinput's "Accel Speed" (GNOME, KDE and xinput show the same number)
  double dpi = 1000.0;  // the mouse's resolution (udev's MOUSE_DPI); motion is normalised to 1000 dpi
};

inline constexpr double kNormalDpi = 1000.0;  // libinput's normalised units: 1 per count of a 1000-dpi mouse
inline constexpr double kMinMouseDpi = 100.0;
inline constexpr double kMaxMouseDpi = 100000.0;

std::string_view accel_profile_name(AccelProfile profile);

// libinput's adaptive ("linear") profile: the acceleration factor for a speed in units per ms at
// 1000 dpi, with the constants its `speed` setting picks.
struct AdaptiveCurve {
  double threshold;  // units/ms: below it, factor 1 (after the slow-motion ramp)
  double max_factor;
  double incline;  // per units/ms above the threshold

  static AdaptiveCurve for_speed(double speed);
  double factor(double units_per_ms) const;
};

class PointerAcceleration {
 public:
  explicit PointerAcceleration(const AccelSettings& settings = {});

  // One frame's motion in device counts at `time` (µs) -> motion in screen px. The adaptive profile works in
  // 1000-dpi units (libinput's normalised coordinates); the flat one scales the device's own counts, as libinput's
  // flat filter for a mouse does (its touchpad one normalises). Frames must come in time order; a time that goes
  // backwards is treated as a pause.
  // Inline: the flat profile, the daemon's per-frame path at its most common, then makes no call.
  Vec2 apply(Vec2 counts, TimeUs time) {
    Vec2 out;
    if (settings_.profile == AccelProfile::adaptive) {
      const Vec2 units = settings_.dpi == kNormalDpi ? counts : counts * (kNormalDpi / settings_.dpi);
      out = units * adaptive_factor(units, time);
    } else {
      out = counts * flat_factor_;
    }
    return is_finite(out) ? out : Vec2{};
  }

  const AccelSettings& settings() const { return settings_; }

 private:
  double adaptive_factor(Vec2 units, TimeUs time);

  AccelSettings settings_;
  AdaptiveCurve curve_;
  double flat_factor_ = 1.0;
  // The velocity tracker (libinput keeps two trackers for a mouse: the speed is the last delta over the
  // time since the frame before).
  TimeUs last_time_ = 0;
  bool have_last_ = false;
  double last_velocity_ = 0.0;  // units/µs
};

}  // namespace ph
