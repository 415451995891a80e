#include "session/x11_desktop.hpp"

#include <X11/Xatom.h>
#include <X11/Xutil.h>
#include <X11/extensions/Xrandr.h>

#include <cstdlib>
#include <utility>
#include <vector>

#include "session/protocol.hpp"

namespace ph::session {

namespace {

// Xlib's default handler ends the program on any protocol error.
int ignore_protocol_error(Display*, XErrorEvent*) { return 0; }

// Xlib's default handler of a lost connection prints "X connection to :0 broken ..." itself: the X11Desktop's
// exit handler says it instead, in the helper's log. (Returning is allowed since libX11 1.7: the display's exit
// handler is called next.)
int quiet_io_error(Display*) { return 0; }

}  // namespace

X11Desktop::X11Desktop(const std::string& display, std::function<void(const std::string&)> lost)
    : lost_(std::move(lost)), display_(XOpenDisplay(display.empty() ? nullptr : display.c_str())) {
  if (!display_) {
    const char* name = display.empty() ? std::getenv("DISPLAY") : display.c_str();
    throw X11Error(std::string("cannot open the X display ") + (name != nullptr ? name : "(DISPLAY is not set)"));
  }
  XSetErrorHandler(ignore_protocol_error);
  if (lost_) {
    XSetIOErrorHandler(quiet_io_error);
    XSetIOErrorExitHandler(
        display_.get(),
        [](Display* d, void* self) {
          static_cast<X11Desktop*>(self)->lost_(std::string("the X server went away (the connection to ") +
                                                DisplayString(d) + " is broken)");
          std::exit(1);
        },
        this);
  }
  int event_base = 0, error_base = 0, major = 0, minor = 0;
  if (XRRQueryExtension(display_.get(), &event_base, &error_base) && XRRQueryVersion(display_.get(), &major, &minor) &&
      (major > 1 || (major == 1 && minor >= 2))) {
    randr_event_base_ = event_base;
    XRRSelectInput(display_.get(), DefaultRootWindow(display_.get()),
                   RRScreenChangeNotifyMask | RRCrtcChangeNotifyMask | RROutputChangeNotifyMask);
  }
  active_window_ = XInternAtom(display_.get(), "_NET_ACTIVE_WINDOW", False);
  XSelectInput(display_.get(), DefaultRootWindow(display_.get()), PropertyChangeMask);
  XFlush(display_.get());
}

X11Desktop::~X11Desktop() {
  if (lost_ && display_)
    XSetIOErrorExitHandler(
        display_.get(), [](Display*, void*) {}, nullptr);
}

int X11Desktop::fd() const { return ConnectionNumber(display_.get()); }

bool X11Desktop::events_queued() const { return XEventsQueued(display_.get(), QueuedAlready) > 0; }

// X scales an absolute device's axes onto the root window (the screen), which may be larger than its CRTCs
// (xrandr --fb): the root is the layout, and the CRTCs the outputs on it.
std::optional<Rect> X11Desktop::layout() const {
  Display* d = display_.get();
  return Rect{0, 0, DisplayWidth(d, DefaultScreen(d)), DisplayHeight(d, DefaultScreen(d))};
}

std::vector<Rect> X11Desktop::outputs() const {
  Display* d = display_.get();
  if (!has_randr()) return {};
  XRRScreenResources* resources = XRRGetScreenResourcesCurrent(d, DefaultRootWindow(d));
  if (resources == nullptr) return {};
  std::vector<Rect> outputs;
  for (int i = 0; i < resources->ncrtc; ++i) {
    XRRCrtcInfo* crtc = XRRGetCrtcInfo(d, resources, resources->crtcs[i]);
    if (crtc == nullptr) continue;
    if (crtc->mode != None && crtc->noutput > 0) {
      Rect shown{crtc->x, crtc->y, static_cast<std::int32_t>(crtc->width), static_cast<std::int32_t>(crtc->height)};
      // A panning CRTC bounds the pointer by its panning area, not by the part it shows now (RandR's cursor_bounds).
      if (XRRPanning* panning = XRRGetPanning(d, resources, resources->crtcs[i])) {
        if (panning->width > 0 && panning->height > 0) {
          shown = {static_cast<std::int32_t>(panning->left), static_cast<std::int32_t>(panning->top),
                   static_cast<std::int32_t>(panning->width), static_cast<std::int32_t>(panning->height)};
        }
        XRRFreePanning(panning);
      }
      outputs.push_back(shown);
    }
    XRRFreeCrtcInfo(crtc);
  }
  XRRFreeScreenResources(resources);
  return outputs_to_report(*layout(), outputs);
}

std::optional<Vec2> X11Desktop::pointer() const {
  Window root = 0, child = 0;
  int x = 0, y = 0, window_x = 0, window_y = 0;
  unsigned int mask = 0;
  if (!XQueryPointer(display_.get(), DefaultRootWindow(display_.get()), &root, &child, &x, &y, &window_x, &window_y,
                     &mask)) {
    return std::nullopt;
  }
  // X gives the pixel only; its centre is where the pointer is within half a pixel, and what the daemon's
  // absolute output emits for a model anywhere in that pixel.
  return Vec2{x + 0.5, y + 0.5};
}

X11Desktop::Changes X11Desktop::read_events() {
  Changes changes;
  while (XPending(display_.get()) > 0) {
    XEvent event;
    XNextEvent(display_.get(), &event);
    if (event.type == PropertyNotify && event.xproperty.atom == active_window_) {
      changes.focus = true;
    } else if (has_randr() && event.type == randr_event_base_ + RRScreenChangeNotify) {
      XRRUpdateConfiguration(&event);  // keeps Xlib's idea of the screen size current
      changes.layout = true;
    } else if (has_randr() && event.type == randr_event_base_ + RRNotify) {
      changes.layout = true;
    }
  }
  return changes;
}

std::optional<std::pair<std::string, std::string>> X11Desktop::active_class() const {
  Display* d = display_.get();
  Atom type = None;
  int format = 0;
  unsigned long count = 0, after = 0;
  unsigned char* data = nullptr;
  Window window = None;
  if (XGetWindowProperty(d, DefaultRootWindow(d), active_window_, 0, 1, False, XA_WINDOW, &type, &format, &count,
                         &after, &data) == Success &&
      type == XA_WINDOW && format == 32 && count == 1) {
    window = static_cast<Window>(*reinterpret_cast<unsigned long*>(data));
  }
  if (data != nullptr) XFree(data);
  if (window == None) return std::nullopt;
  XClassHint hint{};
  if (!XGetClassHint(d, window, &hint)) return std::nullopt;  // gone meanwhile, or no WM_CLASS
  std::pair<std::string, std::string> names{hint.res_name != nullptr ? hint.res_name : "",
                                            hint.res_class != nullptr ? hint.res_class : ""};
  if (hint.res_name != nullptr) XFree(hint.res_name);
  if (hint.res_class != nullptr) XFree(hint.res_class);
  return names;
}

}  // namespace ph::session
