// Errors of the recording readers and writers: "ORIGIN:LINE: what is wrong", or "ORIGIN: what is wrong"
// when no single line is at fault (an empty input, a missing description).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace ph {

// Device names longer than this are refused by the readers and the writer, so that every line a writer
// produces reads back (the kernel's uinput keeps 80 bytes of a name; evdev names are far shorter in practice).
inline constexpr std::size_t kMaxDeviceName = 1024;

class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ph
