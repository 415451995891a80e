// evemu recordings. The reader streams its input line by line and never holds more than one line of
// kMaxEvemuLine characters, so a hostile input costs bounded memory; every mistake is reported as
// "ORIGIN:LINE: what is wrong; what was expected". The writer formats into a buffer and writes it in
// large blocks (a recording can hold millions of events).
#include "recording/evemu.hpp"

#include <fmt/compile.h>
#include <fmt/format.h>

#include <array>
#include <bitset>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <string_view>
#include <system_error>
#include <vector>

namespace ph {
namespace {

using std::string_view;

constexpr std::int64_t kMicrosPerSecond = 1'000'000;

// ------------------------------------------------------------------------------------------------------------
// Errors

// Where the reader is, for messages of the form "ORIGIN:LINE: what".
struct Position {
  const std::string& origin;
  std::size_t line = 0;

  [[noreturn]] void fail(string_view what) const { throw RecordingError(fmt::format("{}:{}: {}", origin, line, what)); }
};

// A piece of the input for a message: short, so that a 4096-character field does not flood the terminal.
std::string quoted(string_view text) {
  constexpr std::size_t kShown = 32;
  if (text.size() <= kShown) return fmt::format("'{}'", text);
  return fmt::format("'{}...'", text.substr(0, kShown));
}

// ------------------------------------------------------------------------------------------------------------
// Lines

constexpr bool is_blank(char c) { return c == ' ' || c == '\t'; }

// Text is printable ASCII, tabs and (in names and comments) UTF-8; other control bytes mean binary data.
constexpr bool is_binary(char c) {
  const auto byte = static_cast<unsigned char>(c);
  return (byte < 0x20 && c != '\t') || byte == 0x7f;
}

// Splits a stream into lines. Reads in blocks and copies at most kMaxEvemuLine + 1 characters of a line,
// so one endless line fails after a few kilobytes instead of exhausting memory.
class LineReader {
 public:
  LineReader(std::istream& in, Position& position) : in_(in), position_(position) {
    line_.reserve(kMaxEvemuLine + 1);  // + 1: the '\r' of a CRLF line end
  }

  // The next line without "\n" or "\r\n"; false at the end of the input. Advances position.line.
  bool next(string_view& line) {
    ++position_.line;
    if (!read_line()) {
      --position_.line;
      return false;
    }
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    if (line_.size() > kMaxEvemuLine) fail_too_long();
    check_text(line_);
    line = line_;
    return true;
  }

 private:
  // Appends the input up to the next '\n' (consumed, not stored) to line_; false when there was no input.
  bool read_line() {
    line_.clear();
    bool read_any = false;
    for (;;) {
      if (begin_ == end_ && !refill()) return read_any;
      read_any = true;
      const char* start = block_.data() + begin_;
      const std::size_t available = end_ - begin_;
      const auto* newline = static_cast<const char*>(std::memchr(start, '\n', available));
      const std::size_t length = newline != nullptr ? static_cast<std::size_t>(newline - start) : available;
      if (line_.size() + length > kMaxEvemuLine + 1) {
        // A file of old Mac line endings is one long line: said as such, not as a line too long. (A carriage return
        // that ends a line before its newline is CRLF's.)
        const std::size_t scanned = newline != nullptr && length > 0 && start[length - 1] == '\r' ? length - 1 : length;
        if (line_.find('\r') != std::string::npos || std::memchr(start, '\r', scanned) != nullptr)
          fail_carriage_return();
        fail_too_long();
      }
      line_.append(start, length);
      begin_ += length;
      if (newline != nullptr) {
        ++begin_;
        return true;
      }
    }
  }

  bool refill() {
    in_.read(block_.data(), static_cast<std::streamsize>(block_.size()));
    const std::streamsize count = in_.gcount();
    if (in_.bad()) position_.fail("read error");
    begin_ = 0;
    end_ = count > 0 ? static_cast<std::size_t>(count) : 0;
    return end_ > 0;
  }

  [[noreturn]] void fail_too_long() const {
    position_.fail(fmt::format("line longer than {} characters; is this an evemu recording?", kMaxEvemuLine));
  }

