// The X11 backend of pseudohaptic-session: where the pointer is (XQueryPointer on the root window) and
// the desktop's layout (the bounding box of the active RandR CRTCs, or the root window's size where
// RandR is absent), and whether RandR says the layout changed.
#pragma once

#include <X11/Xlib.h>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/geometry.hpp"

namespace ph::session {

class X11Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class X11Desktop {
 public:
  // Opens `display` (empty: $DISPLAY). Throws X11Error when it cannot. X protocol errors (an output
  // that went away between two requests) are ignored from then on: the next layout is asked afresh.
  explicit X11Desktop(const std::string& display);

  int fd() const;  // readable when X has sent events
  bool has_randr() const { return randr_event_base_ >= 0; }
  Rect layout() const;
  // Where the pointer is; nullopt while it is on another X screen than the default one.
  std::optional<Vec2> pointer() const;
  // Reads the events X has sent; true when one of them says the screen or an output changed.
  bool layout_changed();

 private:
  struct Closer {
    void operator()(Display* d) const { XCloseDisplay(d); }
  };
  std::unique_ptr<Display, Closer> display_;
  int randr_event_base_ = -1;
};

}  // namespace ph::session
