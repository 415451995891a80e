// Input devices as udev sees them: the event nodes present at start, and hotplug add/remove; and that the
// displays changed (a DRM event: a monitor plugged in or out, a mode forced), for desktop = "auto".
// Without a running udevd (no /run/udev/control: an initramfs, a container, our test VM) the monitor
// listens to the kernel's uevents directly; device nodes then come from devtmpfs.
#pragma once

#include <libudev.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace ph {

class UdevError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct UdevUnref {
  void operator()(udev* u) const { udev_unref(u); }
  void operator()(udev_monitor* m) const { udev_monitor_unref(m); }
  void operator()(udev_enumerate* e) const { udev_enumerate_unref(e); }
  void operator()(udev_device* d) const { udev_device_unref(d); }
};

struct InputHotplug {
  enum class Action { add, remove };
  Action action;
  std::string devnode;  // /dev/input/eventN
};

class UdevWatch {
 public:
  // Starts listening before enumerating, so that no device appears unseen between the two. Throws UdevError.
  UdevWatch();

  int fd() const { return fd_; }  // asked once per wake-up of the event loop: no call into libudev
  bool uses_kernel_events() const { return kernel_events_; }

  // /dev/input/event* nodes of the input devices present now, in sysfs order.
  std::vector<std::string> event_nodes() const;

  // The pending hotplugs of event nodes, in order, and whether a DRM device sent any event among them;
  // messages about anything else (a parent inputN device, an input change event) are read and dropped.
  struct Received {
    std::vector<InputHotplug> inputs;
    bool displays_changed = false;
  };
  Received receive_all();

 private:
  std::unique_ptr<udev, UdevUnref> udev_;
  std::unique_ptr<udev_monitor, UdevUnref> monitor_;
  int fd_ = -1;  // the monitor's
  bool kernel_events_ = false;
};

}  // namespace ph
