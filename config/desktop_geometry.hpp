// The desktop rectangle for `desktop = "auto"`: read from the connected DRM connectors in sysfs.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph {

struct ConnectorMode {
  std::string connector;  // e.g. "card0-HDMI-A-1"
  std::int32_t width = 0, height = 0;
};

// Where the kernel lists the displays' connectors.
inline constexpr std::string_view kDrmDir = "/sys/class/drm";

// Connected connectors (status "connected") and the first mode each lists (the kernel lists the
// preferred mode first), in name order. Missing or unreadable files are skipped.
std::vector<ConnectorMode> connected_modes(const std::filesystem::path& drm_dir = kDrmDir);

// sysfs does not say how the compositor arranges the outputs, so they are taken side by side, left to
// right in name order: width = sum of widths, height = largest height. nullopt when none is connected.
std::optional<Rect> desktop_from_modes(const std::vector<ConnectorMode>& modes);

// What `desktop` resolves to: the configured rectangle if any, else the DRM desktop, else 1920 x 1080
// with `warning` set to a message for the log.
Rect resolve_desktop(const std::optional<Rect>& configured, const std::filesystem::path& drm_dir, std::string& warning);

}  // namespace ph
