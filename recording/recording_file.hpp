// Reads a recording in either format, told apart by content: evemu starts with "# EVEMU" or a
// description line ("N:", "I:", ...), libinput record is YAML with "version:" and "devices:".
#pragma once

#include <filesystem>
#include <istream>
#include <string>

#include "core/device.hpp"
#include "recording/recording_error.hpp"

namespace ph {

enum class RecordingFormat { evemu, libinput_record };

RecordingFormat detect_recording_format(std::string_view start);
Recording read_recording(std::istream& in, const std::string& origin);
// "-" reads standard input.
Recording read_recording_file(const std::string& path);

}  // namespace ph
