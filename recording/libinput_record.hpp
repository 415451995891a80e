// `libinput record` YAML files: read (the evdev device description and the evdev events of one device).
#pragma once

#include <istream>
#include <string>

#include "core/device.hpp"
#include "recording/recording_error.hpp"

namespace ph {

// Files larger than this are refused before parsing (YAML is parsed whole).
// yaml-cpp builds the whole document, about 55 times the file in memory: 32 MiB is about 1.8 GB of RAM.
// Longer recordings: record with evemu-record, whose reader streams.
inline constexpr std::size_t kMaxLibinputRecordBytes = std::size_t{32} << 20;

// Reads device `device_index` of the file. Throws RecordingError naming `origin` (and the line, where
// the YAML library reports one).
Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index = 0);
// The same with another size limit (tests use a small one).
Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index,
                               std::size_t max_bytes);

}  // namespace ph
