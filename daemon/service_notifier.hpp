// Tells systemd how the service is doing (sd_notify(3)): READY, RELOADING, STOPPING, STATUS and the
// watchdog ping. Without NOTIFY_SOCKET (run by hand) every call does nothing.
#pragma once

#include <chrono>
#include <optional>
#include <string_view>

namespace ph {

class ServiceNotifier {
 public:
  void ready(std::string_view status) const;
  void reloading() const;  // with MONOTONIC_USEC, as Type=notify-reload asks
  void stopping() const;
  void status(std::string_view status) const;
  void watchdog() const;

  // How often to ping: half of WATCHDOG_USEC, or nullopt when the unit has no watchdog.
  static std::optional<std::chrono::microseconds> watchdog_interval();
};

}  // namespace ph
