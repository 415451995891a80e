// Reads `libinput record` files (format version 1) with yaml-cpp: the evdev description and the evdev
// events of one device. Everything else in the file (libinput events, udev, quirks, hid, unknown keys) is
// ignored. Every problem becomes a RecordingError "ORIGIN:LINE: what is wrong", or "ORIGIN: what is wrong"
// where no line is at fault.
#include "recording/libinput_record.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string_view>
#include <utility>

namespace ph {
namespace {

constexpr std::size_t kReadChunkBytes = std::size_t{1} << 16;
constexpr std::uint16_t kAbsMax = 0x3f;     // ABS_MAX: absinfo exists only for these codes
constexpr std::size_t kPropertyCount = 32;  // DeviceDescription::properties' size
constexpr std::int64_t kUsecPerSec = 1'000'000;
// The shortest text one event can take, "[0,0,0,0,0]": more events than the file could hold means
// YAML aliases multiply them, which we refuse rather than let a small file fill the memory.
constexpr std::size_t kMinEventTextBytes = 11;

// Where errors point: "ORIGIN:LINE: ..." with yaml-cpp's 0-based line turned 1-based, or "ORIGIN: ..." where
// no line is at fault (as the evemu reader says it).
class ErrorSite {
 public:
  explicit ErrorSite(const std::string& origin) : origin_(origin) {}

  [[noreturn]] void fail_at(const YAML::Mark& mark, std::string_view what) const {
    if (mark.is_null() || mark.line < 0) throw RecordingError(fmt::format("{}: {}", origin_, what));
    throw RecordingError(fmt::format("{}:{}: {}", origin_, mark.line + 1, what));
  }
  [[noreturn]] void fail(const YAML::Node& node, std::string_view what) const { fail_at(node.Mark(), what); }
  [[noreturn]] void fail_without_line(std::string_view what) const { fail_at(YAML::Mark::null_mark(), what); }

 private:
  const std::string& origin_;
};

// Reads the whole stream, refusing it as soon as it grows past `max_bytes` (so a huge stream is never
// held in memory).
std::string read_limited(std::istream& in, std::size_t max_bytes, const ErrorSite& site) {
  std::string text;
  char chunk[kReadChunkBytes];
  while (in) {
    in.read(chunk, sizeof chunk);
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      site.fail_without_line(fmt::format("larger than {} bytes; refusing to parse it", max_bytes));
    }
  }
  if (in.bad()) site.fail_without_line("read error");
  return text;
}

YAML::Node parse_yaml(std::string text, const ErrorSite& site) {
  std::istringstream stream(std::move(text));
  try {
    return YAML::Load(stream);
  } catch (const YAML::Exception& e) {  // mostly ParserException, which includes its nesting limit (DeepRecursion)
    site.fail_at(e.mark, fmt::format("not valid YAML: {}", e.msg));
  }
}

// The value of `key` in `map`, or an undefined node. Const lookup: yaml-cpp's non-const operator[] would
// insert the key.
YAML::Node lookup(const YAML::Node& map, const char* key) {
  if (!map.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  return map[key];
}

YAML::Node require(const YAML::Node& map, const char* key, std::string_view where, const ErrorSite& site) {
  YAML::Node value = lookup(map, key);
  if (!value.IsDefined()) site.fail(map, fmt::format("'{}' missing in {}", key, where));
  return value;
}

void require_map(const YAML::Node& node, std::string_view what, const ErrorSite& site) {
  if (!node.IsMap()) site.fail(node, fmt::format("{} must be a mapping", what));
}

void require_list(const YAML::Node& node, std::string_view what, const ErrorSite& site) {
  if (!node.IsSequence()) site.fail(node, fmt::format("{} must be a list", what));
}

void require_list_of_size(const YAML::Node& node, std::size_t size, std::string_view what, const ErrorSite& site) {
  if (!node.IsSequence() || node.size() != size) {
    site.fail(node, fmt::format("{} must be a list of {} integers", what, size));
  }
}

// Decimal (optionally signed) or 0x-hexadecimal, as YAML writes integers; false when `text` is neither.
bool parse_integer(std::string_view text, std::int64_t& value) {
  bool negative = false;
  if (!text.empty() && (text.front() == '-' || text.front() == '+')) {
    negative = text.front() == '-';
    text.remove_prefix(1);
  }
  int base = 10;
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
    base = 16;
    text.remove_prefix(2);
  }
  if (text.empty() || text.front() == '-' || text.front() == '+') return false;
  std::uint64_t magnitude = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), magnitude, base);
  if (error != std::errc() || end != text.data() + text.size()) return false;
  constexpr auto kMax = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  if (magnitude > kMax + (negative ? 1 : 0)) return false;
  // -2^63 has no positive counterpart: negate in unsigned arithmetic, where it is well defined.
  value = negative ? static_cast<std::int64_t>(~magnitude + 1) : static_cast<std::int64_t>(magnitude);
  return true;
}