  [[noreturn]] void fail_carriage_return() const {
    position_.fail(
        "a carriage return that does not end a line (old Mac line endings?): lines end with a newline, or a carriage "
        "return and a newline");
  }

  void check_text(string_view text) const {
    for (const char c : text) {
      if (c == '\r') fail_carriage_return();
      if (is_binary(c)) {
        position_.fail(fmt::format("binary data (byte 0x{:02x}); expected an evemu text recording",
                                   static_cast<unsigned char>(c)));
      }
    }
  }

  std::istream& in_;
  Position& position_;
  std::vector<char> block_ = std::vector<char>(std::size_t{1} << 16);
  std::size_t begin_ = 0, end_ = 0;  // unread part of block_
  std::string line_;
};

string_view skip_blanks(string_view text) {
  std::size_t first = 0;
  while (first < text.size() && is_blank(text[first])) ++first;
  return text.substr(first);
}

// Comments run from '#' to the end of the line (evemu 1.1 on; earlier files simply have none there).
string_view strip_comment(string_view text) { return text.substr(0, text.find('#')); }

// The whitespace-separated fields of one line.
class Fields {
 public:
  explicit Fields(string_view text) : rest_(text) {}

  bool next(string_view& field) {
    rest_ = skip_blanks(rest_);
    if (rest_.empty()) return false;
    std::size_t end = 0;
    while (end < rest_.size() && !is_blank(rest_[end])) ++end;
    field = rest_.substr(0, end);
    rest_.remove_prefix(end);
    return true;
  }

 private:
  string_view rest_;
};

// ------------------------------------------------------------------------------------------------------------
// Numbers

enum class NumberError { none, malformed, out_of_range };

// Parses all of `text` as an unsigned number; out-of-range values come back as the type's maximum.
template <typename T>
NumberError parse_unsigned(string_view text, int base, T& value) {
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value, base);
  if (stop != end || error == std::errc::invalid_argument) return NumberError::malformed;
  if (error == std::errc::result_out_of_range) {
    value = std::numeric_limits<T>::max();
    return NumberError::out_of_range;
  }
  return NumberError::none;
}

// The syntax of each line, for "expected ..." in messages.
constexpr string_view kIdSyntax = "'I: <bustype> <vendor> <product> <version>' (hex)";
constexpr string_view kPropSyntax = "'P:' and 8 hex bytes";
constexpr string_view kMaskSyntax = "'B: <type>' and 8 hex bytes";
constexpr string_view kAbsSyntax = "'A: <code> <min> <max> <fuzz> <flat> [<resolution>]'";
constexpr string_view kLedSyntax = "'L: <code> <state>'";
constexpr string_view kSwitchSyntax = "'S: <code> <state>'";
constexpr string_view kEventSyntax = "'E: <sec>.<usec> <type> <code> <value>'";

// ------------------------------------------------------------------------------------------------------------
// Reading

class EvemuParser {
 public:
  explicit EvemuParser(Position& position) : at_(position) {}

  void parse_line(string_view line) {
    const string_view text = skip_blanks(line);
    if (text.empty()) return;
    if (text[0] == '#') {
      if (at_.line == 1) check_version(text);
      return;
    }
    if (text.size() < 2 || text[1] != ':') fail_unknown(text);
    has_data_ = true;
    const char kind = text[0];
    if (kind == 'E') return parse_event(strip_comment(text.substr(2)));
    if (kind == 'N') return parse_name(text.substr(2));  // a '#' in a name is part of it
    const string_view data = strip_comment(text.substr(2));
    switch (kind) {
      case 'I':
        return parse_id(data);
      case 'P':
        return parse_properties(data);
      case 'B':
        return parse_mask(data);
      case 'A':
        return parse_absinfo(data);
      case 'L':
        return parse_state(data, recording_.device.leds, kLedSyntax);
      case 'S':
        return parse_state(data, recording_.device.switches, kSwitchSyntax);
      default:
        fail_unknown(text);
    }
  }

  Recording finish() {
    if (!has_data_) throw RecordingError(fmt::format("{}: empty recording", at_.origin));
    if (!has_name_) {
      throw RecordingError(fmt::format("{}: no device description (expected an 'N: <name>' line)", at_.origin));
    }
    return std::move(recording_);
  }

