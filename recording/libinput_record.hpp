// `libinput record` YAML files: read (the evdev device description and the evdev events of one device).
#pragma once

#include <istream>
#include <string>

#include "core/engine/device.hpp"
#include "recording/recording_error.hpp"

namespace ph {

// Files larger than this are refused before parsing (YAML is parsed whole).
// yaml-cpp builds the whole document, about 55 times the file in memory: 32 MiB is about 1.8 GB of RAM.
// Longer recordings: record with evemu-record, whose reader streams.
inline constexpr std::size_t kMaxLibinputRecordBytes = std::size_t{32} << 20;

// device_index that reads the first pointer of the file: device 0, unless device 0 has no REL_X/REL_Y and a
// later device has both, then the first such device (`libinput record --all` lists a keyboard or a power
// button before the mouse as often as not). A file with no pointer at all gives device 0.
inline constexpr std::size_t kFirstPointerDevice = static_cast<std::size_t>(-1);

// Which device was read, and how many the file holds.
struct LibinputDevices {
  std::size_t index = 0;
  std::size_t count = 0;
};

// Reads device `device_index` of the file (or kFirstPointerDevice). Throws RecordingError naming `origin`
// and the line ("ORIGIN:LINE: ..."), or `origin` alone where no line is at fault ("ORIGIN: ...": an empty
// or over-long input).
Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index = 0);
// The same with another size limit (tests use a small one).
Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index,
                               std::size_t max_bytes);
// The same, telling which device was read (`devices` may be null).
Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index,
                               std::size_t max_bytes, LibinputDevices* devices);

}  // namespace ph
