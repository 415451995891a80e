// Input events as the kernel's evdev interface delivers them, with the few codes the engine needs.
// The core includes no Linux header: the values below are the kernel ABI (linux/input-event-codes.h),
// and a test in the daemon side checks them against the real header.
#pragma once

#include <cstdint>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph {

struct InputEvent {
  TimeUs time = 0;  // microseconds, as in the recording or the device's clock
  std::uint16_t type = 0;
  std::uint16_t code = 0;
  std::int32_t value = 0;
};

constexpr bool operator==(const InputEvent& a, const InputEvent& b) {
  return a.time == b.time && a.type == b.type && a.code == b.code && a.value == b.value;
}

namespace ev {
inline constexpr std::uint16_t kSyn = 0x00, kKey = 0x01, kRel = 0x02, kAbs = 0x03, kMsc = 0x04;
inline constexpr std::uint16_t kMaxType = 0x1f;
inline constexpr std::uint16_t kSynReport = 0, kSynConfig = 1, kSynMtReport = 2, kSynDropped = 3;
inline constexpr std::uint16_t kRelX = 0x00, kRelY = 0x01, kRelHWheel = 0x06, kRelWheel = 0x08;
inline constexpr std::uint16_t kRelWheelHiRes = 0x0b, kRelHWheelHiRes = 0x0c;
inline constexpr std::uint16_t kAbsX = 0x00, kAbsY = 0x01;
inline constexpr std::uint16_t kMscScan = 0x04;
inline constexpr std::uint16_t kBtnMouse = 0x110, kBtnLeft = 0x110, kBtnRight = 0x111, kBtnMiddle = 0x112;
inline constexpr std::uint16_t kMaxCode = 0x2ff;  // KEY_MAX, the largest code of any type
}  // namespace ev

// One evdev frame: the events up to and including its SYN_REPORT.
struct Frame {
  std::vector<InputEvent> events;
};

}  // namespace ph
