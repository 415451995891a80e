// libinput record files (recording/libinput_record): the description and evdev events of realistic recordings,
// the choice of device, an error naming the origin and the line for every kind of malformed input, the size
// limit, and format detection by read_recording.
#include "recording/libinput_record.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <streambuf>
#include <string>
#include <string_view>
#include <vector>

#include "recording/evemu.hpp"
#include "recording/recording_file.hpp"

namespace ph {
namespace {

const std::string kDataDir = PH_TEST_DATA_DIR;
const std::string kOrigin = "rec.yml";

Recording parse(std::string_view text, std::size_t device_index = 0) {
  std::istringstream in{std::string(text)};
  return read_libinput_record(in, kOrigin, device_index);
}

// The message of the RecordingError that reading `in` throws, or a test failure.
std::string error_of_stream(std::istream& in, std::size_t device_index, std::size_t max_bytes) {
  try {
    read_libinput_record(in, kOrigin, device_index, max_bytes);
  } catch (const RecordingError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no RecordingError";
  return {};
}

std::string error_of(std::string_view text, std::size_t device_index = 0) {
  std::istringstream in{std::string(text)};
  SCOPED_TRACE(text);
  return error_of_stream(in, device_index, kMaxLibinputRecordBytes);
}

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

// The error names the origin and the line, then says what is wrong; line 0: no line is at fault, and the
// error names the origin alone ("ORIGIN: ...", as the evemu reader says it, never "ORIGIN:0:").
void expect_error(const std::string& message, int line, std::string_view fragment) {
  const std::string prefix = kOrigin + ":" + (line > 0 ? std::to_string(line) + ":" : std::string()) + " ";
  EXPECT_EQ(message.substr(0, prefix.size()), prefix) << message;
  EXPECT_TRUE(contains(message, fragment)) << message << "\n  lacks: " << fragment;
}

DeviceDescription description(std::string name, std::array<std::uint16_t, 4> id) {
  DeviceDescription device;
  device.name = std::move(name);
  device.bustype = id[0];
  device.vendor = id[1];
  device.product = id[2];
  device.version = id[3];
  return device;
}

// Sets the type bit in codes[0] with the codes, as EVIOCGBIT does.
void enable_all(DeviceDescription& device, std::uint16_t type, std::initializer_list<std::uint16_t> codes) {
  device.codes[ev::kSyn].set(type);
  for (const std::uint16_t code : codes) device.enable(type, code);
}

Recording parse_file(const std::string& name, std::size_t device_index = 0) {
  std::ifstream in(kDataDir + "/" + name, std::ios::binary);
  EXPECT_TRUE(in.good()) << name;
  return read_libinput_record(in, name, device_index);
}

constexpr InputEvent event(TimeUs time, std::uint16_t type, std::uint16_t code, std::int32_t value) {
  return InputEvent{time, type, code, value};
}

TEST(LibinputRecord, ReadsAMouseRecordingIgnoringLibinputEventsAndUnknownKeys) {
  const Recording recording = parse_file("libinput_mouse.yml");

  DeviceDescription expected = description("Logitech USB Optical Mouse", {3, 0x46d, 0xc077, 0x111});
  enable_all(expected, ev::kSyn, {});
  enable_all(expected, ev::kKey, {ev::kBtnLeft, ev::kBtnRight, ev::kBtnMiddle});
  enable_all(expected, ev::kRel, {ev::kRelX, ev::kRelY, ev::kRelWheel, ev::kRelWheelHiRes});
  enable_all(expected, ev::kMsc, {ev::kMscScan});
  EXPECT_EQ(recording.device, expected);
  // The SYN_* codes listed under EV_SYN must not turn into event types.
  EXPECT_EQ(recording.device.codes[ev::kSyn].count(), 4u);

  const std::vector<InputEvent> events = {
      event(0, ev::kRel, ev::kRelX, 1),
      event(0, ev::kRel, ev::kRelY, -2),
      event(0, ev::kSyn, ev::kSynReport, 0),
      event(8012, ev::kMsc, ev::kMscScan, 90001),
      event(8012, ev::kKey, ev::kBtnLeft, 1),
      event(8012, ev::kSyn, ev::kSynReport, 0),
      event(96003, ev::kMsc, ev::kMscScan, 90001),
      event(96003, ev::kKey, ev::kBtnLeft, 0),
      event(96003, ev::kSyn, ev::kSynReport, 0),
      event(1'004'000, ev::kRel, ev::kRelWheel, -1),
      event(1'004'000, ev::kRel, ev::kRelWheelHiRes, -120),
      event(1'004'000, ev::kSyn, ev::kSynReport, 0),
      event(1'999'999, ev::kKey, ev::kBtnRight, 1),
      event(1'999'999, ev::kSyn, ev::kSynReport, 0),
  };
  EXPECT_EQ(recording.events, events);
}

TEST(LibinputRecord, ReadsTheChosenDeviceOfSeveral) {
  const Recording keyboard = parse_file("libinput_two_devices.yml", 0);
  EXPECT_EQ(keyboard.device.name, "AT Translated Set 2 keyboard");
  EXPECT_EQ(keyboard.events.size(), 3u);
  EXPECT_TRUE(keyboard.device.has(0x11, 2));  // EV_LED / LED_SCROLLL

  const Recording mouse = parse_file("libinput_two_devices.yml", 1);
  DeviceDescription expected = description("Razer Razer DeathAdder V2", {3, 5426, 132, 256});
  enable_all(expected, ev::kSyn, {});
  enable_all(expected, ev::kKey, {0x110, 0x111, 0x112, 0x113, 0x114});
  enable_all(expected, ev::kRel,
             {ev::kRelX, ev::kRelY, ev::kRelHWheel, ev::kRelWheel, ev::kRelWheelHiRes, ev::kRelHWheelHiRes});
  enable_all(expected, ev::kMsc, {ev::kMscScan});
  EXPECT_EQ(mouse.device, expected);
  const std::vector<InputEvent> events = {
      event(1500, ev::kRel, ev::kRelX, -3),     event(1500, ev::kSyn, ev::kSynReport, 0),
      event(2500, ev::kRel, ev::kRelHWheel, 1), event(2500, ev::kRel, ev::kRelHWheelHiRes, 120),
      event(2500, ev::kSyn, ev::kSynReport, 0),
  };
  EXPECT_EQ(mouse.events, events);
}

TEST(LibinputRecord, FirstPointerDeviceSkipsDevicesWithoutRelativeMotion) {
  const std::string path = kDataDir + "/libinput_two_devices.yml";
  std::ifstream in(path, std::ios::binary);
  LibinputDevices devices;
  const Recording first = read_libinput_record(in, "two", kFirstPointerDevice, kMaxLibinputRecordBytes, &devices);
  EXPECT_EQ(devices.index, 1u);
  EXPECT_EQ(devices.count, 2u);
  EXPECT_EQ(first.device, parse_file("libinput_two_devices.yml", 1).device);
  EXPECT_EQ(first.events, parse_file("libinput_two_devices.yml", 1).events);
  // An explicit index is read as it is, a keyboard included.
  std::ifstream again(path, std::ios::binary);
  EXPECT_EQ(read_libinput_record(again, "two", 0, kMaxLibinputRecordBytes, &devices).device.name,
            "AT Translated Set 2 keyboard");
  EXPECT_EQ(devices.index, 0u);
  // Device 0 a pointer: device 0. No pointer at all (the tablet): device 0.
  for (const char* name : {"libinput_mouse.yml", "libinput_tablet.yml"}) {
    std::ifstream one(kDataDir + "/" + name, std::ios::binary);
    const Recording recording = read_libinput_record(one, name, kFirstPointerDevice, kMaxLibinputRecordBytes, &devices);
    EXPECT_EQ(devices.index, 0u) << name;
    EXPECT_EQ(devices.count, 1u) << name;
    EXPECT_EQ(recording.device, parse_file(name).device) << name;
  }
  // Through read_recording_file, which tells the format too.
  RecordingInfo info;
  EXPECT_EQ(read_recording_file(path, kFirstPointerDevice, &info).device.name, "Razer Razer DeathAdder V2");
  EXPECT_EQ(info.format, RecordingFormat::libinput_record);
  EXPECT_EQ(info.device_index, 1u);
  EXPECT_EQ(info.device_count, 2u);
  EXPECT_EQ(read_recording_file(path, 0, &info).device.name, "AT Translated Set 2 keyboard");
  EXPECT_EQ(info.device_index, 0u);
  // Errors: a device the file does not have; in a file without devices, device 0.
  expect_error(error_of("version: 1\ndevices: []\n", kFirstPointerDevice), 2, "no device 0: the file has 0 device(s)");
}

TEST(LibinputRecord, ReadsAbsinfoAndProperties) {
  const Recording tablet = parse_file("libinput_tablet.yml");
  DeviceDescription expected = description("Wacom Intuos S Pen", {3, 0x56a, 0x374, 0x110});
  enable_all(expected, ev::kSyn, {});
  enable_all(expected, ev::kKey, {320, 321, 330, 331, 332});
  enable_all(expected, ev::kAbs, {0, 1, 24, 26, 27});
  enable_all(expected, ev::kMsc, {0});
  expected.absinfo = {{0, AbsInfo{0, 15200, 4, 0, 100}},
                      {1, AbsInfo{0, 9500, 4, 0, 100}},
                      {24, AbsInfo{0, 4095, 0, 0, 0}},
                      {26, AbsInfo{-64, 63, 0, 0, 57}},
                      {27, AbsInfo{-64, 63, 0, 0, 57}}};
  expected.properties.set(1);  // INPUT_PROP_DIRECT
  EXPECT_EQ(tablet.device, expected);
  ASSERT_EQ(tablet.events.size(), 8u);
  EXPECT_EQ(tablet.events[0], event(0, ev::kAbs, ev::kAbsX, 7600));
  EXPECT_EQ(tablet.events[6], event(7000, ev::kAbs, 26, -12));
}

// A small valid recording; the error tests replace one line of it (numbered from 1, as in the messages).
constexpr std::string_view kBase =
    "version: 1\n"                 // 1
    "devices:\n"                   // 2
    "- node: /dev/input/event0\n"  // 3
    "  evdev:\n"                   // 4
    "    name: \"m\"\n"            // 5
    "    id: [3, 1, 2, 3]\n"       // 6
    "    codes:\n"                 // 7
    "      0: [0]\n"               // 8
    "      2: [0, 1]\n"            // 9
    "    absinfo:\n"               // 10
    "      0: [0, 10, 0, 0, 0]\n"  // 11
    "    properties: [0]\n"        // 12
    "  events:\n"                  // 13
    "  - evdev:\n"                 // 14
    "    - [0, 10, 2, 0, 5]\n"     // 15
    "    - [0, 10, 0, 0, 0]\n";    // 16

// kBase with line `number` replaced by `replacement` (several lines when it holds newlines).
std::string with_line(int number, std::string_view replacement) {
  std::string result;
  std::istringstream lines{std::string(kBase)};
  std::string line;
  for (int i = 1; std::getline(lines, line); ++i) {
    result += (i == number) ? std::string(replacement) : line;
    result += '\n';
  }
  return result;
}

// kBase up to and including line `last`, then `tail`.
std::string base_up_to(int last, std::string_view tail) {
  std::string result;
  std::istringstream lines{std::string(kBase)};
  std::string line;
  for (int i = 1; i <= last && std::getline(lines, line); ++i) result += line + '\n';
  return result + std::string(tail);
}

TEST(LibinputRecord, BaseOfTheErrorTestsIsValid) {
  const Recording recording = parse(kBase);
  EXPECT_EQ(recording.device.name, "m");
  EXPECT_EQ(recording.device.absinfo.at(0), (AbsInfo{0, 10, 0, 0, 0}));
  EXPECT_EQ(recording.events, (std::vector<InputEvent>{event(10, 2, 0, 5), event(10, 0, 0, 0)}));
  // Hexadecimal and signed integers are YAML integers too.
  EXPECT_EQ(parse(with_line(6, "    id: [0x3, 0x46D, +2, 3]")).device.vendor, 0x46d);
  EXPECT_EQ(parse(with_line(15, "    - [0, 10, 2, 0, -2147483648]")).events[0].value, -2147483648);
  // A recording without events is a description only.
  EXPECT_TRUE(parse(base_up_to(12, "")).events.empty());
  EXPECT_TRUE(parse(base_up_to(13, "")).events.empty());
}

struct LineCase {
  int line_to_replace;
  std::string replacement;
  int error_line;
  std::string fragment;
};

TEST(LibinputRecord, WrongShapesAreErrorsWithTheirLine) {
  const std::vector<LineCase> cases = {
      {1, "version: 2", 1, "libinput record format version 2 is not supported; expected 1"},
      {5, "    name: \"a\\nb\"", 5, "'name' contains a control character (0x0a)"},
      {1, "version: one", 1, "must be an integer"},
      {2, "gadgets:", 1, "'devices' missing"},
      {4, "  evdevs:", 3, "'evdev' missing in device 0"},
      {5, "    name: [m]", 5, "'name' must be a string"},
      {5, "    label: m", 5, "'name' missing in 'evdev'"},
      {5, "    name: " + std::string(kMaxDeviceName + 1, 'n'), 5, "'name' has 1025 characters"},
      {6, "    id: [3, 1, 2]", 6, "'id' must be a list of 4 integers"},
      {6, "    id: [3, 70000, 2, 3]", 6, "vendor 70000 is not in [0, 65535]"},
      {6, "    id: 3", 6, "'id' must be a list of 4 integers"},
      {8, "      32: [0]", 8, "event type 32 is not in [0, 31]"},
      {8, "      x: [0]", 8, "event type must be an integer"},
      {9, "      2: [0, 768]", 9, "event code 768 is not in [0, 767]"},
      {9, "      2: 0", 9, "the codes of event type 2 must be a list"},
      {9, "      2: [0, [1]]", 9, "event code must be an integer"},
      {11, "      64: [0, 10, 0, 0, 0]", 11, "absinfo code 64 is not in [0, 63]"},
      {11, "      0: [0, 10, 0, 0]", 11, "must be a list of 5 integers"},
      {11, "      0: [0, 2147483648, 0, 0, 0]", 11, "maximum 2147483648 is not in"},
      {11, "      - [1]", 11, "'absinfo' must be a mapping"},
      {12, "    properties: [32]", 12, "property 32 is not in [0, 31]"},
      {12, "    properties: 1", 12, "'properties' must be a list"},
      {15, "    - 5", 15, "must be a list of 5 integers"},
      {15, "    - [0, 10, 2, 0]", 15, "must be a list of 5 integers"},
      {15, "    - [0, 10, 2, 0, 5, 6]", 15, "must be a list of 5 integers"},
      {15, "    - [0, 10, 2, 0, x]", 15, "event value must be an integer"},
      {15, "    - [0, 10, 2, 0, 1.5]", 15, "event value must be an integer"},
      {15, "    - [0, 10, 2, 0, 0x]", 15, "event value must be an integer"},
      {15, "    - [0, 10, 2, 0, '']", 15, "event value must be an integer"},
      {15, "    - [0, 10, 2, 0, 2147483648]", 15, "event value 2147483648 is not in"},
      {15, "    - [0, 10, 2, 0, -2147483649]", 15, "event value -2147483649 is not in"},
      {15, "    - [0, 10, 2, 0, 99999999999999999999]", 15, "event value must be an integer"},
      {15, "    - [0, 10, 32, 0, 5]", 15, "event type 32 is not in [0, 31]"},
      {15, "    - [0, 10, 2, 768, 5]", 15, "event code 768 is not in [0, 767]"},
      {15, "    - [0, 1000000, 2, 0, 5]", 15, "microseconds 1000000 is not in [0, 999999]"},
      {15, "    - [0, -1, 2, 0, 5]", 15, "microseconds -1 is not in"},
      {15, "    - [-1, 0, 2, 0, 5]", 15, "seconds -1 is not in"},
      {15, "    - [9223372036854775807, 0, 2, 0, 5]", 15, "seconds 9223372036854775807 is not in"},
      {15, "    - [0, 10, 2, 0, {value: 5}]", 15, "event value must be an integer"},
      {16, "    - [0, 10, 0, 0, 0]\n  - 7", 17, "an item of 'events' must be a mapping"},
      {16, "    - [0, 10, 0, 0, 0]\n  - evdev: {a: 1}", 17, "'evdev' of an event item must be a list"},
      {13, "  events: {}\n  - evdev:", 14, "not valid YAML"},
  };
  for (const LineCase& c : cases) {
    SCOPED_TRACE(c.replacement);
    expect_error(error_of(with_line(c.line_to_replace, c.replacement)), c.error_line, c.fragment);
  }
}

TEST(LibinputRecord, WrongShapesOfWholeSectionsAreErrors) {
  expect_error(error_of(base_up_to(3, "  evdev: 5\n")), 4, "'evdev' must be a mapping");
  expect_error(error_of(base_up_to(6, "    codes: [2, 0]\n")), 7, "'codes' must be a mapping");
  expect_error(error_of(base_up_to(12, "  events: 5\n")), 13, "'events' must be a list");
  expect_error(error_of(base_up_to(13, "  - evdev: 5\n")), 14, "'evdev' of an event item must be a list");
  expect_error(error_of("version: 1\ndevices:\n- 5\n"), 3, "device 0 must be a mapping");
  expect_error(error_of("version: 1\ndevices: 5\n"), 2, "'devices' must be a list");
  expect_error(error_of("version: 1\ndevices: []\n"), 2, "no device 0: the file has 0 device(s)");
  expect_error(error_of(kBase, 1), 3, "no device 1: the file has 1 device(s)");
  expect_error(error_of("- version\n- devices\n"), 1, "must be a mapping");
  expect_error(error_of("\n\njust some text\n"), 3, "must be a mapping");
}

// Looking for the first pointer reads the devices before it: a malformed one is an error with its line.
TEST(LibinputRecord, FirstPointerDeviceReportsAMalformedDeviceOnTheWay) {
  const std::string keyboard =
      "version: 1\n"                 // 1
      "devices:\n"                   // 2
      "- node: /dev/input/event3\n"  // 3
      "  evdev:\n"                   // 4
      "    name: \"k\"\n"            // 5
      "    id: [17, 1, 1, 1]\n"      // 6
      "    codes:\n"                 // 7
      "      1: [30]\n";             // 8
  expect_error(error_of(keyboard + "- node: /dev/input/event4\n  evdev:\n    name: [m]\n", kFirstPointerDevice), 11,
               "'name' must be a string");
  // A valid second device without REL_X/REL_Y either: device 0.
  std::istringstream in(keyboard + "- evdev:\n    name: \"b\"\n    id: [25, 0, 1, 0]\n    codes:\n      1: [116]\n");
  LibinputDevices devices;
  EXPECT_EQ(read_libinput_record(in, kOrigin, kFirstPointerDevice, kMaxLibinputRecordBytes, &devices).device.name, "k");
  EXPECT_EQ(devices.index, 0u);
  EXPECT_EQ(devices.count, 2u);
  // Only REL_X is not a pointer.
  std::istringstream rel_x_only(keyboard +
                                "- evdev:\n    name: \"x\"\n    id: [3, 0, 1, 0]\n    codes:\n      2: [0]\n" +
                                "- evdev:\n    name: \"xy\"\n    id: [3, 0, 1, 0]\n    codes:\n      2: [0, 1]\n");
  EXPECT_EQ(
      read_libinput_record(rel_x_only, kOrigin, kFirstPointerDevice, kMaxLibinputRecordBytes, &devices).device.name,
      "xy");
  EXPECT_EQ(devices.index, 2u);
}

// A libinput record file read, written as evemu and read back gives the same description and events.
TEST(LibinputRecord, FixturesRoundTripThroughEvemu) {
  for (const char* name : {"libinput_mouse.yml", "libinput_two_devices.yml", "libinput_tablet.yml"}) {
    for (std::size_t device = 0; device < (std::string_view(name) == "libinput_two_devices.yml" ? 2u : 1u); ++device) {
      SCOPED_TRACE(std::string(name) + " device " + std::to_string(device));
      const Recording yaml = parse_file(name, device);
      ASSERT_FALSE(yaml.events.empty());
      std::ostringstream written;
      write_evemu(written, yaml);
      std::istringstream text(written.str());
      const Recording evemu = read_evemu(text, "written.evemu");
      EXPECT_EQ(evemu.device, yaml.device);
      EXPECT_EQ(evemu.device.name, yaml.device.name);
      EXPECT_EQ(evemu.device.absinfo, yaml.device.absinfo);
      EXPECT_EQ(evemu.device.properties, yaml.device.properties);
      EXPECT_EQ(evemu.events, yaml.events);
      // And once more: evemu written from the evemu read is the same text.
      std::ostringstream again;
      write_evemu(again, evemu);
      EXPECT_EQ(again.str(), written.str());
    }
  }
}

TEST(LibinputRecord, InvalidYamlIsAnErrorWithTheParsersLine) {
  expect_error(error_of("version: 1\ndevices: [\n  {node: a,\n"), 4, "not valid YAML");
  expect_error(error_of("version: 1\ndevices:\n  - a\n - b\n"), 4, "not valid YAML");
  expect_error(error_of("version: 1\ndevices: [a, b}\n"), 2, "not valid YAML: illegal flow end");
  expect_error(error_of("version: 1\n\tdevices: []\n"), 2, "not valid YAML");
  expect_error(error_of("version: 1\ndevices: !<bad tag\n"), 2, "not valid YAML");
  expect_error(error_of("a: *undefined_alias\n"), 1, "not valid YAML");
}

TEST(LibinputRecord, EmptyInputIsAnError) {
  expect_error(error_of(""), 0, "empty input");
  expect_error(error_of(" \n\t\r\n"), 0, "empty input");
  expect_error(error_of("# libinput record\n# nothing else\n"), 0, "empty input");
  expect_error(error_of("# libinput record\n---\n"), 0, "empty input: no YAML document");
  expect_error(error_of("---\n# nothing\n...\n"), 0, "empty input: no YAML document");
  for (const char* text : {"", "# libinput record\n---\n"}) {
    const std::string message = error_of(text);
    EXPECT_EQ(message.rfind(kOrigin + ": ", 0), 0u) << message;
    EXPECT_EQ(message.find(":0:"), std::string::npos) << message;
  }
}

TEST(LibinputRecord, BinaryGarbageIsAnError) {
  std::string garbage;
  std::uint32_t state = 12345;
  for (int i = 0; i < 4096; ++i) {
    state = state * 1103515245u + 12345u;  // a fixed pseudo-random byte sequence
    garbage += static_cast<char>(state >> 24);
  }
  const std::vector<std::string> inputs = {garbage, std::string("\0\0\0\0version: 1", 14),
                                           std::string("\xff\xfe\x00\x00\x01\x02", 6),
                                           "\x7f"
                                           "ELF\x02\x01\x01"};
  for (const std::string& input : inputs) {
    const std::string message = error_of(input);
    EXPECT_EQ(message.rfind(kOrigin + ":", 0), 0u) << message;
  }
}

// Aliases could repeat one list of events many times over; a small file must not expand to a huge recording.
TEST(LibinputRecord, AliasesThatMultiplyEventsAreRefused) {
  std::string text = base_up_to(13, "  - evdev: &frame\n");
  for (int i = 0; i < 50; ++i) text += "    - [0, 10, 0, 0, 0]\n";
  for (int i = 0; i < 500; ++i) text += "  - evdev: *frame\n";
  expect_error(error_of(text), 14, "more events than the file's size allows");
  // A few aliases are fine.
  std::string few = base_up_to(13, "  - evdev: &frame\n    - [0, 10, 0, 0, 0]\n  - evdev: *frame\n");
  EXPECT_EQ(parse(few).events.size(), 2u);
}

// Serves `total` copies of `fill` without storing them, counting how many were asked for.
class GeneratedBytes final : public std::streambuf {
 public:
  GeneratedBytes(std::size_t total, char fill) : remaining_(total) {
    std::fill(std::begin(chunk_), std::end(chunk_), fill);
  }
  std::size_t served() const { return served_; }

 protected:
  int_type underflow() override {
    if (remaining_ == 0) return traits_type::eof();
    const std::size_t n = std::min(remaining_, sizeof chunk_);
    remaining_ -= n;
    served_ += n;
    setg(chunk_, chunk_, chunk_ + n);
    return traits_type::to_int_type(chunk_[0]);
  }

 private:
  std::size_t remaining_;
  std::size_t served_ = 0;
  char chunk_[1 << 16];
};

TEST(LibinputRecord, RefusesAStreamLargerThanTheLimitWithoutReadingItAll) {
  constexpr std::size_t kOneGigabyte = std::size_t{1} << 30;
  GeneratedBytes bytes(kOneGigabyte, '#');
  std::istream in(&bytes);
  const std::string message = error_of_stream(in, 0, kMaxLibinputRecordBytes);
  expect_error(message, 0, "larger than " + std::to_string(kMaxLibinputRecordBytes) + " bytes");
  EXPECT_LT(bytes.served(), kMaxLibinputRecordBytes + (std::size_t{1} << 20));
}

TEST(LibinputRecord, TheSizeLimitCanBeLowered) {
  std::istringstream small{std::string(kBase)};
  expect_error(error_of_stream(small, 0, 100), 0, "larger than 100 bytes");
  std::istringstream exact{std::string(kBase)};
  EXPECT_EQ(read_libinput_record(exact, kOrigin, 0, kBase.size()).events.size(), 2u);
}

TEST(LibinputRecord, ReadRecordingDetectsTheFormat) {
  for (const char* name : {"libinput_mouse.yml", "libinput_two_devices.yml", "libinput_tablet.yml"}) {
    SCOPED_TRACE(name);
    const std::string path = kDataDir + "/" + name;
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    EXPECT_EQ(detect_recording_format(text.str()), RecordingFormat::libinput_record);
    const Recording recording = read_recording_file(path);
    EXPECT_EQ(recording.device, parse_file(name).device);
    EXPECT_EQ(recording.events, parse_file(name).events);
  }
  EXPECT_EQ(detect_recording_format(kBase), RecordingFormat::libinput_record);
}

// What comes before the first line that tells the format: a byte order mark (which YAML allows and some editors
// write), a YAML directive, and comments longer than one read (a header of notes), whose end may fall within a line.
TEST(LibinputRecord, TheFormatIsToldPastAByteOrderMarkADirectiveAndLongComments) {
  const auto read_text = [](const std::string& text) {
    std::istringstream in(text);
    RecordingInfo info;
    const Recording recording = read_recording(in, "test.yml", 0, &info);
    EXPECT_EQ(info.format, RecordingFormat::libinput_record) << text.substr(0, 40);
    return recording;
  };
  const Recording plain = parse(kBase);
  EXPECT_EQ(read_text("\xEF\xBB\xBF" + std::string(kBase)).events, plain.events);
  EXPECT_EQ(read_text("%YAML 1.1\n---\n" + std::string(kBase)).events, plain.events);
  for (std::size_t comments : {4090U, 4096U, 5000U, 300000U}) {  // the key before, across and after the first read
    std::string notes;
    while (notes.size() < comments) notes += "# notes on the recording\n";
    notes.resize(comments - 1);
    EXPECT_EQ(read_text(notes + "\n" + std::string(kBase)).events, plain.events) << comments;
  }
  // An evemu file's byte order mark too.
  std::istringstream evemu("\xEF\xBB\xBF# EVEMU 1.3\nN: m\nI: 0003 0001 0001 0001\n");
  EXPECT_EQ(read_recording(evemu, "test.evemu").device.name, "m");
  // "ver" at the end of what was read first is not yet a line to judge.
  EXPECT_FALSE(recording_format_of("# notes\nver", false).has_value());
  EXPECT_EQ(recording_format_of("# notes\nver", true), RecordingFormat::evemu);
}

TEST(LibinputRecord, ReadRecordingStillReadsEvemu) {
  std::string evemu =
      "# EVEMU 1.3\n"
      "# Input device name: \"Logitech USB Optical Mouse\"\n"
      "N: Logitech USB Optical Mouse\n"
      "I: 0003 046d c077 0111\n"
      "P: 00 00 00 00 00 00 00 00\n"
      "B: 00 17 00 00 00 00 00 00 00\n";
  for (int line = 0; line < 12; ++line) {  // EV_KEY: 96 bytes; BTN_LEFT..BTN_MIDDLE are bits 0-2 of byte 34
    evemu += line == 4 ? "B: 01 00 00 07 00 00 00 00 00\n" : "B: 01 00 00 00 00 00 00 00 00\n";
  }
  evemu +=
      "B: 02 03 09 00 00 00 00 00 00\n"
      "B: 03 00 00 00 00 00 00 00 00\n"
      "B: 04 10 00 00 00 00 00 00 00\n"
      "B: 05 00 00 00 00 00 00 00 00\n"
      "B: 11 00 00 00 00 00 00 00 00\n"
      "B: 12 00 00 00 00 00 00 00 00\n"
      "B: 14 00 00 00 00 00 00 00 00\n"
      "B: 15 00 00 00 00 00 00 00 00\n"
      "B: 15 00 00 00 00 00 00 00 00\n"
      "################################\n"
      "#      Waiting for events      #\n"
      "################################\n"
      "E: 0.000001 0002 0000 0001\t# EV_REL / REL_X                1\n"
      "E: 0.000001 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +0ms\n";
  EXPECT_EQ(detect_recording_format(evemu), RecordingFormat::evemu);
  std::istringstream in(evemu);
  const Recording recording = read_recording(in, "mouse.evemu");
  EXPECT_EQ(recording.device.name, "Logitech USB Optical Mouse");
  EXPECT_EQ(recording.device.vendor, 0x46d);
  EXPECT_TRUE(recording.device.has(ev::kKey, ev::kBtnLeft));
  ASSERT_EQ(recording.events.size(), 2u);
  EXPECT_EQ(recording.events[0].type, ev::kRel);
  EXPECT_EQ(recording.events[0].value, 1);
}

}  // namespace
}  // namespace ph
