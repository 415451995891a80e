#include "session/x11_desktop.hpp"

#include <X11/extensions/Xrandr.h>

#include <cstdlib>
#include <vector>

#include "session/protocol.hpp"

namespace ph::session {

namespace {

// Xlib's default handler ends the program on any protocol error.
int ignore_protocol_error(Display*, XErrorEvent*) { return 0; }

}  // namespace

X11Desktop::X11Desktop(const std::string& display)
    : display_(XOpenDisplay(display.empty() ? nullptr : display.c_str())) {
  if (!display_) {
    const char* name = display.empty() ? std::getenv("DISPLAY") : display.c_str();
    throw X11Error(std::string("cannot open the X display ") + (name != nullptr ? name : "(DISPLAY is not set)"));
  }
  XSetErrorHandler(ignore_protocol_error);
  int event_base = 0, error_base = 0, major = 0, minor = 0;
  if (XRRQueryExtension(display_.get(), &event_base, &error_base) && XRRQueryVersion(display_.get(), &major, &minor) &&
      (major > 1 || (major == 1 && minor >= 2))) {
    randr_event_base_ = event_base;
    XRRSelectInput(display_.get(), DefaultRootWindow(display_.get()),
                   RRScreenChangeNotifyMask | RRCrtcChangeNotifyMask | RROutputChangeNotifyMask);
  }
  XFlush(display_.get());
}

int X11Desktop::fd() const { return ConnectionNumber(display_.get()); }

Rect X11Desktop::layout() const {
  Display* d = display_.get();
  const Window root = DefaultRootWindow(d);
  const Rect whole{0, 0, DisplayWidth(d, DefaultScreen(d)), DisplayHeight(d, DefaultScreen(d))};
  if (!has_randr()) return whole;
  XRRScreenResources* resources = XRRGetScreenResourcesCurrent(d, root);
  if (resources == nullptr) return whole;
  std::vector<Rect> outputs;
  for (int i = 0; i < resources->ncrtc; ++i) {
    XRRCrtcInfo* crtc = XRRGetCrtcInfo(d, resources, resources->crtcs[i]);
    if (crtc == nullptr) continue;
    if (crtc->mode != None && crtc->noutput > 0) {
      outputs.push_back(
          {crtc->x, crtc->y, static_cast<std::int32_t>(crtc->width), static_cast<std::int32_t>(crtc->height)});
    }
    XRRFreeCrtcInfo(crtc);
  }
  XRRFreeScreenResources(resources);
  return bounding_box(outputs).value_or(whole);
}

std::optional<Vec2> X11Desktop::pointer() const {
  Window root = 0, child = 0;
  int x = 0, y = 0, window_x = 0, window_y = 0;
  unsigned int mask = 0;
  if (!XQueryPointer(display_.get(), DefaultRootWindow(display_.get()), &root, &child, &x, &y, &window_x, &window_y,
                     &mask)) {
    return std::nullopt;
  }
  return Vec2{static_cast<double>(x), static_cast<double>(y)};
}

bool X11Desktop::layout_changed() {
  bool changed = false;
  while (XPending(display_.get()) > 0) {
    XEvent event;
    XNextEvent(display_.get(), &event);
    if (!has_randr()) continue;
    if (event.type == randr_event_base_ + RRScreenChangeNotify) {
      XRRUpdateConfiguration(&event);  // keeps Xlib's idea of the screen size current
      changed = true;
    } else if (event.type == randr_event_base_ + RRNotify) {
      changed = true;
    }
  }
  return changed;
}

}  // namespace ph::session
