// A stand-in for systemd-logind on a private system bus, for tests/vm/kwin_session_check.cpp: the little of
// org.freedesktop.login1 that KWin's DRM backend uses to open its GPU and input devices (KWin 5.27 opens
// them only through logind or ConsoleKit). One session, active, on seat0, that KWin may take control of;
// TakeDevice opens the device node as root and hands the descriptor over, as logind does.
#pragma once

#include <fcntl.h>
#include <sys/sysmacros.h>
#include <systemd/sd-bus.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "tests/kwin_stand_in.hpp"

namespace ph::logind_stand_in {

inline constexpr const char* kSessionPath = "/org/freedesktop/login1/session/ph";
inline constexpr const char* kSeatPath = "/org/freedesktop/login1/seat/seat0";

// The device node of a character device: /dev/ plus DEVNAME from its sysfs uevent file.
inline std::string device_node(unsigned major_number, unsigned minor_number) {
  std::ifstream uevent("/sys/dev/char/" + std::to_string(major_number) + ":" + std::to_string(minor_number) +
                       "/uevent");
  for (std::string line; std::getline(uevent, line);) {
    if (line.rfind("DEVNAME=", 0) == 0) return "/dev/" + line.substr(8);
  }
  return "";
}

class StandInLogind {
 public:
  explicit StandInLogind(std::string address) : address_(std::move(address)) {
    std::promise<bool> ready;
    std::future<bool> started = ready.get_future();
    thread_ = std::thread([this, &ready] { serve(ready); });
    started_ = started.get();
  }
  ~StandInLogind() {
    stop_ = true;
    thread_.join();
  }
  StandInLogind(const StandInLogind&) = delete;
  StandInLogind& operator=(const StandInLogind&) = delete;

  bool started() const { return started_; }
  // The nodes KWin took, in order ("/dev/dri/card0", "/dev/input/event3", ...).
  std::vector<std::string> taken() const {
    const std::lock_guard lock(mutex_);
    return taken_;
  }

 private:
  void serve(std::promise<bool>& ready) {
    kwin_stand_in::BusPtr bus = kwin_stand_in::connect_bus(address_);
    static const sd_bus_vtable manager[] = {SD_BUS_VTABLE_START(0),
                                            SD_BUS_METHOD("GetSession", "s", "o", &StandInLogind::get_session, 0),
                                            SD_BUS_METHOD("GetSessionByPID", "u", "o", &StandInLogind::get_session, 0),
                                            SD_BUS_SIGNAL("PrepareForSleep", "b", 0), SD_BUS_VTABLE_END};
    static const sd_bus_vtable session[] = {
        SD_BUS_VTABLE_START(0),
        SD_BUS_METHOD("Activate", "", "", &StandInLogind::nothing, 0),
        SD_BUS_METHOD("TakeControl", "b", "", &StandInLogind::nothing, 0),
        SD_BUS_METHOD("ReleaseControl", "", "", &StandInLogind::nothing, 0),
        SD_BUS_METHOD("TakeDevice", "uu", "hb", &StandInLogind::take_device, 0),
        SD_BUS_METHOD("ReleaseDevice", "uu", "", &StandInLogind::nothing, 0),
        SD_BUS_METHOD("PauseDeviceComplete", "uu", "", &StandInLogind::nothing, 0),
        SD_BUS_PROPERTY("Active", "b", &StandInLogind::active, 0, SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("VTNr", "u", &StandInLogind::vt, 0, SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_PROPERTY("Seat", "(so)", &StandInLogind::seat, 0, SD_BUS_VTABLE_PROPERTY_CONST),
        SD_BUS_SIGNAL("PauseDevice", "uus", 0),
        SD_BUS_SIGNAL("ResumeDevice", "uuh", 0),
        SD_BUS_VTABLE_END};
    static const sd_bus_vtable seat[] = {
        SD_BUS_VTABLE_START(0), SD_BUS_METHOD("SwitchTo", "u", "", &StandInLogind::nothing, 0), SD_BUS_VTABLE_END};
    if (!bus ||
        sd_bus_add_object_vtable(bus.get(), nullptr, "/org/freedesktop/login1", "org.freedesktop.login1.Manager",
                                 manager, this) < 0 ||
        sd_bus_add_object_vtable(bus.get(), nullptr, kSessionPath, "org.freedesktop.login1.Session", session, this) <
            0 ||
        sd_bus_add_object_vtable(bus.get(), nullptr, kSeatPath, "org.freedesktop.login1.Seat", seat, this) < 0 ||
        sd_bus_request_name(bus.get(), "org.freedesktop.login1", 0) < 0) {
      ready.set_value(false);
      return;
    }
    ready.set_value(true);
    while (!stop_) {
      while (sd_bus_process(bus.get(), nullptr) > 0) {
      }
      sd_bus_wait(bus.get(), 100000);
    }
  }

  static int get_session(sd_bus_message* m, void*, sd_bus_error*) {
    return sd_bus_reply_method_return(m, "o", kSessionPath);
  }
  static int nothing(sd_bus_message* m, void*, sd_bus_error*) { return sd_bus_reply_method_return(m, ""); }
  static int take_device(sd_bus_message* m, void* data, sd_bus_error* error) {
    auto& self = *static_cast<StandInLogind*>(data);
    unsigned major_number = 0, minor_number = 0;
    if (sd_bus_message_read(m, "uu", &major_number, &minor_number) < 0) return -EINVAL;
    const std::string node = device_node(major_number, minor_number);
    const int fd = node.empty() ? -1 : ::open(node.c_str(), O_RDWR | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
      return sd_bus_error_setf(error, SD_BUS_ERROR_FILE_NOT_FOUND, "cannot open %u:%u (%s)", major_number, minor_number,
                               node.c_str());
    }
    {
      const std::lock_guard lock(self.mutex_);
      self.taken_.push_back(node);
    }
    const int r = sd_bus_reply_method_return(m, "hb", fd, 0);  // sd-bus sends a duplicate
    ::close(fd);
    return r;
  }
  static int active(sd_bus*, const char*, const char*, const char*, sd_bus_message* reply, void*, sd_bus_error*) {
    return sd_bus_message_append(reply, "b", 1);
  }
  static int vt(sd_bus*, const char*, const char*, const char*, sd_bus_message* reply, void*, sd_bus_error*) {
    return sd_bus_message_append(reply, "u", 0U);
  }
  static int seat(sd_bus*, const char*, const char*, const char*, sd_bus_message* reply, void*, sd_bus_error*) {
    return sd_bus_message_append(reply, "(so)", "seat0", kSeatPath);
  }

  std::string address_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  bool started_ = false;
  mutable std::mutex mutex_;
  std::vector<std::string> taken_;
};

}  // namespace ph::logind_stand_in
