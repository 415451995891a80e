// evemu recordings (evemu-record output), versions 1.0 to 1.3: read and write.
#pragma once

#include <istream>
#include <ostream>
#include <string>

#include "core/engine/device.hpp"
#include "recording/recording_error.hpp"

namespace ph {

// Lines longer than this are refused (a recording's longest line is well under 200 characters).
inline constexpr std::size_t kMaxEvemuLine = 4096;

// Reads a whole recording. `origin` names the input in errors ("FILE:LINE: ..."). Throws RecordingError.
Recording read_evemu(std::istream& in, const std::string& origin);

// Writes "# EVEMU 1.3", the description (N, I, P, B, A, L, S lines) and one "E:" line per event. Throws
// RecordingError, before writing anything, for what evemu cannot represent: a negative time, a type above
// 0x1f or a code above 0x2ff, a control character in the device name. codes[0] must hold the type mask.
void write_evemu(std::ostream& out, const Recording& recording);

}  // namespace ph