std::int64_t integer_in(const YAML::Node& node, std::int64_t low, std::int64_t high, std::string_view what,
                        const ErrorSite& site) {
  std::int64_t value = 0;
  if (!node.IsScalar() || !parse_integer(node.Scalar(), value)) {
    site.fail(node, fmt::format("{} must be an integer", what));
  }
  if (value < low || value > high) site.fail(node, fmt::format("{} {} is not in [{}, {}]", what, value, low, high));
  return value;
}

std::int32_t int32_value(const YAML::Node& node, std::string_view what, const ErrorSite& site) {
  using Limits = std::numeric_limits<std::int32_t>;
  return static_cast<std::int32_t>(integer_in(node, Limits::min(), Limits::max(), what, site));
}

std::uint16_t event_type(const YAML::Node& node, const ErrorSite& site) {
  return static_cast<std::uint16_t>(integer_in(node, 0, ev::kMaxType, "event type", site));
}

std::uint16_t event_code(const YAML::Node& node, const ErrorSite& site) {
  return static_cast<std::uint16_t>(integer_in(node, 0, ev::kMaxCode, "event code", site));
}

// id: [bustype, vendor, product, version]
void read_id(const YAML::Node& id, DeviceDescription& device, const ErrorSite& site) {
  require_list_of_size(id, 4, "'id'", site);
  auto field = [&](std::size_t i, const char* name) {
    return static_cast<std::uint16_t>(integer_in(id[i], 0, 0xffff, name, site));
  };
  device.bustype = field(0, "bustype");
  device.vendor = field(1, "vendor");
  device.product = field(2, "product");
  device.version = field(3, "version");
}

// codes: {type: [code, ...]}. codes[0] becomes the set of types (as EVIOCGBIT(0) and evemu's "B: 00" have
// it); the codes listed under EV_SYN are dropped, since libinput record lists every SYN_* code there
// (libevdev reports them all as present) and they would read as types in codes[0].
void read_codes(const YAML::Node& codes, DeviceDescription& device, const ErrorSite& site) {
  require_map(codes, "'codes'", site);
  for (const auto& entry : codes) {
    const std::uint16_t type = event_type(entry.first, site);
    require_list(entry.second, fmt::format("the codes of event type {}", type), site);
    device.codes[ev::kSyn].set(type);
    if (type == ev::kSyn) continue;
    for (const auto& code : entry.second) device.codes[type].set(event_code(code, site));
  }
}

// absinfo: {code: [minimum, maximum, fuzz, flat, resolution]}
void read_absinfo(const YAML::Node& absinfo, DeviceDescription& device, const ErrorSite& site) {
  require_map(absinfo, "'absinfo'", site);
  for (const auto& entry : absinfo) {
    const auto code = static_cast<std::uint16_t>(integer_in(entry.first, 0, kAbsMax, "absinfo code", site));
    const YAML::Node& values = entry.second;
    require_list_of_size(values, 5, "absinfo (minimum, maximum, fuzz, flat, resolution)", site);
    device.absinfo[code] = AbsInfo{int32_value(values[0], "minimum", site), int32_value(values[1], "maximum", site),
                                   int32_value(values[2], "fuzz", site), int32_value(values[3], "flat", site),
                                   int32_value(values[4], "resolution", site)};
  }
}

void read_properties(const YAML::Node& properties, DeviceDescription& device, const ErrorSite& site) {
  require_list(properties, "'properties'", site);
  for (const auto& property : properties) {
    device.properties.set(static_cast<std::size_t>(integer_in(property, 0, kPropertyCount - 1, "property", site)));
  }
}

DeviceDescription read_description(const YAML::Node& evdev, const ErrorSite& site) {
  require_map(evdev, "'evdev'", site);
  DeviceDescription device;
  const YAML::Node name = require(evdev, "name", "'evdev'", site);
  if (!name.IsScalar()) site.fail(name, "'name' must be a string");
  if (name.Scalar().size() > kMaxDeviceName) {
    site.fail(name,
              fmt::format("'name' has {} characters; at most {} are allowed", name.Scalar().size(), kMaxDeviceName));
  }
  // A name no device can have (the kernel's are text) and no evemu file can hold: refused here, at its line.
  for (const char c : name.Scalar()) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && c != '\t') || byte == 0x7f)
      site.fail(name, fmt::format("'name' contains a control character (0x{:02x})", byte));
  }
  device.name = name.Scalar();
  read_id(require(evdev, "id", "'evdev'", site), device, site);
  read_codes(require(evdev, "codes", "'evdev'", site), device, site);
  if (const YAML::Node absinfo = lookup(evdev, "absinfo"); absinfo.IsDefined()) read_absinfo(absinfo, device, site);
  if (const YAML::Node props = lookup(evdev, "properties"); props.IsDefined()) read_properties(props, device, site);
  return device;
}

// [sec, usec, type, code, value]; the time stays as recorded (libinput record starts it at zero).
InputEvent read_event(const YAML::Node& node, const ErrorSite& site) {
  require_list_of_size(node, 5, "an evdev event [sec, usec, type, code, value]", site);
  constexpr std::int64_t kMaxSec = (std::numeric_limits<std::int64_t>::max() - kUsecPerSec) / kUsecPerSec;
  const std::int64_t sec = integer_in(node[0], 0, kMaxSec, "seconds", site);
  const std::int64_t usec = integer_in(node[1], 0, kUsecPerSec - 1, "microseconds", site);
  return InputEvent{sec * kUsecPerSec + usec, event_type(node[2], site), event_code(node[3], site),
                    int32_value(node[4], "event value", site)};
}

