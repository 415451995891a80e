#include "session/compositor_answers.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <limits>

#include "session/protocol.hpp"

namespace ph::session {

Rect logical_rect(const WaylandOutput& output) {
  if (output.logical) return *output.logical;
  const std::int32_t scale = std::max(output.scale, 1);
  const bool quarter_turn = (output.transform & 1) != 0;  // 90, 270, flipped-90, flipped-270
  const std::int32_t w = quarter_turn ? output.mode_height : output.mode_width;
  const std::int32_t h = quarter_turn ? output.mode_width : output.mode_height;
  return Rect{output.x, output.y, w / scale, h / scale};
}

std::vector<Rect> wayland_output_rects(const std::vector<WaylandOutput>& outputs) {
  std::vector<Rect> rects;
  rects.reserve(outputs.size());
  for (const WaylandOutput& o : outputs) rects.push_back(logical_rect(o));
  return rects;
}

std::optional<Rect> wayland_layout(const std::vector<WaylandOutput>& outputs) {
  return bounding_box(wayland_output_rects(outputs));
}

std::vector<std::string> hyprland_socket_candidates(std::string_view runtime_dir, std::string_view signature) {
  // A signature is one path component; anything else is not Hyprland's.
  if (signature.empty() || signature.find('/') != std::string_view::npos || signature == "." || signature == "..")
    return {};
  std::vector<std::string> paths;
  const std::string tail = "/hypr/" + std::string(signature) + "/.socket.sock";
  if (!runtime_dir.empty()) paths.push_back(std::string(runtime_dir) + tail);
  paths.push_back("/tmp" + tail);
  return paths;
}

namespace {

std::optional<std::int32_t> whole_number(std::string_view& text) {
  std::int32_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc()) return std::nullopt;
  text.remove_prefix(static_cast<std::size_t>(end - text.data()));
  return value;
}

}  // namespace

std::optional<Vec2> parse_hyprland_cursorpos(std::string_view answer) {
  while (!answer.empty() && (answer.back() == '\n' || answer.back() == ' ')) answer.remove_suffix(1);
  const std::optional<std::int32_t> x = whole_number(answer);
  if (!x || answer.substr(0, 2) != ", ") return std::nullopt;
  answer.remove_prefix(2);
  const std::optional<std::int32_t> y = whole_number(answer);
  if (!y || !answer.empty()) return std::nullopt;
  // Hyprland floors the position to a whole logical pixel: where the pointer is, within half a pixel.
  return Vec2{*x + 0.5, *y + 0.5};
}

std::string wayfire_message(std::string_view json) {
  const auto length = static_cast<std::uint32_t>(json.size());
  std::string message(kWayfireHeader, '\0');
  std::memcpy(message.data(), &length, kWayfireHeader);
  message.append(json);
  return message;
}

std::optional<std::size_t> wayfire_message_length(std::string_view header) {
  if (header.size() != kWayfireHeader) return std::nullopt;
  std::uint32_t length = 0;
  std::memcpy(&length, header.data(), kWayfireHeader);
  if (length > kWayfireMaxMessage) return std::nullopt;
  return length;
}

std::string wayfire_cursor_request() {
  return wayfire_message(R"({"method": "window-rules/get_cursor_position", "data": {}})");
}

std::optional<Vec2> parse_wayfire_cursor_position(std::string_view json) {
  // JSON is YAML's flow style, so yaml-cpp (which the project already uses) reads it.
  try {
    const YAML::Node reply = YAML::Load(std::string(json));
    if (!reply.IsMap() || reply["error"] || !reply["pos"] || !reply["pos"].IsMap()) return std::nullopt;
    const YAML::Node x = reply["pos"]["x"], y = reply["pos"]["y"];
    if (!x || !y || !x.IsScalar() || !y.IsScalar()) return std::nullopt;
    const Vec2 at{x.as<double>(), y.as<double>()};
    if (!is_finite(at)) return std::nullopt;
    return at;
  } catch (const YAML::Exception&) {
    return std::nullopt;
  }
}

}  // namespace ph::session