 private:
  // "# EVEMU <major>.<minor>" on the first line gives the format version; this reader knows 1.0 to 1.3 and
  // accepts the later minor versions' lines in any 1.x file.
  void check_version(string_view comment) const {
    constexpr string_view kMagic = "# EVEMU";
    if (!comment.starts_with(kMagic) || (comment.size() > kMagic.size() && !is_blank(comment[kMagic.size()]))) return;
    Fields fields(comment.substr(kMagic.size()));
    string_view version, extra;
    const bool one_field = fields.next(version) && !fields.next(extra);
    const std::size_t dot = version.find('.');
    unsigned major = 0, minor = 0;
    const bool ok = one_field && dot != string_view::npos &&
                    parse_unsigned(version.substr(0, dot), 10, major) == NumberError::none &&
                    parse_unsigned(version.substr(dot + 1), 10, minor) == NumberError::none;
    if (!ok) at_.fail("bad version line; expected '# EVEMU <major>.<minor>'");
    if (major != 1) at_.fail(fmt::format("evemu format version {} is not supported; expected 1.x", version));
  }

  [[noreturn]] void fail_unknown(string_view text) const {
    at_.fail(
        fmt::format("unknown line {}; expected N:, I:, P:, B:, A:, L:, S: or E: and its fields, or a "
                    "'#' comment",
                    quoted(text)));
  }

  // Description lines come before the events: a replay creates the device, then sends the events.
  void start_description_line(char kind) const {
    if (!recording_.events.empty()) {
      at_.fail(
          fmt::format("'{}:' line after the first event; the device description (N, I, P, B, A, L, S "
                      "lines) comes before the events",
                      kind));
    }
  }

  string_view need_field(Fields& fields, string_view syntax) const {
    string_view field;
    if (!fields.next(field)) at_.fail(fmt::format("missing field; expected {}", syntax));
    return field;
  }

  void need_end(Fields& fields, string_view syntax) const {
    string_view extra;
    if (fields.next(extra))
      at_.fail(fmt::format("unexpected {} after the last field; expected {}", quoted(extra), syntax));
  }

  std::uint32_t hex(string_view field, std::uint32_t max, string_view what) const {
    std::uint32_t value = 0;
    const NumberError error = parse_unsigned(field, 16, value);
    if (error == NumberError::malformed) {
      at_.fail(fmt::format("bad {} {}; expected a hex number (without 0x)", what, quoted(field)));
    }
    if (error == NumberError::out_of_range || value > max) {
      at_.fail(fmt::format("{} {} out of range; expected at most {:x}", what, quoted(field), max));
    }
    return value;
  }

  std::int32_t int32(string_view field, string_view what) const {
    // from_chars takes no '+', evemu's sscanf does.
    const string_view digits = field.size() > 1 && field[0] == '+' && field[1] != '-' ? field.substr(1) : field;
    std::int32_t value = 0;
    const char* end = digits.data() + digits.size();
    const auto [stop, error] = std::from_chars(digits.data(), end, value, 10);
    if (stop != end || error == std::errc::invalid_argument) {
      at_.fail(fmt::format("bad {} {}; expected a decimal integer", what, quoted(field)));
    }
    if (error == std::errc::result_out_of_range) {
      at_.fail(fmt::format("{} {} outside the 32-bit range [-2147483648, 2147483647]", what, quoted(field)));
    }
    return value;
  }

  std::uint16_t type_field(string_view field) const {
    return static_cast<std::uint16_t>(hex(field, ev::kMaxType, "event type"));
  }
  std::uint16_t code_field(string_view field) const {
    return static_cast<std::uint16_t>(hex(field, ev::kMaxCode, "event code"));
  }

  void parse_name(string_view rest) {
    start_description_line('N');
    if (has_name_) at_.fail("second 'N:' line; expected one device per recording");
    has_name_ = true;
    const string_view name = skip_blanks(rest);
    if (name.size() > kMaxDeviceName)
      at_.fail(fmt::format("device name of {} characters; at most {} are allowed", name.size(), kMaxDeviceName));
    recording_.device.name = std::string(name);
  }