// events: a list of items; those with an `evdev` key hold one frame of evdev events each.
std::vector<InputEvent> read_events(const YAML::Node& items, std::size_t max_events, const ErrorSite& site) {
  std::vector<InputEvent> events;
  if (!items.IsDefined() || items.IsNull()) return events;  // a recording of the description only
  require_list(items, "'events'", site);
  for (const auto& item : items) {
    require_map(item, "an item of 'events'", site);
    const YAML::Node frame = lookup(item, "evdev");
    if (!frame.IsDefined()) continue;  // libinput events, hidraw reports, ...
    require_list(frame, "'evdev' of an event item", site);
    if (frame.size() > max_events - events.size()) {
      site.fail(frame, "more events than the file's size allows (YAML aliases repeating them?)");
    }
    for (const auto& event : frame) events.push_back(read_event(event, site));
  }
  return events;
}

// The checked top level: a mapping of format version 1 with a list of devices.
YAML::Node device_list(const YAML::Node& root, const ErrorSite& site) {
  // An empty document ("---", comments) has no line at fault: yaml-cpp marks its end, or nothing.
  if (!root.IsDefined() || root.IsNull()) site.fail_without_line("empty input: no YAML document");
  require_map(root, "a libinput record (the top level)", site);
  if (const YAML::Node version = lookup(root, "version"); version.IsDefined()) {
    const std::int64_t number = integer_in(version, std::numeric_limits<std::int64_t>::min(),
                                           std::numeric_limits<std::int64_t>::max(), "version", site);
    if (number != 1) {
      site.fail(version, fmt::format("libinput record format version {} is not supported; expected 1", number));
    }
  }
  const YAML::Node devices = require(root, "devices", "the libinput record", site);
  require_list(devices, "'devices'", site);
  return devices;
}

YAML::Node device_at(const YAML::Node& devices, std::size_t device_index, const ErrorSite& site) {
  if (device_index >= devices.size()) {
    site.fail(devices, fmt::format("no device {}: the file has {} device(s)", device_index, devices.size()));
  }
  const YAML::Node device = devices[device_index];
  require_map(device, fmt::format("device {}", device_index), site);
  return device;
}

DeviceDescription description_of(const YAML::Node& device, std::size_t device_index, const ErrorSite& site) {
  return read_description(require(device, "evdev", fmt::format("device {}", device_index), site), site);
}

bool is_pointer(const DeviceDescription& device) {
  return device.has(ev::kRel, ev::kRelX) && device.has(ev::kRel, ev::kRelY);
}

// kFirstPointerDevice: device 0, unless it has no REL_X/REL_Y and a later device has both. The devices
// before the one chosen are read in full, so a malformed one is an error here too.
std::size_t choose_device(const YAML::Node& devices, std::size_t device_index, const ErrorSite& site) {
  if (device_index != kFirstPointerDevice) return device_index;
  if (devices.size() == 0 || is_pointer(description_of(device_at(devices, 0, site), 0, site))) return 0;
  for (std::size_t i = 1; i < devices.size(); ++i) {
    if (is_pointer(description_of(device_at(devices, i, site), i, site))) return i;
  }
  return 0;  // no pointer at all: device 0, whose events all pass through a replay unchanged
}

Recording interpret(const YAML::Node& root, std::size_t device_index, std::size_t max_events, const ErrorSite& site,
                    LibinputDevices* devices_read) {
  const YAML::Node devices = device_list(root, site);
  const std::size_t index = choose_device(devices, device_index, site);
  const YAML::Node device = device_at(devices, index, site);
  Recording recording;
  recording.device = description_of(device, index, site);
  recording.events = read_events(lookup(device, "events"), max_events, site);
  if (devices_read != nullptr) *devices_read = {index, devices.size()};
  return recording;
}

}  // namespace

Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index,
                               std::size_t max_bytes, LibinputDevices* devices) {
  const ErrorSite site(origin);
  std::string text = read_limited(in, max_bytes, site);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) site.fail_without_line("empty input");
  const std::size_t max_events = text.size() / kMinEventTextBytes;
  const YAML::Node root = parse_yaml(std::move(text), site);
  try {
    return interpret(root, device_index, max_events, site, devices);
  } catch (const YAML::Exception& e) {  // a yaml-cpp conversion the checks above missed: still the file's fault
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    throw;  // a check above that missed a case: what fuzz/fuzz_libinput_record.cpp looks for
#endif
    site.fail_at(e.mark, e.msg);
  }
}

Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index,
                               std::size_t max_bytes) {
  return read_libinput_record(in, origin, device_index, max_bytes, nullptr);
}

Recording read_libinput_record(std::istream& in, const std::string& origin, std::size_t device_index) {
  return read_libinput_record(in, origin, device_index, kMaxLibinputRecordBytes, nullptr);
}

}  // namespace ph
