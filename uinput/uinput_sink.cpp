#include "uinput/uinput_sink.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <thread>

namespace ph {

LibevdevPtr describe(const DeviceDescription& d) {
  LibevdevPtr dev(libevdev_new());
  if (!dev) throw UinputError("out of memory creating a libevdev device");
  libevdev_set_name(dev.get(), d.name.c_str());
  libevdev_set_id_bustype(dev.get(), d.bustype);
  libevdev_set_id_vendor(dev.get(), d.vendor);
  libevdev_set_id_product(dev.get(), d.product);
  libevdev_set_id_version(dev.get(), d.version);
  for (unsigned prop = 0; prop < d.properties.size(); ++prop) {
    if (d.properties.test(prop)) libevdev_enable_property(dev.get(), prop);
  }
  // codes[0] is the type mask; every other type lists its codes. EV_SYN is always there.
  libevdev_enable_event_type(dev.get(), EV_SYN);
  for (unsigned type = 1; type <= ev::kMaxType; ++type) {
    if (!d.codes[0].test(type) && d.codes[type].none()) continue;
    libevdev_enable_event_type(dev.get(), type);
    for (unsigned code = 0; code <= ev::kMaxCode; ++code) {
      if (!d.codes[type].test(code)) continue;
      if (type == EV_ABS) {
        const auto it = d.absinfo.find(static_cast<std::uint16_t>(code));
        input_absinfo info{};
        if (it != d.absinfo.end()) {
          info = {0, it->second.minimum, it->second.maximum, it->second.fuzz, it->second.flat, it->second.resolution};
        }
        libevdev_enable_event_code(dev.get(), type, code, &info);
      } else if (type == EV_REP) {
        int value = 0;
        libevdev_enable_event_code(dev.get(), type, code, &value);
      } else {
        libevdev_enable_event_code(dev.get(), type, code, nullptr);
      }
    }
  }
  return dev;
}

std::string uinput_error_message(int negative_errno) {
  const int err = -negative_errno;
  switch (err) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return "cannot create the virtual pointer: /dev/uinput does not exist. Load the uinput module "
             "(sudo modprobe uinput; once installed, modules-load.d/pseudohaptic.conf loads it at boot) and "
             "try again.";
    case EACCES:
    case EPERM:
      return "cannot create the virtual pointer: no permission to open /dev/uinput. Run pseudohapticd as "
             "root, or as a member of the group uinput once 60-pseudohaptic.rules gives /dev/uinput to that "
             "group (the systemd unit does so).";
    default:
      return fmt::format("cannot create the virtual pointer through /dev/uinput: {}", std::strerror(err));
  }
}

UinputSink::UinputSink(const DeviceDescription& description) {
  const LibevdevPtr dev = describe(description);
  libevdev_uinput* raw = nullptr;
  const int rc = libevdev_uinput_create_from_device(dev.get(), LIBEVDEV_UINPUT_OPEN_MANAGED, &raw);
  if (rc < 0) throw UinputError(uinput_error_message(rc));
  uidev_.reset(raw);
  fd_ = libevdev_uinput_get_fd(raw);
}

// Nothing may stay pressed once the device is gone. The kernel discards what a reader has not read
// when the device is removed, so the readers (the compositor) get a moment to read the release.
UinputSink::~UinputSink() {
  if (release_held()) std::this_thread::sleep_for(kReleaseGrace);
}

bool UinputSink::release_held() {
  if (!uidev_ || !held_.any()) return false;
  for (const InputEvent& e : held_.release_all(last_time_).events) {
    libevdev_uinput_write_event(uidev_.get(), e.type, e.code, e.value);
  }
  held_ = HeldKeys{};
  return true;
}

[[gnu::hot]] void UinputSink::write(const Frame& frame) {
  batch_.clear();
  for (const InputEvent& e : frame.events) {
    // SYN_DROPPED describes the source's buffer, not an event of the stream: it is not written.
    if (e.type == ev::kSyn && e.code == ev::kSynDropped) continue;
    // The kernel stamps the events itself: the time stays zero, as libevdev's writes leave it.
    input_event out{};
    out.type = e.type;
    out.code = e.code;
    out.value = e.value;
    batch_.push_back(out);
  }
  // The whole frame in one write(): one system call per frame, as a bare re-emitter makes.
  const char* data = reinterpret_cast<const char*>(batch_.data());
  std::size_t left = batch_.size() * sizeof(input_event);
  while (left > 0) {
    const ssize_t n = ::write(fd_, data, left);
    if (n < 0 && errno == EINTR) continue;
    // A write can only fail if the device is gone.
    if (n <= 0) throw UinputError(fmt::format("writing to the virtual pointer failed: {}", std::strerror(errno)));
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  for (const InputEvent& e : frame.events) {
    if (e.type == ev::kSyn && e.code == ev::kSynDropped) continue;
    held_.observe(e);
    last_time_ = e.time;
    if (e.type == ev::kKey) {
      last_key_time_ = e.time;
      wrote_a_key_ = true;
    }
  }
}

std::string UinputSink::devnode() const {
  const char* node = libevdev_uinput_get_devnode(uidev_.get());
  return node != nullptr ? node : "";
}

std::string UinputSink::syspath() const {
  const char* path = libevdev_uinput_get_syspath(uidev_.get());
  return path != nullptr ? path : "";
}

}  // namespace ph