  void parse_id(string_view data) {
    start_description_line('I');
    if (has_id_) at_.fail("second 'I:' line; expected one device per recording");
    has_id_ = true;
    Fields fields(data);
    DeviceDescription& device = recording_.device;
    constexpr std::uint32_t kMax = 0xffff;
    device.bustype = static_cast<std::uint16_t>(hex(need_field(fields, kIdSyntax), kMax, "bus type"));
    device.vendor = static_cast<std::uint16_t>(hex(need_field(fields, kIdSyntax), kMax, "vendor"));
    device.product = static_cast<std::uint16_t>(hex(need_field(fields, kIdSyntax), kMax, "product"));
    device.version = static_cast<std::uint16_t>(hex(need_field(fields, kIdSyntax), kMax, "version"));
    need_end(fields, kIdSyntax);
  }

  std::array<std::uint8_t, 8> eight_bytes(Fields& fields, string_view syntax) const {
    std::array<std::uint8_t, 8> bytes{};
    for (auto& byte : bytes) byte = static_cast<std::uint8_t>(hex(need_field(fields, syntax), 0xff, "byte"));
    need_end(fields, syntax);
    return bytes;
  }

  // Bitmasks come as bytes like EVIOCGBIT's (bit n is bit n % 8 of byte n / 8), 8 per line; consecutive
  // lines continue the mask. Bits past what the description holds must be clear.
  template <std::size_t N>
  void store_mask_bytes(std::bitset<N>& mask, std::size_t& next_byte, const std::array<std::uint8_t, 8>& bytes,
                        string_view what) const {
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      for (std::size_t bit_in_byte = 0; bit_in_byte < 8; ++bit_in_byte) {
        if (((bytes[i] >> bit_in_byte) & 1U) == 0) continue;
        const std::size_t bit = (next_byte + i) * 8 + bit_in_byte;
        if (bit >= N) at_.fail(fmt::format("{} bit {:#x} set; expected bits up to {:#x} only", what, bit, N - 1));
        mask.set(bit);
      }
    }
    next_byte += bytes.size();
  }

  void parse_properties(string_view data) {
    start_description_line('P');
    Fields fields(data);
    store_mask_bytes(recording_.device.properties, property_bytes_, eight_bytes(fields, kPropSyntax), "input property");
  }

  void parse_mask(string_view data) {
    start_description_line('B');
    Fields fields(data);
    const std::uint16_t type = type_field(need_field(fields, kMaskSyntax));
    const std::string what = type == ev::kSyn ? std::string("event type mask") : fmt::format("type {:#04x} code", type);
    store_mask_bytes(recording_.device.codes[type], mask_bytes_[type], eight_bytes(fields, kMaskSyntax), what);
  }

  void parse_absinfo(string_view data) {
    start_description_line('A');
    Fields fields(data);
    const std::uint16_t code = code_field(need_field(fields, kAbsSyntax));
    AbsInfo info;
    info.minimum = int32(need_field(fields, kAbsSyntax), "minimum");
    info.maximum = int32(need_field(fields, kAbsSyntax), "maximum");
    info.fuzz = int32(need_field(fields, kAbsSyntax), "fuzz");
    info.flat = int32(need_field(fields, kAbsSyntax), "flat");
    string_view resolution;  // evemu 1.2 on
    if (fields.next(resolution)) info.resolution = int32(resolution, "resolution");
    need_end(fields, kAbsSyntax);
    recording_.device.absinfo[code] = info;
  }

  void parse_state(string_view data, std::map<std::uint16_t, std::int32_t>& states, string_view syntax) {
    start_description_line(syntax[1]);
    Fields fields(data);
    const std::uint16_t code = code_field(need_field(fields, syntax));
    const std::int32_t state = int32(need_field(fields, syntax), "state");
    need_end(fields, syntax);
    states[code] = state;
  }

