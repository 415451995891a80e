// Run inside the VM (tests/vm/run-in-vm): the daemon's EvdevDevice on a real uinput mouse. It is seen as a
// pointer, a held button is reported before grabbing, the grab is exclusive, events are read in order,
// a flood that overflows the kernel's buffer (SYN_DROPPED) is resynchronised, and unplugging is noticed.
#include <cstdio>
#include <string>
#include <vector>

#include "daemon/evdev_device.hpp"
#include "tests/vm/vm_check.hpp"
#include "uinput/uinput_sink.hpp"

namespace {

constexpr const char* kProgram = "evdev device check";

ph::Frame frame(std::vector<ph::InputEvent> events) {
  events.push_back({0, ph::ev::kSyn, ph::ev::kSynReport, 0});
  return ph::Frame{std::move(events)};
}

}  // namespace

int main() {
  auto physical = std::make_unique<ph::UinputSink>(ph::vm::vm_mouse("pseudohaptic vm physical mouse"));
  ph::EvdevDevice device(physical->devnode());
  if (!device.is_pointer()) return ph::vm::fail(kProgram, "a REL_X/REL_Y/BTN_LEFT device is not seen as a pointer");
  if (device.description().name != "pseudohaptic vm physical mouse") return ph::vm::fail(kProgram, "wrong name");

  physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnLeft, 1}}));
  if (!device.any_key_held()) return ph::vm::fail(kProgram, "a held button was not reported");
  physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnLeft, 0}}));
  if (device.any_key_held()) return ph::vm::fail(kProgram, "a released button is still reported held");

  device.grab();
  ph::EvdevDevice other(physical->devnode());
  try {
    other.grab();
    return ph::vm::fail(kProgram, "a second grab succeeded");
  } catch (const ph::DeviceError&) {
  }

  std::vector<ph::InputEvent> got;
  auto collect = [&got](const ph::InputEvent& e) { got.push_back(e); };
  device.read_available(collect);  // the button frames from before the grab
  got.clear();
  physical->write(frame({{0, ph::ev::kRel, ph::ev::kRelX, 7}, {0, ph::ev::kRel, ph::ev::kRelY, -2}}));
  device.read_available(collect);
  if (got.size() != 3 || got[0].code != ph::ev::kRelX || got[0].value != 7 || got[1].value != -2) {
    return ph::vm::fail(kProgram, "events did not arrive in order");
  }

  // Overflow the kernel's per-client buffer, with a button pressed in the middle of it.
  for (int i = 0; i < 4000; ++i) {
    physical->write(frame({{0, ph::ev::kRel, ph::ev::kRelX, 1}}));
    if (i == 2000) physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnRight, 1}}));
  }
  got.clear();
  device.read_available(collect);
  bool dropped = false, right_down = false;
  for (const ph::InputEvent& e : got) {
    dropped = dropped || (e.type == ph::ev::kSyn && e.code == ph::ev::kSynDropped);
    right_down = right_down || (e.type == ph::ev::kKey && e.code == ph::ev::kBtnRight && e.value == 1);
  }
  if (!dropped) return ph::vm::fail(kProgram, "no SYN_DROPPED after 4000 unread frames");
  if (!right_down) return ph::vm::fail(kProgram, "the resync did not deliver the button pressed during the overflow");
  if (got.back().type != ph::ev::kSyn || got.back().code != ph::ev::kSynReport)
    return ph::vm::fail(kProgram, "stream does not end a frame");
  const std::size_t after_flood = got.size();

  physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnRight, 0}}));
  physical.reset();  // unplug
  got.clear();
  if (device.read_available(collect) != ph::ReadStatus::gone)
    return ph::vm::fail(kProgram, "unplugging was not noticed");
  std::printf(
      "evdev device check: pointer, held button, exclusive grab, order, SYN_DROPPED resync (%zu events "
      "after the flood), unplug\n",
      after_flood);
  return 0;
}
