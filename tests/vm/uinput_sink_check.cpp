// Run inside the VM (tests/vm/run-in-vm): pseudohaptic's UinputSink on a real uinput device. Frames
// written to the sink come out of its evdev node unchanged, and a button still held when the sink is
// destroyed is released first, so that no button stays stuck when the daemon exits.
#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/engine/event.hpp"
#include "tests/vm/vm_check.hpp"
#include "uinput/uinput_sink.hpp"

namespace {

constexpr const char* kProgram = "uinput sink check";

// Reads events until `count` non-SYN events arrived, the device went away, or 2 s passed.
std::vector<input_event> read_events(libevdev* dev, int fd, std::size_t count) {
  std::vector<input_event> got;
  for (int waits = 0; got.size() < count && waits < 20; ++waits) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) < 0) break;
    input_event e;
    int rc;
    while ((rc = libevdev_next_event(dev, LIBEVDEV_READ_FLAG_NORMAL, &e)) == LIBEVDEV_READ_STATUS_SUCCESS) {
      if (e.type != EV_SYN) got.push_back(e);
    }
    if (rc != -EAGAIN) break;  // the device is gone (-ENODEV) or a read failed: nothing more will come
  }
  return got;
}

}  // namespace

int main() {
  auto sink = std::make_unique<ph::UinputSink>(ph::vm::vm_mouse("pseudohaptic vm check mouse"));
  const std::string node = sink->devnode();
  if (node.empty()) return ph::vm::fail(kProgram, "the kernel gave no device node");
  const int fd = open(node.c_str(), O_RDONLY | O_NONBLOCK);
  if (fd < 0) return ph::vm::fail(kProgram, "cannot open " + node);
  libevdev* raw = nullptr;
  if (libevdev_new_from_fd(fd, &raw) < 0) return ph::vm::fail(kProgram, "libevdev cannot read " + node);
  const ph::LibevdevPtr reader(raw);

  ph::Frame frame;
  frame.events = {{0, ph::ev::kRel, ph::ev::kRelX, 5},
                  {0, ph::ev::kRel, ph::ev::kRelY, -3},
                  {0, ph::ev::kKey, ph::ev::kBtnLeft, 1},
                  {0, ph::ev::kSyn, ph::ev::kSynReport, 0}};
  sink->write(frame);
  const auto first = read_events(reader.get(), fd, 3);
  if (first.size() != 3 || first[0].code != REL_X || first[0].value != 5 || first[1].code != REL_Y ||
      first[1].value != -3 || first[2].code != BTN_LEFT || first[2].value != 1) {
    return ph::vm::fail(kProgram, "the frame did not come out unchanged");
  }
  // BTN_LEFT is still down. Destroy the sink while reading, as the compositor would be.
  std::thread destroyer([&sink] { sink.reset(); });
  const auto last = read_events(reader.get(), fd, 1);
  destroyer.join();
  if (last.size() != 1 || last[0].type != EV_KEY || last[0].code != BTN_LEFT || last[0].value != 0) {
    return ph::vm::fail(kProgram, "the held button was not released before the device went away");
  }
  close(fd);
  std::printf("uinput sink check: frame passed through, held button released on destruction (%s)\n", node.c_str());
  return 0;
}
