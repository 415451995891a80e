// The X11 backend of pseudohaptic-session: where the pointer is (XQueryPointer on the root window) and
// the desktop's layout (the root window's size, onto which X maps absolute devices, and the active RandR CRTCs on
// it, their panning areas where they pan), and whether RandR says the layout changed.
#pragma once

#include <X11/Xlib.h>

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/engine/geometry.hpp"
#include "session/desktop.hpp"

namespace ph::session {

class X11Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class X11Desktop : public Desktop {
 public:
  // Opens `display` (empty: $DISPLAY). Throws X11Error when it cannot. X protocol errors (an output
  // that went away between two requests) are ignored from then on: the next layout is asked afresh. When the
  // connection is lost (the X server ended), `lost` is told why and the process exits with status 1, as Xlib's
  // own handler exits (it cannot be returned from); without `lost`, Xlib's message goes to stderr.
  explicit X11Desktop(const std::string& display, std::function<void(const std::string&)> lost = {});
  // A server already gone when the display is closed (logout: the X server ends as SIGTERM comes) is no error then.
  ~X11Desktop() override;

  std::string backend_name() const override { return "x11"; }
  int fd() const override;  // readable when X has sent events
  // Events Xlib has already read from the socket (during a request's round trip): poll(2) on fd() does
  // not see them.
  bool events_queued() const override;
  bool has_randr() const { return randr_event_base_ >= 0; }
  // Always known: the root window's size where RandR says nothing.
  std::optional<Rect> layout() const override;
  std::vector<Rect> outputs() const override;
  bool knows_pointer() const override { return true; }
  // Where the pointer is (the centre of its pixel); nullopt while it is on another X screen than the default one.
  std::optional<Vec2> pointer() const override;
  // What the events X has sent so far say changed: the screen or an output (RandR), the active window
  // (_NET_ACTIVE_WINDOW on the root window).
  Changes read_events() override;
  // The WM_CLASS (instance, class) of the active window, as the window manager names it in
  // _NET_ACTIVE_WINDOW; nullopt when there is none or it has no WM_CLASS.
  std::optional<std::pair<std::string, std::string>> active_class() const override;

 private:
  struct Closer {
    void operator()(Display* d) const { XCloseDisplay(d); }
  };
  std::function<void(const std::string&)> lost_;  // (declared first: it outlives the display)
  std::unique_ptr<Display, Closer> display_;
  int randr_event_base_ = -1;
  Atom active_window_ = None;
};

}  // namespace ph::session
