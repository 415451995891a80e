// Errors of the recording readers and writers: "ORIGIN:LINE: what is wrong", or "ORIGIN: what is wrong"
// when no single line is at fault (an empty input, a missing description).
#pragma once

#include <stdexcept>
#include <string>

namespace ph {

class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ph
