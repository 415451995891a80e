#include "daemon/evdev_device.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

namespace ph {

namespace {

TimeUs to_us(const input_event& e) { return static_cast<TimeUs>(e.input_event_sec) * 1'000'000 + e.input_event_usec; }

InputEvent to_event(const input_event& e) {
  return {to_us(e), static_cast<std::uint16_t>(e.type), static_cast<std::uint16_t>(e.code), e.value};
}

}  // namespace

EvdevDevice::EvdevDevice(const std::string& node) : node_(node) {
  fd_ = ::open(node.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int error = errno;
    throw DeviceError(fmt::format("{}: cannot open: {}", node, std::strerror(error)), error);
  }
  libevdev* raw = nullptr;
  const int rc = libevdev_new_from_fd(fd_, &raw);
  if (rc < 0) {
    ::close(fd_);
    fd_ = -1;
    throw DeviceError(fmt::format("{}: not an evdev device: {}", node, std::strerror(-rc)), -rc);
  }
  dev_.reset(raw);
  libevdev_set_clock_id(dev_.get(), CLOCK_MONOTONIC);
}

EvdevDevice::~EvdevDevice() {
  if (grabbed_) libevdev_grab(dev_.get(), LIBEVDEV_UNGRAB);
  dev_.reset();
  if (fd_ >= 0) ::close(fd_);
}

std::string EvdevDevice::name() const {
  const char* n = libevdev_get_name(dev_.get());
  return n != nullptr ? n : "";
}

bool EvdevDevice::moves_the_cursor() const {
  const libevdev* d = dev_.get();
  if (libevdev_has_event_code(d, EV_REL, REL_X) && libevdev_has_event_code(d, EV_REL, REL_Y)) return true;
  if (!libevdev_has_event_code(d, EV_ABS, ABS_X) || !libevdev_has_event_code(d, EV_ABS, ABS_Y)) return false;
  for (const unsigned code : {BTN_TOUCH, BTN_TOOL_FINGER, BTN_TOOL_PEN, BTN_LEFT}) {
    if (libevdev_has_event_code(d, EV_KEY, code)) return true;
  }
  return false;
}

bool EvdevDevice::is_pointer() const {
  if (!libevdev_has_event_code(dev_.get(), EV_REL, REL_X) || !libevdev_has_event_code(dev_.get(), EV_REL, REL_Y)) {
    return false;
  }
  for (unsigned code = BTN_MOUSE; code < BTN_JOYSTICK; ++code) {
    if (libevdev_has_event_code(dev_.get(), EV_KEY, code)) return true;
  }
  return false;
}

DeviceDescription EvdevDevice::description() const {
  DeviceDescription d;
  d.name = name();
  d.bustype = static_cast<std::uint16_t>(libevdev_get_id_bustype(dev_.get()));
  d.vendor = static_cast<std::uint16_t>(libevdev_get_id_vendor(dev_.get()));
  d.product = static_cast<std::uint16_t>(libevdev_get_id_product(dev_.get()));
  d.version = static_cast<std::uint16_t>(libevdev_get_id_version(dev_.get()));
  for (unsigned prop = 0; prop < d.properties.size(); ++prop) {
    if (libevdev_has_property(dev_.get(), prop)) d.properties.set(prop);
  }
  for (unsigned type = 1; type <= ev::kMaxType; ++type) {
    if (!libevdev_has_event_type(dev_.get(), type)) continue;
    d.enable(ev::kSyn, static_cast<std::uint16_t>(type));
    const int max = libevdev_event_type_get_max(type);
    for (int code = 0; code <= max && code <= ev::kMaxCode; ++code) {
      if (!libevdev_has_event_code(dev_.get(), type, static_cast<unsigned>(code))) continue;
      d.enable(static_cast<std::uint16_t>(type), static_cast<std::uint16_t>(code));
      if (type == EV_ABS) {
        const input_absinfo* a = libevdev_get_abs_info(dev_.get(), static_cast<unsigned>(code));
        if (a != nullptr)
          d.absinfo[static_cast<std::uint16_t>(code)] = {a->minimum, a->maximum, a->fuzz, a->flat, a->resolution};
      }
    }
  }
  d.enable(ev::kSyn, ev::kSyn);
  return d;
}

bool EvdevDevice::any_key_held() const {
  std::array<unsigned char, KEY_MAX / 8 + 1> keys{};
  if (::ioctl(fd_, EVIOCGKEY(keys.size()), keys.data()) < 0) return false;
  for (unsigned char byte : keys) {
    if (byte != 0) return true;
  }
  return false;
}

void EvdevDevice::grab() {
  if (grabbed_) return;
  const int rc = libevdev_grab(dev_.get(), LIBEVDEV_GRAB);
  if (rc < 0) {
    throw DeviceError(rc == -EBUSY ? fmt::format("{}: another program has grabbed it", node_)
                                   : fmt::format("{}: cannot grab: {}", node_, std::strerror(-rc)));
  }
  grabbed_ = true;
}

void EvdevDevice::ungrab() {
  if (!grabbed_) return;
  libevdev_grab(dev_.get(), LIBEVDEV_UNGRAB);
  grabbed_ = false;
}

ReadStatus EvdevDevice::read_available(const std::function<void(const InputEvent&)>& on_event) {
  unsigned flags = LIBEVDEV_READ_FLAG_NORMAL;
  for (;;) {
    input_event e;
    const int rc = libevdev_next_event(dev_.get(), flags, &e);
    if (rc == LIBEVDEV_READ_STATUS_SYNC) {
      // SYN_DROPPED (in normal mode), or a state difference (in sync mode): read on in sync mode until
      // libevdev says the resync is complete (-EAGAIN), then go back to normal reads.
      if (flags == LIBEVDEV_READ_FLAG_NORMAL) {
        on_event(to_event(e));  // the SYN_DROPPED itself: the frame processor passes the resync through
        flags = LIBEVDEV_READ_FLAG_SYNC;
        continue;
      }
      on_event(to_event(e));
      continue;
    }
    if (rc == LIBEVDEV_READ_STATUS_SUCCESS) {
      on_event(to_event(e));
      continue;
    }
    if (rc == -EAGAIN) {
      if (flags == LIBEVDEV_READ_FLAG_SYNC) {
        flags = LIBEVDEV_READ_FLAG_NORMAL;  // resync done; there may be normal events behind it
        continue;
      }
      return ReadStatus::ok;
    }
    if (rc == -ENODEV) return ReadStatus::gone;
    throw DeviceError(fmt::format("{}: read failed: {}", node_, std::strerror(-rc)));
  }
}

}  // namespace ph
