#include "daemon/evdev_device.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <linux/input.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

#include "core/engine/frame_path.hpp"

namespace ph {

namespace {

TimeUs to_us(const input_event& e) { return static_cast<TimeUs>(e.input_event_sec) * 1'000'000 + e.input_event_usec; }

InputEvent to_event(const input_event& e) {
  return {to_us(e), static_cast<std::uint16_t>(e.type), static_cast<std::uint16_t>(e.code), e.value};
}

}  // namespace

EvdevDevice::EvdevDevice(const std::string& node) : node_(node) {
  fd_ = UniqueFd(::open(node.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (!fd_) {
    const int error = errno;
    throw DeviceError(fmt::format("{}: cannot open: {}", node, std::strerror(error)), error);
  }
  libevdev* raw = nullptr;
  const int rc = libevdev_new_from_fd(fd_.get(), &raw);
  if (rc < 0) {
    throw DeviceError(fmt::format("{}: not an evdev device: {}", node, std::strerror(-rc)), -rc);
  }
  dev_.reset(raw);
  libevdev_set_clock_id(dev_.get(), CLOCK_MONOTONIC);
  keys_ = keys_down_now();
}

EvdevDevice::~EvdevDevice() {
  if (grabbed_) libevdev_grab(dev_.get(), LIBEVDEV_UNGRAB);
  dev_.reset();  // (then fd_ closes itself)
}

bool EvdevDevice::hung_up() const {
  pollfd p{fd_.get(), POLLIN, 0};
  return ::poll(&p, 1, 0) == 1 && (p.revents & (POLLHUP | POLLERR)) != 0;
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
  if (::ioctl(fd_.get(), EVIOCGKEY(keys.size()), keys.data()) < 0) return false;
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
                                   : fmt::format("{}: cannot grab: {}", node_, std::strerror(-rc)),
                      -rc);
  }
  grabbed_ = true;
}

void EvdevDevice::ungrab() {
  if (!grabbed_) return;
  libevdev_grab(dev_.get(), LIBEVDEV_UNGRAB);
  grabbed_ = false;
}

EvdevDevice::KeyBits EvdevDevice::keys_down_now() const {
  std::array<unsigned char, kKeyCount / 8> bytes{};
  KeyBits down;
  if (::ioctl(fd_.get(), EVIOCGKEY(bytes.size()), bytes.data()) < 0) return down;
  for (std::size_t code = 0; code < kKeyCount; ++code) {
    if ((bytes[code / 8] >> (code % 8)) & 1U) down.set(code);
  }
  return down;
}

void EvdevDevice::set_blocking(bool blocking) {
  const int flags = ::fcntl(fd_.get(), F_GETFL);
  if (flags < 0 || ::fcntl(fd_.get(), F_SETFL, blocking ? flags & ~O_NONBLOCK : flags | O_NONBLOCK) < 0)
    throw DeviceError(
        fmt::format("{}: cannot set the node {}blocking: {}", node_, blocking ? "" : "non-", std::strerror(errno)),
        errno);
  blocking_ = blocking;
}

// Inline in read_batch, the frame's path: out of line it sat on a page of its own (core/engine/frame_path.hpp).
[[gnu::always_inline]] inline ssize_t EvdevDevice::read_some(void* buffer, std::size_t size, Wait wait) {
  if (blocking_ && wait == Wait::no) {
    pollfd queued{fd_.get(), POLLIN, 0};
    if (::poll(&queued, 1, 0) == 0) {
      errno = EAGAIN;
      return -1;
    }
    // Readable, or an error (unplugged): either way read() does not wait.
  }
  return ::read(fd_.get(), buffer, size);
}

// After SYN_DROPPED the kernel's buffer holds only part of the stream: everything still in it is dropped
// (as libevdev does) and the keys whose state changed in the lost part are reported from EVIOCGKEY.
void EvdevDevice::resync(std::vector<InputEvent>& events, TimeUs time) {
  std::array<input_event, 64> discard;
  // Bounded, like libevdev's drain: a device cannot fill the buffer faster than this empties it.
  for (int i = 0; i < 16 && read_some(discard.data(), sizeof discard, Wait::no) > 0; ++i) {
  }
  const KeyBits now = keys_down_now();
  const KeyBits changed = now ^ keys_;
  for (std::size_t code = 0; code < kKeyCount; ++code) {
    if (!changed.test(code)) continue;
    events.push_back({time, ev::kKey, static_cast<std::uint16_t>(code), now.test(code) ? 1 : 0});
  }
  keys_ = now;
  events.push_back({time, ev::kSyn, ev::kSynReport, 0});
}

PH_FRAME_PATH ReadStatus EvdevDevice::read_batch(std::vector<InputEvent>& events, Wait wait) {
  events.clear();
  std::array<input_event, 64> batch;
  for (;;) {
    const ssize_t n = read_some(batch.data(), sizeof batch, wait);
    if (n < 0) {
      if (errno == EINTR && wait == Wait::yes) return ReadStatus::ok;  // woken to look at something else
      if (errno == EINTR) continue;
      if (errno == EAGAIN) return ReadStatus::ok;
      if (errno == ENODEV) return ReadStatus::gone;
      throw DeviceError(fmt::format("{}: read failed: {}", node_, std::strerror(errno)));
    }
    const std::size_t count = static_cast<std::size_t>(n) / sizeof(input_event);
    for (std::size_t i = 0; i < count; ++i) {
      const InputEvent e = to_event(batch[i]);
      events.push_back(e);
      if (e.type == ev::kKey && e.code < kKeyCount) keys_.set(e.code, e.value != 0);
      if (e.type == ev::kSyn && e.code == ev::kSynDropped) {
        resync(events, e.time);
        return ReadStatus::ok;
      }
    }
    // Less than a full batch: the kernel had no more, and a second read() would only say EAGAIN.
    if (count < batch.size()) return ReadStatus::ok;
    wait = Wait::no;  // more was queued than one batch: the rest, without waiting for new events
  }
}

ReadStatus EvdevDevice::read_available(const std::function<void(const InputEvent&)>& on_event) {
  const ReadStatus status = read_batch(scratch_);
  for (const InputEvent& e : scratch_) on_event(e);
  return status;
}

}  // namespace ph
