// The daemon's virtual output device, through libevdev's uinput API (docs/METHODS.md, "Cursor and output").
#pragma once

#include <libevdev/libevdev-uinput.h>
#include <libevdev/libevdev.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/engine/device.hpp"
#include "core/engine/pipeline.hpp"
#include "uinput/held_keys.hpp"

namespace ph {

class UinputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LibevdevFree {
  void operator()(libevdev* dev) const { libevdev_free(dev); }
};
using LibevdevPtr = std::unique_ptr<libevdev, LibevdevFree>;

struct LibevdevUinputDestroy {
  void operator()(libevdev_uinput* uidev) const { libevdev_uinput_destroy(uidev); }
};
using LibevdevUinputPtr = std::unique_ptr<libevdev_uinput, LibevdevUinputDestroy>;

// A libevdev device (not yet a kernel device) with the description's name, ids, properties, event
// codes and axis ranges: what the virtual device will announce.
LibevdevPtr describe(const DeviceDescription& description);

// What went wrong creating a uinput device, in words a user can act on.
std::string uinput_error_message(int negative_errno);

class UinputSink final : public EventSink {
 public:
  // How long readers get to read the release of held keys before the device goes away.
  static constexpr std::chrono::milliseconds kReleaseGrace{50};

  // Throws UinputError (e.g. no /dev/uinput, permission denied) with a message that says what to do.
  explicit UinputSink(const DeviceDescription& description);
  // Releases whatever the stream still holds down (then waits kReleaseGrace), then destroys the device.
  ~UinputSink() override;
  UinputSink(const UinputSink&) = delete;
  UinputSink& operator=(const UinputSink&) = delete;

  void write(const Frame& frame) override;
  // The /dev/input/eventN node of the virtual device ("" when the kernel did not say).
  std::string devnode() const;
  bool holds_keys() const { return held_.any(); }
  // Writes the release of whatever the stream still holds down; true if it wrote one. The device should then
  // stay kReleaseGrace before it is destroyed, which whoever calls this arranges (the destructor waits only for a
  // release it writes itself).
  bool release_held();
  // Whether a key or button event was written with a time (the events' own, CLOCK_MONOTONIC) at or after `since`: a
  // release the stream itself carried lately (the kernel releases what an unplugged mouse held) needs the same wait.
  bool wrote_a_key_since(TimeUs since) const { return wrote_a_key_ && last_key_time_ >= since; }
  std::string syspath() const;

 private:
  LibevdevUinputPtr uidev_;
  int fd_ = -1;  // uidev_'s, asked once rather than per frame
  HeldKeys held_;
  TimeUs last_time_ = 0;
  TimeUs last_key_time_ = 0;
  bool wrote_a_key_ = false;
  std::vector<input_event> batch_;  // the frame being written, kept to reuse its memory
};

}  // namespace ph