  // "<sec>.<usec>", absolute or zero-based; kept as given (also when it goes backwards).
  TimeUs event_time(string_view field) const {
    const std::size_t dot = field.find('.');
    if (dot == string_view::npos) at_.fail(fmt::format("bad time {}; expected <sec>.<usec>", quoted(field)));
    if (field[0] == '-') at_.fail(fmt::format("negative time {}; expected seconds >= 0", quoted(field)));
    std::uint64_t seconds = 0, micros = 0;
    if (parse_unsigned(field.substr(0, dot), 10, seconds) == NumberError::malformed ||
        parse_unsigned(field.substr(dot + 1), 10, micros) == NumberError::malformed) {
      at_.fail(fmt::format("bad time {}; expected <sec>.<usec> in decimal digits", quoted(field)));
    }
    if (micros >= kMicrosPerSecond) {
      at_.fail(fmt::format("microseconds of time {} not below 1000000; expected <sec>.<usec>", quoted(field)));
    }
    constexpr auto kMaxTime = static_cast<std::uint64_t>(std::numeric_limits<TimeUs>::max());
    if (seconds > (kMaxTime - micros) / kMicrosPerSecond) {
      at_.fail(fmt::format("time {} too large; expected at most 9223372036854.775807", quoted(field)));
    }
    return static_cast<TimeUs>(seconds * kMicrosPerSecond + micros);
  }

  void parse_event(string_view data) {
    if (!has_name_) at_.fail("event before the device description; expected an 'N: <name>' line first");
    Fields fields(data);
    InputEvent event;
    event.time = event_time(need_field(fields, kEventSyntax));
    event.type = type_field(need_field(fields, kEventSyntax));
    event.code = code_field(need_field(fields, kEventSyntax));
    event.value = int32(need_field(fields, kEventSyntax), "event value");
    need_end(fields, kEventSyntax);
    recording_.events.push_back(event);
  }

  Position& at_;
  Recording recording_;
  bool has_data_ = false, has_name_ = false, has_id_ = false;
  std::size_t property_bytes_ = 0;                          // bytes of the "P:" mask so far
  std::array<std::size_t, ev::kMaxType + 1> mask_bytes_{};  // bytes of each type's "B:" mask so far
};

// ------------------------------------------------------------------------------------------------------------
// Writing

using Buffer = fmt::memory_buffer;

// The largest code of the masks evemu writes (the kernel's EVIOCGBIT sizes, in 64-bit words): with these
// line counts a written file looks like evemu-record's.
struct EvemuMask {
  std::uint16_t type, max_code;
};
constexpr std::array<EvemuMask, 9> kEvemuMasks{{{0x00, 0x1f},
                                                {0x01, 0x2ff},
                                                {0x02, 0x0f},
                                                {0x03, 0x3f},
                                                {0x04, 0x07},
                                                {0x05, 0x10},
                                                {0x11, 0x0f},
                                                {0x12, 0x07},
                                                {0x15, 0x7f}}};

constexpr std::size_t kBitsPerLine = 64;

template <std::size_t N>
std::size_t highest_bit_count(const std::bitset<N>& mask) {
  for (std::size_t bit = N; bit > 0; --bit) {
    if (mask.test(bit - 1)) return bit;
  }
  return 0;
}

// Lines of 8 bytes for a type: evemu's count, or more where higher bits are set; 0 skips the type.
std::size_t mask_lines(const DeviceDescription& device, std::uint16_t type) {
  std::size_t bits = highest_bit_count(device.codes[type]);
  for (const EvemuMask& mask : kEvemuMasks) {
    if (mask.type == type) bits = std::max<std::size_t>(bits, mask.max_code + 1U);
  }
  return (bits + kBitsPerLine - 1) / kBitsPerLine;
}

template <std::size_t N>
unsigned mask_byte(const std::bitset<N>& mask, std::size_t index) {
  unsigned byte = 0;
  for (std::size_t bit = 0; bit < 8; ++bit) {
    const std::size_t position = index * 8 + bit;
    if (position < N && mask.test(position)) byte |= 1U << bit;
  }
  return byte;
}

template <std::size_t N>
void append_mask_line(Buffer& out, const std::bitset<N>& mask, std::size_t line) {
  for (std::size_t i = 0; i < 8; ++i) fmt::format_to(std::back_inserter(out), " {:02x}", mask_byte(mask, line * 8 + i));
  out.push_back('\n');
}

