#include "daemon/udev_watch.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string_view>

namespace ph {

namespace {

bool udevd_running() { return ::access("/run/udev/control", F_OK) == 0; }

bool is_event_node(const char* devnode) {
  return devnode != nullptr && std::string_view(devnode).starts_with("/dev/input/event");
}

}  // namespace

UdevWatch::UdevWatch() : udev_(udev_new()) {
  if (!udev_) throw UdevError(fmt::format("cannot start libudev: {}", std::strerror(errno)));
  kernel_events_ = !udevd_running();
  monitor_.reset(udev_monitor_new_from_netlink(udev_.get(), kernel_events_ ? "kernel" : "udev"));
  if (!monitor_) throw UdevError(fmt::format("cannot listen for device hotplug (netlink): {}", std::strerror(errno)));
  if (udev_monitor_filter_add_match_subsystem_devtype(monitor_.get(), "input", nullptr) < 0 ||
      udev_monitor_filter_add_match_subsystem_devtype(monitor_.get(), "drm", nullptr) < 0 ||
      udev_monitor_enable_receiving(monitor_.get()) < 0) {
    throw UdevError(fmt::format("cannot listen for input hotplug: {}", std::strerror(errno)));
  }
  fd_ = udev_monitor_get_fd(monitor_.get());
}

std::vector<std::string> UdevWatch::event_nodes() const {
  std::unique_ptr<udev_enumerate, UdevUnref> enumerate(udev_enumerate_new(udev_.get()));
  if (!enumerate) throw UdevError(fmt::format("cannot list input devices: {}", std::strerror(errno)));
  udev_enumerate_add_match_subsystem(enumerate.get(), "input");
  udev_enumerate_add_match_sysname(enumerate.get(), "event*");
  if (udev_enumerate_scan_devices(enumerate.get()) < 0) {
    throw UdevError(fmt::format("cannot list input devices: {}", std::strerror(errno)));
  }
  std::vector<std::string> nodes;
  udev_list_entry* entry = nullptr;
  udev_list_entry_foreach(entry, udev_enumerate_get_list_entry(enumerate.get())) {
    std::unique_ptr<udev_device, UdevUnref> device(
        udev_device_new_from_syspath(udev_.get(), udev_list_entry_get_name(entry)));
    if (!device) continue;  // gone since the scan
    const char* devnode = udev_device_get_devnode(device.get());
    if (is_event_node(devnode)) nodes.emplace_back(devnode);
  }
  return nodes;
}

UdevWatch::Received UdevWatch::receive_all() {
  Received received;
  // The monitor's socket is non-blocking: this ends when nothing more is queued.
  while (std::unique_ptr<udev_device, UdevUnref> device{udev_monitor_receive_device(monitor_.get())}) {
    const char* subsystem = udev_device_get_subsystem(device.get());
    if (subsystem != nullptr && std::string_view(subsystem) == "drm") {
      received.displays_changed = true;
      continue;
    }
    const char* devnode = udev_device_get_devnode(device.get());
    const char* action = udev_device_get_action(device.get());
    if (!is_event_node(devnode) || action == nullptr) continue;
    const std::string_view a = action;
    if (a == "add") received.inputs.push_back({InputHotplug::Action::add, devnode});
    if (a == "remove") received.inputs.push_back({InputHotplug::Action::remove, devnode});
  }
  return received;
}

}  // namespace ph
