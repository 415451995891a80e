// The Wayland backend of pseudohaptic-session: the desktop's layout from every wl_output's logical
// position and size (xdg-output, which any compositor but the smallest offers; wl_output's own mode and
// scale otherwise), kept current as outputs come, go and change; and where the pointer is from the
// compositor where it says it (Hyprland's and Wayfire's sockets, compositor_cursor.hpp; KWin's script,
// kwin_cursor.hpp). Wayland gives clients no global pointer position, so elsewhere (GNOME, sway, weston)
// the helper reports the layout only.
#pragma once

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/engine/geometry.hpp"
#include "session/compositor_cursor.hpp"
#include "session/desktop.hpp"

namespace ph::session {

class WaylandError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The display cannot be reached at all (no socket, or the connection refused): the one failure after which the
// helper tries the X display (session/protocol.hpp, fallback_backend).
class WaylandUnreachable : public WaylandError {
 public:
  using WaylandError::WaylandError;
};

class WaylandDesktop : public Desktop {
 public:
  // Connects to `display` (empty: $WAYLAND_DISPLAY, else "wayland-0") and reads the outputs. Throws
  // WaylandError when it cannot. `cursor` may be null (no position query).
  WaylandDesktop(const std::string& display, std::unique_ptr<CursorSource> cursor);
  ~WaylandDesktop() override;
  WaylandDesktop(const WaylandDesktop&) = delete;
  WaylandDesktop& operator=(const WaylandDesktop&) = delete;

  std::string backend_name() const override;
  int fd() const override;
  bool events_queued() const override { return false; }  // read_events() dispatches all it reads
  // Throws WaylandError when the compositor has gone (or broke the connection).
  Changes read_events() override;
  Watch watch() const override { return cursor_ ? cursor_->watch() : Watch{}; }
  std::optional<Rect> layout() const override;
  std::vector<Rect> outputs() const override;
  bool knows_pointer() const override { return cursor_ != nullptr; }
  std::optional<Vec2> pointer() const override;
  std::optional<std::pair<std::string, std::string>> active_class() const override { return std::nullopt; }
  // Whether the compositor offers xdg-output (for messages).
  bool has_xdg_output() const;
  const CursorSource* cursor() const { return cursor_.get(); }

  struct State;  // the Wayland objects and what they said (wayland_desktop.cpp)

 private:
  std::unique_ptr<State> state_;
  std::unique_ptr<CursorSource> cursor_;
};

}  // namespace ph::session
