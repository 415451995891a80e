// What pseudohaptic-session asks of a desktop, whatever its display server: the layout, where the pointer
// is, and what has changed. The backends: X11 (x11_desktop.hpp) and Wayland (wayland_desktop.hpp).
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "core/engine/geometry.hpp"

namespace ph::session {

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
  // The bounding box of all outputs in logical pixels; nullopt while there is none.
  virtual std::optional<Rect> layout() const = 0;
  // Whether this desktop can say where the pointer is. Without it the helper reports the layout only
  // and does not present itself as the daemon's helper (the daemon then never waits for its answer).
  virtual bool knows_pointer() const = 0;
  // Where the pointer is; nullopt when it cannot be said now.
  virtual std::optional<Vec2> pointer() const = 0;
  // The (instance, class) names of the application that has the focus; nullopt when unknown.
  virtual std::optional<std::pair<std::string, std::string>> active_class() const = 0;
};

}  // namespace ph::session
