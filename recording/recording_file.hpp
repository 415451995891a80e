// Reads a recording in either format, told apart by content: evemu starts with "# EVEMU" or a
// description line ("N:", "I:", ...), libinput record is YAML with "version:" and "devices:".
#pragma once

#include <filesystem>
#include <istream>
#include <optional>
#include <string>

#include "core/engine/device.hpp"
#include "recording/libinput_record.hpp"
#include "recording/recording_error.hpp"

namespace ph {

enum class RecordingFormat { evemu, libinput_record };

// What read_recording read: the format, the device (an index into the file's devices) and how many the
// file holds (an evemu recording holds one).
struct RecordingInfo {
  RecordingFormat format = RecordingFormat::evemu;
  std::size_t device_index = 0;
  std::size_t device_count = 1;
};

// The format told by the first line of `start` that is not blank or a comment; evemu where none is. With `complete`
// false (more may follow `start`), nothing where `start` holds only blank lines, comments and a line cut short.
std::optional<RecordingFormat> recording_format_of(std::string_view start, bool complete);
RecordingFormat detect_recording_format(std::string_view start);
// device_index: which device of a libinput record file, or kFirstPointerDevice (libinput_record.hpp); an
// evemu recording holds only device 0 (kFirstPointerDevice gives it too). `info` may be null.
Recording read_recording(std::istream& in, const std::string& origin, std::size_t device_index = 0,
                         RecordingInfo* info = nullptr);
// "-" reads standard input.
Recording read_recording_file(const std::string& path, std::size_t device_index = 0, RecordingInfo* info = nullptr);

}  // namespace ph
