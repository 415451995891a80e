// Which keys and buttons a stream holds down, so that whoever closes an output device can release them
// first: nothing may stay pressed when the daemon exits or a device goes away.
#pragma once

#include <bitset>

#include "core/engine/event.hpp"

namespace ph {

class HeldKeys {
 public:
  void observe(const InputEvent& e) {
    if (e.type == ev::kKey && e.code <= ev::kMaxCode) held_.set(e.code, e.value != 0);
  }
  void observe(const Frame& frame) {
    for (const InputEvent& e : frame.events) observe(e);
  }
  bool any() const { return held_.any(); }
  bool held(std::uint16_t code) const { return code <= ev::kMaxCode && held_.test(code); }

  // A frame releasing every held key, in code order, then SYN_REPORT; empty when nothing is held.
  Frame release_all(TimeUs time) const {
    Frame frame;
    if (!held_.any()) return frame;
    for (std::uint16_t code = 0; code <= ev::kMaxCode; ++code) {
      if (held_.test(code)) frame.events.push_back({time, ev::kKey, code, 0});
    }
    frame.events.push_back({time, ev::kSyn, ev::kSynReport, 0});
    return frame;
  }

 private:
  std::bitset<ev::kMaxCode + 1> held_;
};

}  // namespace ph
