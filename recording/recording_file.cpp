#include "recording/recording_file.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <system_error>

#include "recording/evemu.hpp"
#include "recording/libinput_record.hpp"

namespace ph {

std::optional<RecordingFormat> recording_format_of(std::string_view start, bool complete) {
  // Skip blank lines and YAML/evemu comments; the first meaningful line tells.
  std::size_t pos = 0;
  while (pos < start.size()) {
    const std::size_t newline = start.find('\n', pos);
    if (newline == std::string_view::npos && !complete) return std::nullopt;  // a line cut short: read on
    const std::size_t end = std::min(newline, start.size());
    const std::string_view line = start.substr(pos, end - pos);
    if (line.starts_with("# EVEMU")) return RecordingFormat::evemu;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first != std::string_view::npos && line[first] != '#') {
      // libinput record files start with their top-level YAML keys (or a YAML directive, or the document's
      // start); anything else is read as evemu, whose reader names the line it cannot make sense of.
      const std::string_view word = line.substr(first);
      for (std::string_view yaml_start :
           {"version:", "ndevices:", "libinput:", "system:", "devices:", "---", "%YAML"}) {
        if (word.starts_with(yaml_start)) return RecordingFormat::libinput_record;
      }
      return RecordingFormat::evemu;
    }
    pos = end + 1;
  }
  if (!complete) return std::nullopt;
  return RecordingFormat::evemu;  // empty input: the evemu reader says what is missing
}

RecordingFormat detect_recording_format(std::string_view start) { return *recording_format_of(start, true); }

namespace {

// Serves the bytes already read for format detection, then the rest of the original stream, so that a
// reader can stream the input (and refuse an over-long line) without the whole file in memory.
class PrefixedBuffer final : public std::streambuf {
 public:
  PrefixedBuffer(std::string head, std::streambuf* rest) : head_(std::move(head)), rest_(rest) {
    setg(head_.data(), head_.data(), head_.data() + head_.size());
  }

 protected:
  int_type underflow() override {
    const std::streamsize n = rest_->sgetn(chunk_, sizeof chunk_);
    if (n <= 0) return traits_type::eof();
    setg(chunk_, chunk_, chunk_ + n);
    return traits_type::to_int_type(*gptr());
  }

 private:
  std::string head_;
  std::streambuf* rest_;
  char chunk_[1 << 16];
};

}  // namespace

Recording read_recording(std::istream& in, const std::string& origin, std::size_t device_index, RecordingInfo* info) {
  // Read until the first meaningful line tells the format: a long comment at the start (a header of notes) is
  // read past, up to kMaxHead bytes.
  constexpr std::size_t kChunk = 4096, kMaxHead = std::size_t{1} << 20;
  std::string head;
  std::optional<RecordingFormat> format;
  while (!format) {
    const std::size_t had = head.size();
    head.resize(had + kChunk);
    in.read(head.data() + had, static_cast<std::streamsize>(kChunk));
    head.resize(had + static_cast<std::size_t>(in.gcount()));
    if (in.bad()) throw RecordingError(fmt::format("{}: read error", origin));
    // A UTF-8 byte order mark, which some editors write and YAML allows: not part of the first line.
    if (had == 0 && head.starts_with("\xEF\xBB\xBF")) head.erase(0, 3);
    format = recording_format_of(head, in.eof() || head.size() >= kMaxHead);
  }
  PrefixedBuffer buffer(std::move(head), in.rdbuf());
  std::istream whole(&buffer);
  if (*format == RecordingFormat::libinput_record) {
    LibinputDevices devices;
    Recording recording = read_libinput_record(whole, origin, device_index, kMaxLibinputRecordBytes, &devices);
    if (info != nullptr) *info = {*format, devices.index, devices.count};
    return recording;
  }
  if (device_index != 0 && device_index != kFirstPointerDevice) {
    throw RecordingError(
        fmt::format("{}: no device {}: an evemu recording holds one device (0)", origin, device_index));
  }
  Recording recording = read_evemu(whole, origin);
  if (info != nullptr) *info = {*format, 0, 1};
  return recording;
}

Recording read_recording_file(const std::string& path, std::size_t device_index, RecordingInfo* info) {
  if (path == "-") return read_recording(std::cin, "<stdin>", device_index, info);
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw RecordingError(fmt::format("{}: cannot open: {}", path, std::strerror(error)));
  }
  // A folder opens, and then fails to read with no reason given: said here, as the scene file's reader says it.
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored))
    throw RecordingError(fmt::format("{}: is a folder, not a recording", path));
  return read_recording(in, path, device_index, info);
}

}  // namespace ph
