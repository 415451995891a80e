#include "config/desktop_geometry.hpp"

#include <algorithm>
#include <charconv>
#include <fstream>

namespace ph {

namespace {

std::string first_line(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  return line;
}

// "1920x1080" (a mode may carry a suffix such as "i" for interlaced) to width and height.
bool parse_mode(const std::string& text, std::int32_t& width, std::int32_t& height) {
  const std::size_t x = text.find('x');
  if (x == std::string::npos) return false;
  const char* end = text.data() + text.size();
  const auto w = std::from_chars(text.data(), text.data() + x, width);
  const auto h = std::from_chars(text.data() + x + 1, end, height);
  return w.ec == std::errc{} && w.ptr == text.data() + x && h.ec == std::errc{} && width > 0 && height > 0;
}

}  // namespace

std::vector<ConnectorMode> connected_modes(const std::filesystem::path& drm_dir) {
  std::vector<ConnectorMode> modes;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(drm_dir, ec)) {
    const std::string name = entry.path().filename().string();
    // Connectors are "cardN-TYPE-M"; "cardN" itself and render nodes are not.
    if (!name.starts_with("card") || name.find('-') == std::string::npos) continue;
    if (first_line(entry.path() / "status") != "connected") continue;
    ConnectorMode mode{name, 0, 0};
    if (parse_mode(first_line(entry.path() / "modes"), mode.width, mode.height)) modes.push_back(mode);
  }
  std::sort(modes.begin(), modes.end(), [](const auto& a, const auto& b) { return a.connector < b.connector; });
  return modes;
}

std::optional<Rect> desktop_from_modes(const std::vector<ConnectorMode>& modes) {
  if (modes.empty()) return std::nullopt;
  Rect desktop{0, 0, 0, 0};
  for (const ConnectorMode& m : modes) {
    desktop.w += m.width;
    desktop.h = std::max(desktop.h, m.height);
  }
  return desktop;
}

Rect resolve_desktop(const std::optional<Rect>& configured, const std::filesystem::path& drm_dir,
                     std::string& warning) {
  warning.clear();
  if (configured) return *configured;
  if (const auto found = desktop_from_modes(connected_modes(drm_dir))) return *found;
  warning = "desktop = \"auto\" found no connected display under " + drm_dir.string() +
            "; assuming 1920x1080 until the session helper gives the layout (or set desktop = [x, y, width, "
            "height] in a scene file's [daemon] table)";
  return {0, 0, 1920, 1080};
}

}  // namespace ph
