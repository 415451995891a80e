// One physical input device read through libevdev: what the daemon grabs and reads its events from.
#pragma once

#include <bitset>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/unique_fd.hpp"
#include "core/engine/device.hpp"
#include "core/engine/event.hpp"
#include "uinput/uinput_sink.hpp"  // LibevdevPtr

namespace ph {

class DeviceError : public std::runtime_error {
 public:
  explicit DeviceError(const std::string& what, int error = 0) : std::runtime_error(what), error_(error) {}
  // The errno behind it (0 when none): EACCES or ENOENT from open() mean "try again later" to hotplug.
  int error() const { return error_; }

 private:
  int error_;
};

// What a frame of reading found.
enum class ReadStatus { ok, gone };

// Whether a read may wait for the device's next events (see EvdevDevice::set_blocking).
enum class Wait { no, yes };

class EvdevDevice {
 public:
  // Opens a /dev/input/eventN node (non-blocking). Events carry CLOCK_MONOTONIC times, so that a change of
  // the wall clock never looks like a pause of the hand. Throws DeviceError naming the node and the reason.
  explicit EvdevDevice(const std::string& node);
  ~EvdevDevice();
  EvdevDevice(const EvdevDevice&) = delete;
  EvdevDevice& operator=(const EvdevDevice&) = delete;

  const std::string& node() const { return node_; }
  int fd() const { return fd_.get(); }
  // Whether the device has gone (unplugged): its node hangs up.
  bool hung_up() const;
  std::string name() const;

  // A pointer the daemon can drive: REL_X, REL_Y and at least one mouse button.
  bool is_pointer() const;
  // Anything that moves the desktop's cursor: a pointer, or a touchpad, tablet or touchscreen (ABS_X and
  // ABS_Y with a touch, tool or mouse button). The daemon watches those it does not take, to resync.
  bool moves_the_cursor() const;
  DeviceDescription description() const;

  // Asks the kernel now (EVIOCGKEY) whether any key or button is down: the daemon grabs only when none
  // is, so that no press is grabbed without its release.
  bool any_key_held() const;

  // EVIOCGRAB. Throws DeviceError (EBUSY: another program holds the grab).
  void grab();
  void ungrab();
  bool grabbed() const { return grabbed_; }

  // The node is opened non-blocking. A thread that does nothing but wait for this device sets it blocking,
  // so that it waits in read() itself (the cheapest wake-up, docs/PERFORMANCE.md); reads that must not
  // wait then ask poll() first.
  void set_blocking(bool blocking);

  // Replaces `events` with every event that can be read now, in order, read straight from the node in
  // batches (one read() when the kernel holds less than a batch: what a bare re-emitter does). A
  // SYN_DROPPED is handed on, then what the kernel's buffer still held is discarded and the buttons whose
  // state differs from the stream's (EVIOCGKEY) follow as events, ending in SYN_REPORT: the same shape as
  // a recording's dropped frame, which FrameProcessor passes through without applying its motion.
  // Returns gone when the device was unplugged. Wait::yes on a blocking node: the first read() waits for
  // events; a signal that interrupts it returns ok with no events.
  ReadStatus read_batch(std::vector<InputEvent>& events, Wait wait = Wait::no);
  // The same, one event at a time.
  ReadStatus read_available(const std::function<void(const InputEvent&)>& on_event);

 private:
  static constexpr std::size_t kKeyCount = 0x300;  // KEY_CNT
  using KeyBits = std::bitset<kKeyCount>;

  KeyBits keys_down_now() const;
  // One read() of the node; on a blocking node without `wait`, -1 and EAGAIN when nothing is queued.
  inline ssize_t read_some(void* buffer, std::size_t size, Wait wait);  // (defined in evdev_device.cpp, its only user)
  void resync(std::vector<InputEvent>& events, TimeUs time);

  std::string node_;
  UniqueFd fd_;  // closed after dev_ is freed (members go in reverse order)
  LibevdevPtr dev_;
  bool grabbed_ = false;
  bool blocking_ = false;
  KeyBits keys_;  // the keys and buttons down as the events read so far say
  std::vector<InputEvent> scratch_;
};

}  // namespace ph
