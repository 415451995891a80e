// What pseudohaptic-session asks of a desktop, whatever its display server: the layout, where the pointer
// is, and what has changed. The backends: X11 (x11_desktop.hpp) and Wayland (wayland_desktop.hpp).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph::session {

// A descriptor besides the display server's that the helper's loop waits on (the session bus, where
// KWin's script reports the pointer): the poll(2) events it waits for and how long the loop may sleep
// before it must be handled anyway (ms; -1: no limit). fd -1: none.
struct Watch {
  int fd = -1;
  short events = 0;
  int timeout_ms = -1;
};

class Desktop {
 public:
  virtual ~Desktop() = default;

  // The name the helper gives the daemon (`helper NAME`): "x11", "wayland-hyprland"...
  virtual std::string backend_name() const = 0;
  virtual int fd() const = 0;  // readable when the display server has sent something
  // Whether events already read from the socket wait to be handled: poll(2) on fd() does not see them.
  virtual bool events_queued() const = 0;
  // What the events sent so far say changed. Never blocks.
  struct Changes {
    bool layout = false;  // an output came, went, moved or changed size
    bool focus = false;   // the active window
  };
  virtual Changes read_events() = 0;
  // The second descriptor to wait on; read_events() handles what arrives there too.
  virtual Watch watch() const { return {}; }
  // What absolute axes span in logical pixels (the bounding box of all outputs; X's root window); nullopt while there
  // is no output.
  virtual std::optional<Rect> layout() const = 0;
  // Where on it the outputs are, where they do not cover it (session/protocol.hpp, outputs_to_report).
  virtual std::vector<Rect> outputs() const = 0;
  // Whether this desktop can say where the pointer is. Without it the helper reports the layout only
  // and does not present itself as the daemon's helper (the daemon then never waits for its answer).
  virtual bool knows_pointer() const = 0;
  // Where the pointer is; nullopt when it cannot be said now.
  virtual std::optional<Vec2> pointer() const = 0;
  // The (instance, class) names of the application that has the focus; nullopt when unknown.
  virtual std::optional<std::pair<std::string, std::string>> active_class() const = 0;
};

}  // namespace ph::session
