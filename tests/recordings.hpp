// Recordings for the tests: a mouse description and scripted streams of frames the tests generate, and the
// paths of the real recordings kept in tests/data/recordings.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/device.hpp"

namespace ph::testing {

inline DeviceDescription test_mouse() {
  DeviceDescription d;
  d.name = "pseudohaptic test mouse";
  d.bustype = 0x03;
  d.vendor = 0x1234;
  d.product = 0x5678;
  d.version = 0x0111;
  for (std::uint16_t type : {ev::kSyn, ev::kKey, ev::kRel, ev::kMsc}) d.enable(ev::kSyn, type);
  for (std::uint16_t b : {ev::kBtnLeft, ev::kBtnRight, ev::kBtnMiddle}) d.enable(ev::kKey, b);
  for (std::uint16_t r :
       {ev::kRelX, ev::kRelY, ev::kRelWheel, ev::kRelHWheel, ev::kRelWheelHiRes, ev::kRelHWheelHiRes}) {
    d.enable(ev::kRel, r);
  }
  d.enable(ev::kMsc, ev::kMscScan);
  return d;
}

// Appends one frame at time t: the given events, then SYN_REPORT.
inline void add_frame(Recording& r, TimeUs t, std::vector<InputEvent> events) {
  for (InputEvent& e : events) {
    e.time = t;
    r.events.push_back(e);
  }
  r.events.push_back({t, ev::kSyn, ev::kSynReport, 0});
}

inline InputEvent rel(std::uint16_t code, std::int32_t v) { return {0, ev::kRel, code, v}; }
inline InputEvent key(std::uint16_t code, std::int32_t v) { return {0, ev::kKey, code, v}; }
inline InputEvent scan(std::int32_t v) { return {0, ev::kMsc, ev::kMscScan, v}; }

// A stroke of `frames` frames of (dx, dy) counts every 8 ms, with a click, wheel, hi-res wheel and a
// SYN_DROPPED partial frame along the way.
inline Recording scripted_stroke(int frames, std::int32_t dx, std::int32_t dy, TimeUs t0 = 1'000'000) {
  Recording r;
  r.device = test_mouse();
  for (int i = 0; i < frames; ++i) {
    const TimeUs t = t0 + 8000 * i;
    std::vector<InputEvent> events;
    if (dx != 0) events.push_back(rel(ev::kRelX, dx));
    if (dy != 0) events.push_back(rel(ev::kRelY, dy));
    if (i == frames / 4) events.insert(events.begin(), {scan(0x90001), key(ev::kBtnLeft, 1)});
    if (i == frames / 4 + 5) events.insert(events.begin(), {scan(0x90001), key(ev::kBtnLeft, 0)});
    if (i == frames / 2) events.insert(events.end(), {rel(ev::kRelWheel, -1), rel(ev::kRelWheelHiRes, -120)});
    if (i == frames / 2 + 1) events = {rel(ev::kRelHWheel, 1), rel(ev::kRelHWheelHiRes, 60)};
    add_frame(r, t, events);
    if (i == (3 * frames) / 4) {
      // A buffer overrun: SYN_DROPPED, the tail of a frame, its SYN_REPORT.
      r.events.push_back({t + 1, ev::kSyn, ev::kSynDropped, 0});
      r.events.push_back({t + 2, ev::kRel, ev::kRelX, 7});
      r.events.push_back({t + 2, ev::kSyn, ev::kSynReport, 0});
    }
  }
  return r;
}

// The two real mouse recordings kept in the repository (tests/data/recordings/README.md: where they come
// from, their MIT licence). Every clone has them, so a test that reads them asserts that they are there
// (missing_file) and fails, rather than skips, when they are not.
inline std::vector<std::filesystem::path> recorded_mice() {
  const std::filesystem::path dir = PH_RECORDINGS_DIR;
  return {dir / "ps2-generic-mouse.evemu", dir / "saitek-cyborg-rat5.evemu"};
}

// "" when every path is a regular file; otherwise a message naming the first one missing.
inline std::string missing_file(const std::vector<std::filesystem::path>& paths) {
  for (const std::filesystem::path& path : paths) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return path.string() + " is missing (tests/data/recordings)";
  }
  return {};
}

}  // namespace ph::testing
