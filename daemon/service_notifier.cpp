#include "daemon/service_notifier.hpp"

#include <fmt/format.h>
#include <systemd/sd-daemon.h>

#include <cstdint>
#include <ctime>
#include <string>

namespace ph {

namespace {

void notify(const std::string& message) { sd_notify(0, message.c_str()); }

// STATUS= is one line; a newline would start another assignment.
std::string one_line(std::string_view text) {
  std::string line(text);
  for (char& c : line) {
    if (c == '\n') c = ' ';
  }
  return line;
}

}  // namespace

void ServiceNotifier::ready(std::string_view status) const { notify("READY=1\nSTATUS=" + one_line(status)); }

void ServiceNotifier::reloading() const {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const long long usec = static_cast<long long>(now.tv_sec) * 1'000'000 + now.tv_nsec / 1000;
  notify(fmt::format("RELOADING=1\nMONOTONIC_USEC={}\nSTATUS=reloading the scene", usec));
}

void ServiceNotifier::stopping() const { notify("STOPPING=1\nSTATUS=stopping"); }

void ServiceNotifier::status(std::string_view status) const { notify("STATUS=" + one_line(status)); }

void ServiceNotifier::watchdog() const { notify("WATCHDOG=1"); }

std::optional<std::chrono::microseconds> ServiceNotifier::watchdog_interval() {
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) <= 0 || usec == 0) return std::nullopt;
  return std::chrono::microseconds(usec / 2);
}

}  // namespace ph
