// Smoke test for the VM harness (tests/vm/run-in-vm): needs a kernel with uinput and evdev, run as root.
// Creates a uinput "physical" mouse, grabs its evdev node, checks that a second grab fails with EBUSY,
// writes events through uinput and reads them back from the grabbed node.
#include <libevdev/libevdev-uinput.h>
#include <libevdev/libevdev.h>

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace {

struct EvdevDeleter {
  void operator()(libevdev* d) const { libevdev_free(d); }
};
struct UinputDeleter {
  void operator()(libevdev_uinput* u) const { libevdev_uinput_destroy(u); }
};
using EvdevPtr = std::unique_ptr<libevdev, EvdevDeleter>;
using UinputPtr = std::unique_ptr<libevdev_uinput, UinputDeleter>;

class Fd {
 public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  Fd(Fd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Fd& operator=(Fd&& other) noexcept {
    if (this != &other) {
      reset();
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  int get() const { return fd_; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

[[noreturn]] void fail(const std::string& what, int err = 0) {
  throw std::runtime_error(err != 0 ? what + ": " + std::strerror(err) : what);
}

Fd open_or_fail(const char* path, int flags) {
  Fd fd(::open(path, flags));
  if (fd.get() < 0) fail(std::string("open ") + path, errno);
  return fd;
}

// libevdev returns negative errno values.
void check(int rc, const std::string& what) {
  if (rc < 0) fail(what, -rc);
}

struct Event {
  unsigned type;
  unsigned code;
  int value;
};

UinputPtr create_mouse() {
  EvdevPtr proto(libevdev_new());
  if (!proto) fail("libevdev_new");
  libevdev_set_name(proto.get(), "pseudohaptic vm smoke mouse");
  libevdev_set_id_bustype(proto.get(), BUS_USB);
  libevdev_set_id_vendor(proto.get(), 0x1234);
  libevdev_set_id_product(proto.get(), 0x5678);
  for (unsigned code : {REL_X, REL_Y, REL_WHEEL})
    check(libevdev_enable_event_code(proto.get(), EV_REL, code, nullptr), "enable EV_REL");
  for (unsigned code : {BTN_LEFT, BTN_RIGHT})
    check(libevdev_enable_event_code(proto.get(), EV_KEY, code, nullptr), "enable EV_KEY");
  libevdev_uinput* raw = nullptr;
  check(libevdev_uinput_create_from_device(proto.get(), LIBEVDEV_UINPUT_OPEN_MANAGED, &raw),
        "libevdev_uinput_create_from_device");
  return UinputPtr(raw);
}

std::string describe(const Event& e) {
  const char* name = libevdev_event_code_get_name(e.type, e.code);
  return (name ? std::string(name) : std::to_string(e.type) + ":" + std::to_string(e.code)) + " " +
         std::to_string(e.value);
}

// Reads one event from the grabbed device, waiting at most timeout_ms.
Event next_event(libevdev* dev, int fd, int timeout_ms) {
  for (;;) {
    input_event ev{};
    int rc = libevdev_next_event(dev, LIBEVDEV_READ_FLAG_NORMAL, &ev);
    if (rc == LIBEVDEV_READ_STATUS_SUCCESS) return {ev.type, ev.code, ev.value};
    if (rc == LIBEVDEV_READ_STATUS_SYNC) fail("unexpected SYN_DROPPED");
    if (rc != -EAGAIN) check(rc, "libevdev_next_event");
    pollfd p{fd, POLLIN, 0};
    int n = ::poll(&p, 1, timeout_ms);
    if (n < 0) fail("poll", errno);
    if (n == 0) fail("timed out waiting for an event");
  }
}

int run() {
  UinputPtr mouse = create_mouse();
  const char* node = libevdev_uinput_get_devnode(mouse.get());
  if (node == nullptr) fail("uinput device has no /dev/input node");

  Fd fd = open_or_fail(node, O_RDONLY | O_NONBLOCK);
  libevdev* raw = nullptr;
  check(libevdev_new_from_fd(fd.get(), &raw), std::string("libevdev_new_from_fd ") + node);
  EvdevPtr dev(raw);
  if (std::string(libevdev_get_name(dev.get())) != "pseudohaptic vm smoke mouse")
    fail("wrong device name on " + std::string(node));
  check(libevdev_grab(dev.get(), LIBEVDEV_GRAB), "EVIOCGRAB");

  // A second grab, through another open file, must fail with EBUSY while the first holds.
  {
    Fd other = open_or_fail(node, O_RDONLY | O_NONBLOCK);
    libevdev* raw2 = nullptr;
    check(libevdev_new_from_fd(other.get(), &raw2), "libevdev_new_from_fd (second)");
    EvdevPtr dev2(raw2);
    int rc = libevdev_grab(dev2.get(), LIBEVDEV_GRAB);
    if (rc != -EBUSY) fail("second EVIOCGRAB returned " + std::to_string(rc) + ", expected -EBUSY");
  }

  const std::vector<Event> sent = {
      {EV_REL, REL_X, 5},      {EV_REL, REL_Y, -3},   {EV_SYN, SYN_REPORT, 0}, {EV_REL, REL_WHEEL, 1},
      {EV_SYN, SYN_REPORT, 0}, {EV_KEY, BTN_LEFT, 1}, {EV_SYN, SYN_REPORT, 0}, {EV_KEY, BTN_LEFT, 0},
      {EV_SYN, SYN_REPORT, 0}, {EV_REL, REL_X, -120}, {EV_SYN, SYN_REPORT, 0},
  };
  for (const Event& e : sent)
    check(libevdev_uinput_write_event(mouse.get(), e.type, e.code, e.value), "libevdev_uinput_write_event");

  for (std::size_t i = 0; i < sent.size(); ++i) {
    Event got = next_event(dev.get(), fd.get(), 2000);
    const Event& want = sent[i];
    if (got.type != want.type || got.code != want.code || got.value != want.value) {
      fail("event " + std::to_string(i) + ": got " + describe(got) + ", expected " + describe(want));
    }
  }
  check(libevdev_grab(dev.get(), LIBEVDEV_UNGRAB), "EVIOCGRAB release");
  std::printf("uinput smoke: %zu events round-tripped (%s)\n", sent.size(), node);
  return 0;
}

}  // namespace

int main() {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uinput smoke: FAILED: %s\n", e.what());
    return 1;
  }
}
