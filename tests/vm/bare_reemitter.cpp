// Run inside the VM by daemon_e2e: the baseline of the daemon's latency, the least a program that stands
// between a mouse and the desktop can do. It grabs the mouse, makes a virtual device with the mouse's
// capabilities, and then only re-emits: one blocking read() of whatever the mouse queued, one write() of
// it to uinput. No event loop, no frame assembly, no model.
//
//   bare_reemitter NODE NAME [poll]
//
// NODE: the mouse's /dev/input/eventN; NAME: the virtual device's name. With `poll` it waits in poll() and
// then reads, as an event loop must (one system call more per frame), instead of blocking in read(): the
// baseline for how much of a daemon's cost is that shape alone. Runs until killed.
#include <fcntl.h>
#include <libevdev/libevdev-uinput.h>
#include <libevdev/libevdev.h>
#include <linux/input.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace {

int fail(const char* what) {
  std::fprintf(stderr, "bare_reemitter: %s: %s\n", what, std::strerror(errno));
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  const bool wait_in_poll = argc == 4 && std::strcmp(argv[3], "poll") == 0;
  if (argc != 3 && !wait_in_poll) {
    std::fprintf(stderr, "usage: bare_reemitter NODE NAME [poll]\n");
    return 2;
  }
  const int in = ::open(argv[1], O_RDONLY | O_CLOEXEC);
  if (in < 0) return fail(argv[1]);
  libevdev* description = nullptr;
  if (const int rc = libevdev_new_from_fd(in, &description); rc < 0) {
    errno = -rc;
    return fail("libevdev_new_from_fd");
  }
  libevdev_set_name(description, argv[2]);
  libevdev_uinput* out = nullptr;
  if (const int rc = libevdev_uinput_create_from_device(description, LIBEVDEV_UINPUT_OPEN_MANAGED, &out); rc < 0) {
    errno = -rc;
    return fail("creating the uinput device");
  }
  if (::ioctl(in, EVIOCGRAB, 1) < 0) return fail("EVIOCGRAB");
  const int out_fd = libevdev_uinput_get_fd(out);
  std::array<input_event, 64> batch;
  for (;;) {
    if (wait_in_poll) {
      pollfd p{in, POLLIN, 0};
      if (::poll(&p, 1, -1) < 0 && errno != EINTR) return fail("poll");
    }
    const ssize_t n = ::read(in, batch.data(), sizeof batch);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return fail("read");
    if (::write(out_fd, batch.data(), static_cast<std::size_t>(n)) != n) return fail("write");
  }
}