// The format is line-based and has no escapes, and the reader refuses codes it cannot store: refuse to
// write what would not read back, before writing anything.
void check_writable(const Recording& recording) {
  const DeviceDescription& device = recording.device;
  if (device.name.size() > kMaxDeviceName) {
    throw RecordingError(fmt::format("cannot write evemu: the device name has {} characters, more than {}",
                                     device.name.size(), kMaxDeviceName));
  }
  for (const char c : device.name) {
    if (is_binary(c)) throw RecordingError("cannot write evemu: the device name contains a control character");
  }
  for (const auto* states : {&device.leds, &device.switches}) {
    for (const auto& [code, state] : *states) {
      if (code > ev::kMaxCode)
        throw RecordingError(fmt::format("cannot write evemu: LED/switch code {:#x} above 0x2ff", code));
    }
  }
  for (const auto& [code, info] : device.absinfo) {
    if (code > ev::kMaxCode) throw RecordingError(fmt::format("cannot write evemu: axis code {:#x} above 0x2ff", code));
  }
  for (std::size_t i = 0; i < recording.events.size(); ++i) {
    const InputEvent& event = recording.events[i];
    if (event.time < 0) {
      throw RecordingError(fmt::format("cannot write evemu: event {} has negative time {} us", i, event.time));
    }
    if (event.type > ev::kMaxType || event.code > ev::kMaxCode) {
      throw RecordingError(fmt::format("cannot write evemu: event {} has type {:#x} code {:#x}, above 0x1f/0x2ff", i,
                                       event.type, event.code));
    }
  }
}

void append_description(Buffer& out, const DeviceDescription& device) {
  auto to = std::back_inserter(out);
  fmt::format_to(to, "# EVEMU 1.3\n# Input device name: \"{}\"\n", device.name);
  fmt::format_to(to, "# Input device ID: bus {:#04x} vendor {:#06x} product {:#06x} version {:#06x}\n", device.bustype,
                 device.vendor, device.product, device.version);
  fmt::format_to(to, "# Written by pseudohaptic; times are seconds.microseconds as recorded\n");
  fmt::format_to(to, "N: {}\nI: {:04x} {:04x} {:04x} {:04x}\n", device.name, device.bustype, device.vendor,
                 device.product, device.version);
  fmt::format_to(to, "P:");
  append_mask_line(out, device.properties, 0);  // 32 properties fit in one line, as evemu writes them
  for (std::uint16_t type = 0; type <= ev::kMaxType; ++type) {
    for (std::size_t line = 0, lines = mask_lines(device, type); line < lines; ++line) {
      fmt::format_to(to, "B: {:02x}", type);
      append_mask_line(out, device.codes[type], line);
    }
  }
  for (const auto& [code, a] : device.absinfo) {
    fmt::format_to(to, "A: {:02x} {} {} {} {} {}\n", code, a.minimum, a.maximum, a.fuzz, a.flat, a.resolution);
  }
  for (const auto& [code, state] : device.leds) fmt::format_to(to, "L: {:02x} {}\n", code, state);
  for (const auto& [code, state] : device.switches) fmt::format_to(to, "S: {:02x} {}\n", code, state);
}

void append_event(Buffer& out, const InputEvent& event) {
  // evemu's "E: %lu.%06u %04x %04x %04d": -1 is "-001".
  fmt::format_to(std::back_inserter(out), FMT_COMPILE("E: {}.{:06} {:04x} {:04x} {:04}\n"),
                 event.time / kMicrosPerSecond, event.time % kMicrosPerSecond, event.type, event.code, event.value);
}

void flush(std::ostream& out, Buffer& buffer) {
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  buffer.clear();
}

}  // namespace

Recording read_evemu(std::istream& in, const std::string& origin) {
  Position position{origin};
  LineReader lines(in, position);
  EvemuParser parser(position);
  string_view line;
  while (lines.next(line)) parser.parse_line(line);
  return parser.finish();
}

void write_evemu(std::ostream& out, const Recording& recording) {
  check_writable(recording);
  constexpr std::size_t kFlushBytes = std::size_t{1} << 20;  // large writes, bounded memory
  Buffer buffer;
  append_description(buffer, recording.device);
  for (const InputEvent& event : recording.events) {
    append_event(buffer, event);
    if (buffer.size() >= kFlushBytes) flush(out, buffer);
  }
  flush(out, buffer);
}

}  // namespace ph
