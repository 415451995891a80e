// What the Wayland side of pseudohaptic-session makes of what compositors say, pure: each output's
// logical rectangle (xdg-output, or wl_output's mode, scale and transform where xdg-output is absent),
// Hyprland's `cursorpos` answer and request socket, Wayfire's IPC framing and its cursor-position reply.
// No I/O here; wayland_desktop.cpp and compositor_cursor.cpp do that.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph::session {

// One wl_output as the compositor last described it (after its `done`).
struct WaylandOutput {
  std::optional<Rect> logical;  // xdg-output's logical position and size, where the compositor sends them
  std::int32_t x = 0, y = 0;    // wl_output.geometry: the position in the compositor's space
  std::int32_t mode_width = 0, mode_height = 0;  // the current mode, in hardware pixels
  std::int32_t scale = 1;                        // wl_output.scale (version 2 and later)
  std::int32_t transform = 0;                    // wl_output.transform (WL_OUTPUT_TRANSFORM_*)
};

// The output's rectangle in the desktop's logical pixels: xdg-output's where known, else wl_output's
// position with the mode divided by the scale (width and height swapped for a 90 or 270 degree transform),
// which is the same for integer scales.
Rect logical_rect(const WaylandOutput& output);
// The desktop: the bounding box of all outputs' logical rectangles; nullopt while there is none.
std::optional<Rect> wayland_layout(const std::vector<WaylandOutput>& outputs);
// Each output's logical rectangle, in the order given.
std::vector<Rect> wayland_output_rects(const std::vector<WaylandOutput>& outputs);

// Hyprland's request socket: $XDG_RUNTIME_DIR/hypr/SIGNATURE/.socket.sock, then /tmp/hypr/SIGNATURE/.socket.sock
// (where older versions put it); empty without a signature.
std::vector<std::string> hyprland_socket_candidates(std::string_view runtime_dir, std::string_view signature);
// Hyprland's answer to `cursorpos`, "X, Y" (whole logical pixels, floored): the centre of that pixel.
std::optional<Vec2> parse_hyprland_cursorpos(std::string_view answer);

// A Wayfire IPC message: a 32-bit length in the machine's byte order (little endian on the machines
// Wayfire runs on), then that many bytes of JSON.
inline constexpr std::size_t kWayfireHeader = 4;
inline constexpr std::size_t kWayfireMaxMessage = 1 << 20;  // Wayfire's own limit
std::string wayfire_message(std::string_view json);
// The length a 4-byte header announces; nullopt when it is over kWayfireMaxMessage.
std::optional<std::size_t> wayfire_message_length(std::string_view header);
// The request for the pointer's position (the ipc-rules plugin's `window-rules/get_cursor_position`).
std::string wayfire_cursor_request();
// Its reply, {"result": "ok", "pos": {"x": X, "y": Y}} in logical pixels; nullopt for an error reply
// ({"error": ...}, as when the ipc-rules plugin is not loaded) or anything else.
std::optional<Vec2> parse_wayfire_cursor_position(std::string_view json);

}  // namespace ph::session
