// What the checks against a real X server (x11_cursor_e2e.cpp) need from it, through Xlib and XInput 2:
// its input devices by name, the libinput driver's acceleration profile, the pointer's position, and
// a count of the raw motion events each device produced, to know when X has taken a frame in.
#pragma once

#include <X11/Xatom.h>
#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <X11/extensions/XInput2.h>
#include <X11/extensions/XTest.h>
#include <poll.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tests/vm/e2e_support.hpp"

namespace ph::e2e {

// Xlib reports protocol errors through a callback; the last one is kept here for the call that caused
// it (the default handler would end the program).
inline int& last_x_error() {
  static int code = 0;
  return code;
}

inline int record_x_error(Display*, XErrorEvent* event) {
  last_x_error() = event->error_code;
  return 0;
}

class XServer {
 public:
  XServer() : display_(XOpenDisplay(nullptr)) {
    const char* name = std::getenv("DISPLAY");
    if (!display_)
      throw Fatal(std::string("cannot open the X display ") + (name != nullptr ? name : "(DISPLAY unset)"));
    XSetErrorHandler(record_x_error);
    int event = 0, error = 0;
    if (!XQueryExtension(get(), "XInputExtension", &xi_opcode_, &event, &error)) throw Fatal("X has no XInput");
    int major = 2, minor = 2;
    if (XIQueryVersion(get(), &major, &minor) != Success) throw Fatal("X has no XInput 2.2");
    // Raw events go to the root window only; they come for every event a device sends, moved or not.
    unsigned char bits[XIMaskLen(XI_LASTEVENT)] = {};
    XISetMask(bits, XI_RawMotion);
    XIEventMask mask{XIAllDevices, static_cast<int>(sizeof bits), bits};
    XISelectEvents(get(), root(), &mask, 1);
    XSync(get(), False);
  }

  Display* get() const { return display_.get(); }
  Window root() const { return DefaultRootWindow(get()); }

  // The XInput id of the enabled slave pointer called `name`; nullopt when X has none.
  std::optional<int> pointer_device(const std::string& name) const {
    int count = 0;
    XIDeviceInfo* devices = XIQueryDevice(get(), XIAllDevices, &count);
    std::optional<int> id;
    for (int i = 0; i < count; ++i) {
      if (devices[i].use == XISlavePointer && devices[i].enabled && name == devices[i].name) id = devices[i].deviceid;
    }
    XIFreeDeviceInfo(devices);
    return id;
  }

  // Waits until X has added (hotplug) the pointer `name`; returns its id, nullopt on timeout.
  std::optional<int> wait_for_pointer(const std::string& name, Clock::duration timeout) const {
    std::optional<int> id;
    wait_until([&] { return (id = pointer_device(name)).has_value(); }, timeout, nullptr, 100ms);
    return id;
  }

  bool wait_pointer_gone(const std::string& name, Clock::duration timeout) const {
    return wait_until([&] { return !pointer_device(name); }, timeout, nullptr, 100ms);
  }

  // The libinput driver's "libinput Accel Profile Enabled" (one byte per profile: adaptive, flat[,
  // custom]) as "adaptive" or "flat", as xinput would set it.
  void set_accel_profile(int device, const std::string& profile) {
    std::vector<unsigned char> values = property_bytes(device, "libinput Accel Profile Enabled");
    if (values.size() < 2) throw Fatal("the device has no 'libinput Accel Profile Enabled'");
    std::fill(values.begin(), values.end(), 0);
    values[profile == "flat" ? 1 : 0] = 1;
    last_x_error() = 0;
    XIChangeProperty(get(), device, atom("libinput Accel Profile Enabled"), XA_INTEGER, 8, PropModeReplace,
                     values.data(), static_cast<int>(values.size()));
    XSync(get(), False);
    if (last_x_error() != 0) throw Fatal("X refused the acceleration profile: error " + std::to_string(last_x_error()));
  }

