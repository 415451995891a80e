// Run inside the VM (tests/vm/run-in-vm): the daemon's EvdevDevice on a real uinput mouse. It is seen as a
// pointer, a held button is reported before grabbing, the grab is exclusive, events are read in order,
// a flood that overflows the kernel's buffer (SYN_DROPPED) is resynchronised, and unplugging is noticed.
#include <cstdio>
#include <string>
#include <vector>

#include "daemon/evdev_device.hpp"
#include "uinput/uinput_sink.hpp"

namespace {

int fail(const std::string& what) {
  std::fprintf(stderr, "evdev device check: %s\n", what.c_str());
  return 1;
}

ph::DeviceDescription mouse() {
  ph::DeviceDescription d;
  d.name = "pseudohaptic vm physical mouse";
  d.bustype = 0x03;
  for (std::uint16_t type : {ph::ev::kSyn, ph::ev::kKey, ph::ev::kRel}) d.enable(ph::ev::kSyn, type);
  d.enable(ph::ev::kKey, ph::ev::kBtnLeft);
  d.enable(ph::ev::kKey, ph::ev::kBtnRight);
  for (std::uint16_t r : {ph::ev::kRelX, ph::ev::kRelY, ph::ev::kRelWheel}) d.enable(ph::ev::kRel, r);
  return d;
}

ph::Frame frame(std::vector<ph::InputEvent> events) {
  events.push_back({0, ph::ev::kSyn, ph::ev::kSynReport, 0});
  return ph::Frame{std::move(events)};
}

}  // namespace

int main() {
  auto physical = std::make_unique<ph::UinputSink>(mouse());
  ph::EvdevDevice device(physical->devnode());
  if (!device.is_pointer()) return fail("a REL_X/REL_Y/BTN_LEFT device is not seen as a pointer");
  if (device.description().name != "pseudohaptic vm physical mouse") return fail("wrong name");

  physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnLeft, 1}}));
  if (!device.any_key_held()) return fail("a held button was not reported");
  physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnLeft, 0}}));
  if (device.any_key_held()) return fail("a released button is still reported held");

  device.grab();
  ph::EvdevDevice other(physical->devnode());
  try {
    other.grab();
    return fail("a second grab succeeded");
  } catch (const ph::DeviceError&) {
  }

  std::vector<ph::InputEvent> got;
  auto collect = [&got](const ph::InputEvent& e) { got.push_back(e); };
  device.read_available(collect);  // the button frames from before the grab
  got.clear();
  physical->write(frame({{0, ph::ev::kRel, ph::ev::kRelX, 7}, {0, ph::ev::kRel, ph::ev::kRelY, -2}}));
  device.read_available(collect);
  if (got.size() != 3 || got[0].code != ph::ev::kRelX || got[0].value != 7 || got[1].value != -2) {
    return fail("events did not arrive in order");
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
  if (!dropped) return fail("no SYN_DROPPED after 4000 unread frames");
  if (!right_down) return fail("the resync did not deliver the button pressed during the overflow");
  if (got.back().type != ph::ev::kSyn || got.back().code != ph::ev::kSynReport)
    return fail("stream does not end a frame");
  const std::size_t after_flood = got.size();

  physical->write(frame({{0, ph::ev::kKey, ph::ev::kBtnRight, 0}}));
  physical.reset();  // unplug
  got.clear();
  if (device.read_available(collect) != ph::ReadStatus::gone) return fail("unplugging was not noticed");
  std::printf(
      "evdev device check: pointer, held button, exclusive grab, order, SYN_DROPPED resync (%zu events "
      "after the flood), unplug\n",
      after_flood);
  return 0;
}
