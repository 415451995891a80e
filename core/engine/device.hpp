// What a recording says about its input device: identity, capabilities, axis ranges and state, enough to
// write an evemu header back or to create a virtual device like it.
#pragma once

#include <array>
#include <bitset>
#include <cstdint>
#include <map>
#include <string>

#include "core/engine/event.hpp"

namespace ph {

struct AbsInfo {
  std::int32_t minimum = 0, maximum = 0, fuzz = 0, flat = 0, resolution = 0;
  constexpr bool operator==(const AbsInfo&) const = default;
};

struct DeviceDescription {
  std::string name;
  std::uint16_t bustype = 0, vendor = 0, product = 0, version = 0;
  std::bitset<32> properties;                                         // INPUT_PROP_*
  std::array<std::bitset<ev::kMaxCode + 1>, ev::kMaxType + 1> codes;  // supported codes per event type
  std::map<std::uint16_t, AbsInfo> absinfo;                           // per ABS_* code
  std::map<std::uint16_t, std::int32_t> leds;                         // LED state (evemu "L:")
  std::map<std::uint16_t, std::int32_t> switches;                     // switch state (evemu "S:")

  bool has(std::uint16_t type, std::uint16_t code) const {
    return type <= ev::kMaxType && code <= ev::kMaxCode && codes[type].test(code);
  }
  void enable(std::uint16_t type, std::uint16_t code) {
    if (type <= ev::kMaxType && code <= ev::kMaxCode) codes[type].set(code);
  }
  bool operator==(const DeviceDescription&) const = default;
};

// A device and the events it sent, in order.
struct Recording {
  DeviceDescription device;
  std::vector<InputEvent> events;
};

}  // namespace ph
