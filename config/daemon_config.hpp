// The daemon's settings: the optional [daemon] table of the scene file (parsed in config/scene_file.cpp).
// Which input devices the daemon takes over, how it emits, the desktop it keeps the cursor in, and the
// base pointer speed. Pure: matching a device is a function of its name and ids.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/engine/engine_options.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/pipeline.hpp"

namespace ph {

// One matcher of `devices`: "name:GLOB" (fnmatch(3), case-sensitive), "usb:VVVV:PPPP" or "id:VVVV:PPPP"
// (vendor:product, 4 hex digits each; both prefixes mean vendor:product regardless of the bus).
struct DeviceMatch {
  std::optional<std::string> name_glob;
  std::optional<std::uint16_t> vendor, product;
  bool written_usb = false;  // "usb:" rather than "id:" (the same matcher): said back as it was written
};

struct DaemonSettings {
  std::vector<DeviceMatch> devices;  // empty = any pointer
  // Absolute by default: the desktop then puts the cursor where the model is, and applies no
  // acceleration of its own (docs/SERVICE.md, "Absolute output").
  OutputMode output = OutputMode::absolute;
  std::optional<Rect> desktop;               // nullopt = auto (the size of the screen)
  std::optional<AccelProfile> acceleration;  // nullopt: adaptive with absolute output, flat with relative
  double speed = 0.0;                        // [-1, 1], as the desktop's pointer speed slider
  double mouse_dpi = 1000.0;                 // the mice's resolution, for the adaptive profile
  double pointer_speed = 1.0;                // screen px per device count at C/D 1
  EngineOptions engine;  // traversal and sampling (docs/SPEED_VS_ACCURACY.md); applied by load_scene
};

inline constexpr double kMaxPointerSpeed = 100.0;
// The least: a hundred counts of motion for one screen px. Below it a mouse barely moves the cursor, and at 1e-300
// (which "greater than 0" let through) every mouse the daemon takes stopped moving it at all.
inline constexpr double kMinPointerSpeed = 0.01;

// The pointer acceleration the daemon applies: the relative output's default is flat at speed 0, the
// identity, because the desktop accelerates relative motion itself.
AccelSettings acceleration_of(const DaemonSettings& settings);

// The pipeline the daemon runs with these settings in `desktop` (the table's rectangle, or the screens' where it says
// "auto"): their output mode, acceleration and pointer speed; the cursor starts at the desktop's centre.
PipelineConfig pipeline_config_of(const DaemonSettings& settings, Rect desktop);

// Parses one matcher; on a mistake returns nullopt and sets `error` to what is wrong and what is allowed.
std::optional<DeviceMatch> parse_device_match(std::string_view text, std::string& error);

// The matcher as it is written in the file ("name:Logitech*", "id:046d:c077").
std::string format_device_match(const DeviceMatch& match);

// True when the device matches any matcher, or when the settings name none (any pointer: the caller checks
// that the device is a pointer).
bool device_matches(const DaemonSettings& settings, std::string_view name, std::uint16_t vendor, std::uint16_t product);

}  // namespace ph