  std::string accel_profile(int device) const {
    const std::vector<unsigned char> values = property_bytes(device, "libinput Accel Profile Enabled");
    if (values.size() >= 2 && values[1] != 0) return "flat";
    if (!values.empty() && values[0] != 0) return "adaptive";
    return "none";
  }

  struct Pointer {
    int x = 0, y = 0;
  };

  Pointer pointer() const {
    Window root_return = 0, child = 0;
    int x = 0, y = 0, wx = 0, wy = 0;
    unsigned mask = 0;
    XQueryPointer(get(), root(), &root_return, &child, &x, &y, &wx, &wy, &mask);
    return {x, y};
  }

  // A relative motion through X's own XTEST pointer.
  void xtest_move_by(int dx, int dy) const {
    XTestFakeRelativeMotionEvent(get(), dx, dy, CurrentTime);
    XSync(get(), False);
  }

  // Sets _NET_ACTIVE_WINDOW on the root window, as a window manager does when the focus moves.
  void set_active_window(Window window) const {
    const unsigned long value = window;
    XChangeProperty(get(), root(), XInternAtom(get(), "_NET_ACTIVE_WINDOW", False), XA_WINDOW, 32, PropModeReplace,
                    reinterpret_cast<const unsigned char*>(&value), 1);
    XSync(get(), False);
  }

  void warp(int x, int y) const {
    XWarpPointer(get(), None, root(), 0, 0, 0, 0, x, y);
    XSync(get(), False);
  }

  // Raw motion events with an x or y valuator that `device` produced since this connection began.
  long motions(int device) const {
    const auto it = motions_.find(device);
    return it == motions_.end() ? 0 : it->second;
  }

  // Reads X's events until `device` has produced `count` raw motion events; false on timeout. X sends
  // a device's raw event while it processes that device's event, before it moves the pointer, and
  // answers requests only between such batches: a query that follows sees the pointer moved.
  bool wait_motions(int device, long count, Clock::duration timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      drain();
      if (motions(device) >= count) return true;
      if (Clock::now() >= deadline) return false;
      pollfd p{ConnectionNumber(get()), POLLIN, 0};
      ::poll(&p, 1, ms_until(deadline));
    }
  }

  // Reads what X sent so far and forgets everything but the raw motion counts.
  void drain() {
    XFlush(get());
    while (XEventsQueued(get(), QueuedAfterReading) > 0) {
      XEvent event;
      XNextEvent(get(), &event);
      XGenericEventCookie* cookie = &event.xcookie;
      if (cookie->type != GenericEvent || cookie->extension != xi_opcode_ || !XGetEventData(get(), cookie)) continue;
      if (cookie->evtype == XI_RawMotion) {
        const auto* raw = static_cast<const XIRawEvent*>(cookie->data);
        const bool moves = (raw->valuators.mask_len > 0) &&
                           (XIMaskIsSet(raw->valuators.mask, 0) || XIMaskIsSet(raw->valuators.mask, 1));
        // A raw event comes once from the device itself and once more through its master (deviceid
        // then names the master): count the device's own.
        if (moves && raw->deviceid == raw->sourceid) ++motions_[raw->sourceid];
      }
      XFreeEventData(get(), cookie);
    }
  }

 private:
  struct Closer {
    void operator()(Display* d) const { XCloseDisplay(d); }
  };

  Atom atom(const char* name) const { return XInternAtom(get(), name, False); }

  std::vector<unsigned char> property_bytes(int device, const char* name) const {
    Atom type = 0;
    int format = 0;
    unsigned long count = 0, after = 0;
    unsigned char* data = nullptr;
    std::vector<unsigned char> values;
    if (XIGetProperty(get(), device, atom(name), 0, 16, False, XA_INTEGER, &type, &format, &count, &after, &data) ==
            Success &&
        format == 8) {
      values.assign(data, data + count);
    }
    if (data != nullptr) XFree(data);
    return values;
  }

  std::unique_ptr<Display, Closer> display_;
  int xi_opcode_ = 0;
  std::map<int, long> motions_;  // device id -> raw motion events
};

}  // namespace ph::e2e
