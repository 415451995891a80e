// Shared by the programs that run inside the VM: a failure report and the "physical" mouse they create.
#pragma once

#include <cstdio>
#include <string>

#include "core/engine/device.hpp"

namespace ph::vm {

// Prints what went wrong, prefixed with the program's name; returns the exit status for main.
inline int fail(const char* program, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", program, what.c_str());
  return 1;
}

// A plain USB mouse: REL_X/REL_Y/REL_WHEEL, left and right buttons.
inline DeviceDescription vm_mouse(const std::string& name) {
  DeviceDescription d;
  d.name = name;
  d.bustype = 0x03;
  for (std::uint16_t type : {ev::kSyn, ev::kKey, ev::kRel}) d.enable(ev::kSyn, type);
  d.enable(ev::kKey, ev::kBtnLeft);
  d.enable(ev::kKey, ev::kBtnRight);
  for (std::uint16_t r : {ev::kRelX, ev::kRelY, ev::kRelWheel}) d.enable(ev::kRel, r);
  return d;
}

}  // namespace ph::vm
