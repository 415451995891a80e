// evemu recordings (recording/evemu): the two real recordings in tests/data/recordings, round trips of read
// and written files, an error naming the line for every kind of mistake, and inputs meant to hurt: an endless
// line, binary garbage.
#include "recording/evemu.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <streambuf>
#include <string>
#include <string_view>
#include <vector>

namespace ph {
namespace {

namespace fs = std::filesystem;

const fs::path kRecordings = PH_RECORDINGS_DIR;  // tests/data/recordings

Recording read_text(const std::string& text) {
  std::istringstream in(text);
  return read_evemu(in, "test");
}

std::string write_text(const Recording& recording) {
  std::ostringstream out;
  write_evemu(out, recording);
  return out.str();
}

// The message of the RecordingError that reading `text` throws ("" if none is thrown).
std::string read_error(const std::string& text) {
  try {
    read_text(text);
  } catch (const RecordingError& error) {
    return error.what();
  }
  return "";
}

void expect_same(const Recording& expected, const Recording& actual) {
  EXPECT_TRUE(expected.device == actual.device) << "device descriptions differ";
  ASSERT_EQ(expected.events.size(), actual.events.size());
  for (std::size_t i = 0; i < expected.events.size(); ++i) {
    ASSERT_EQ(expected.events[i], actual.events[i]) << "event " << i;
  }
}

void expect_round_trip(const Recording& recording) {
  const std::string written = write_text(recording);
  SCOPED_TRACE(written.substr(0, 2000));
  expect_same(recording, read_text(written));
}

// ---------------------------------------------------------------------------------------------------------
// The real recordings

struct RealRecording {
  std::string file;
  std::string name;
  std::uint16_t bustype, vendor, product, version;
  InputEvent first, last;
};

// gtest, and with it ctest's list of tests, names each instance by this rather than by the struct's bytes, which
// hold heap pointers: every ctest line was padded to the 340 characters of those names.
void PrintTo(const RealRecording& recording, std::ostream* os) { *os << recording.file; }

const std::vector<RealRecording>& real_recordings() {
  static const std::vector<RealRecording> recordings{
      {"ps2-generic-mouse.evemu",
       "PS/2 Generic Mouse",
       0x11,
       0x02,
       0x01,
       0x0000,
       {1329846856201613, ev::kRel, ev::kRelY, -1},
       {1329846909186100, ev::kSyn, ev::kSynReport, 0}},
      {"saitek-cyborg-rat5.evemu",
       "Saitek Cyborg R.A.T.5 Mouse",
       0x03,
       0x06a3,
       0x0cc3,
       0x0111,
       {1331553248067422, ev::kRel, ev::kRelY, -1},
       {1331553262733930, ev::kSyn, ev::kSynReport, 1}},  // an old kernel's SYN_REPORT value 1
  };
  return recordings;
}

std::size_t count_event_lines(const fs::path& path) {
  std::ifstream in(path);
  std::size_t count = 0;
  for (std::string line; std::getline(in, line);) count += line.starts_with("E:") ? 1 : 0;
  return count;
}

class RealRecordingTest : public testing::TestWithParam<RealRecording> {
 protected:
  void SetUp() override {
    path_ = kRecordings / GetParam().file;
    ASSERT_TRUE(fs::is_regular_file(path_)) << path_ << " is missing (tests/data/recordings)";
  }
  Recording read() const {
    std::ifstream in(path_, std::ios::binary);
    return read_evemu(in, path_.string());
  }
  fs::path path_;
};

TEST_P(RealRecordingTest, ReadsDescriptionAndEvents) {
  const RealRecording& expected = GetParam();
  const Recording recording = read();
  const DeviceDescription& device = recording.device;
  EXPECT_EQ(device.name, expected.name);
  EXPECT_EQ(device.bustype, expected.bustype);
  EXPECT_EQ(device.vendor, expected.vendor);
  EXPECT_EQ(device.product, expected.product);
  EXPECT_EQ(device.version, expected.version);
  EXPECT_TRUE(device.has(ev::kRel, ev::kRelX));
  EXPECT_TRUE(device.has(ev::kRel, ev::kRelY));
  EXPECT_TRUE(device.has(ev::kKey, ev::kBtnLeft));
  EXPECT_FALSE(device.has(ev::kKey, 0x100));
  EXPECT_TRUE(device.codes[ev::kSyn].test(ev::kKey)) << "type mask (B: 00)";
  EXPECT_TRUE(device.codes[ev::kSyn].test(ev::kRel));
  EXPECT_FALSE(device.codes[ev::kSyn].test(ev::kAbs));
  EXPECT_TRUE(device.absinfo.empty());
  ASSERT_EQ(recording.events.size(), count_event_lines(path_));
  EXPECT_EQ(recording.events.front(), expected.first);
  EXPECT_EQ(recording.events.back(), expected.last);
}

TEST_P(RealRecordingTest, RoundTrips) { expect_round_trip(read()); }

INSTANTIATE_TEST_SUITE_P(Recorded, RealRecordingTest, testing::ValuesIn(real_recordings()),
                         [](const testing::TestParamInfo<RealRecording>& info) {
                           return info.index == 0 ? "Ps2" : "Saitek";
                         });

TEST(Evemu, SaitekHasWheelScanAndSideButtons) {
  const fs::path path = kRecordings / "saitek-cyborg-rat5.evemu";
  ASSERT_TRUE(fs::is_regular_file(path)) << path << " is missing (tests/data/recordings)";
  std::ifstream in(path, std::ios::binary);
  const Recording recording = read_evemu(in, path.string());
  EXPECT_TRUE(recording.device.has(ev::kRel, ev::kRelWheel));
  EXPECT_TRUE(recording.device.has(ev::kMsc, ev::kMscScan));
  for (std::uint16_t code = 0x110; code <= 0x11c; ++code) EXPECT_TRUE(recording.device.has(ev::kKey, code)) << code;
  EXPECT_FALSE(recording.device.has(ev::kKey, 0x11d));
  EXPECT_EQ(recording.device.properties.count(), 0U);
}

// ---------------------------------------------------------------------------------------------------------
// Generated recordings

Recording generated_mouse() {
  Recording recording;
  DeviceDescription& device = recording.device;
  device.name = "Test Mouse #2 (with a hash)";
  device.bustype = 0x03;
  device.vendor = 0x046d;
  device.product = 0xc52b;
  device.version = 0x0111;
  device.properties.set(0).set(31);
  for (const std::uint16_t type : {ev::kSyn, ev::kKey, ev::kRel, ev::kMsc}) device.codes[ev::kSyn].set(type);
  for (const std::uint16_t code : {ev::kBtnLeft, ev::kBtnRight, ev::kBtnMiddle, std::uint16_t{0x2ff}})
    device.enable(ev::kKey, code);
  for (const std::uint16_t code : {ev::kRelX, ev::kRelY, ev::kRelWheel, ev::kRelHWheel, ev::kRelWheelHiRes}) {
    device.enable(ev::kRel, code);
  }
  device.enable(ev::kMsc, ev::kMscScan);
  device.enable(0x14, 0x01);  // EV_REP: a type evemu writes no line for unless it has bits
  device.enable(0x15, 0x7f);
  device.absinfo[ev::kAbsX] = {-100, 4095, 8, 2, 12};
  device.absinfo[0x2f] = {0, 9, 0, 0, 0};
  device.leds[0x00] = 1;
  device.switches[0x05] = 0;
  const auto add = [&](TimeUs time, std::uint16_t type, std::uint16_t code, std::int32_t value) {
    recording.events.push_back({time, type, code, value});
  };
  add(0, ev::kRel, ev::kRelX, 5);
  add(0, ev::kRel, ev::kRelY, -3);
  add(0, ev::kSyn, ev::kSynReport, 0);
  add(8000, ev::kMsc, ev::kMscScan, 589825);
  add(8000, ev::kKey, ev::kBtnLeft, 1);
  add(8000, ev::kSyn, ev::kSynReport, 1);
  add(16000, ev::kRel, ev::kRelWheel, -1);
  add(16000, ev::kRel, ev::kRelWheelHiRes, -120);
  add(16000, ev::kSyn, ev::kSynReport, 0);
  add(16500, ev::kSyn, ev::kSynDropped, 0);
  add(12000, ev::kKey, ev::kBtnLeft, 0);  // time going backwards is kept
  add(12000, ev::kSyn, ev::kSynReport, 0);
  add(1'999'999'999'999'999, ev::kRel, ev::kRelX, std::numeric_limits<std::int32_t>::min());
  add(std::numeric_limits<TimeUs>::max(), ev::kRel, ev::kRelY, std::numeric_limits<std::int32_t>::max());
  return recording;
}

TEST(Evemu, GeneratedRecordingRoundTrips) { expect_round_trip(generated_mouse()); }

TEST(Evemu, DescriptionOnlyRoundTrips) {
  Recording recording = generated_mouse();
  recording.events.clear();
  expect_round_trip(recording);
}

TEST(Evemu, RandomRecordingsRoundTrip) {
  std::mt19937_64 random(20240611);
  for (int round = 0; round < 50; ++round) {
    Recording recording;
    recording.device.name = "random " + std::to_string(round);
    recording.device.vendor = static_cast<std::uint16_t>(random());
    recording.device.properties = std::bitset<32>(random());
    for (int i = 0; i < 40; ++i) {
      recording.device.enable(static_cast<std::uint16_t>(random() % (ev::kMaxType + 1)),
                              static_cast<std::uint16_t>(random() % (ev::kMaxCode + 1)));
    }
    recording.device.absinfo[static_cast<std::uint16_t>(random() % 0x40)] = {static_cast<std::int32_t>(random()),
                                                                             static_cast<std::int32_t>(random()), 1, 2,
                                                                             static_cast<std::int32_t>(random())};
    TimeUs time = static_cast<TimeUs>(random() % 2'000'000'000'000'000);
    for (int i = 0; i < 200; ++i) {
      time += static_cast<TimeUs>(random() % 20'000);
      recording.events.push_back({time, static_cast<std::uint16_t>(random() % (ev::kMaxType + 1)),
                                  static_cast<std::uint16_t>(random() % (ev::kMaxCode + 1)),
                                  static_cast<std::int32_t>(random())});
    }
    SCOPED_TRACE(round);
    expect_round_trip(recording);
  }
}

TEST(Evemu, WritesEvemuLayout) {
  const std::string text = write_text(generated_mouse());
  EXPECT_TRUE(text.starts_with("# EVEMU 1.3\n"));
  EXPECT_NE(text.find("\nN: Test Mouse #2 (with a hash)\n"), std::string::npos);
  EXPECT_NE(text.find("\nI: 0003 046d c52b 0111\n"), std::string::npos);
  EXPECT_NE(text.find("\nP: 01 00 00 80 00 00 00 00\n"), std::string::npos);
  EXPECT_NE(text.find("\nB: 00 17 00 00 00 00 00 00 00\n"), std::string::npos);
  EXPECT_NE(text.find("\nB: 02 43 09 00 00 00 00 00 00\n"), std::string::npos);  // X Y HWHEEL WHEEL WHEEL_HI_RES
  EXPECT_NE(text.find("\nB: 14 02 00 00 00 00 00 00 00\n"), std::string::npos);
  EXPECT_NE(text.find("\nA: 00 -100 4095 8 2 12\n"), std::string::npos);
  EXPECT_NE(text.find("\nL: 00 1\n"), std::string::npos);
  EXPECT_NE(text.find("\nS: 05 0\n"), std::string::npos);
  EXPECT_NE(text.find("\nE: 0.000000 0002 0001 -003\n"), std::string::npos);
  EXPECT_NE(text.find("\nE: 0.008000 0004 0004 589825\n"), std::string::npos);
  EXPECT_NE(text.find("\nE: 0.008000 0000 0000 0001\n"), std::string::npos);
  EXPECT_NE(text.find("\nE: 9223372036854.775807 0002 0001 2147483647\n"), std::string::npos);
  // As many mask lines as evemu-record writes: one per 64 codes up to each type's largest code.
  const auto count = [&](std::string_view prefix) {
    std::size_t n = 0;
    for (std::size_t at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("\nP: "), 1U);
  EXPECT_EQ(count("\nB: 00 "), 1U);
  EXPECT_EQ(count("\nB: 01 "), 12U);
  EXPECT_EQ(count("\nB: 02 "), 1U);
  EXPECT_EQ(count("\nB: 03 "), 1U);
  EXPECT_EQ(count("\nB: 05 "), 1U);
  EXPECT_EQ(count("\nB: 15 "), 2U);
  EXPECT_EQ(count("\nB: 16 "), 0U);
}

TEST(Evemu, RefusesToWriteWhatCannotBeReadBack) {
  Recording negative = generated_mouse();
  negative.events[3].time = -1;
  Recording control = generated_mouse();
  control.device.name = "two\nlines";
  Recording code = generated_mouse();
  code.events[0].code = 0x300;
  Recording long_name = generated_mouse();
  long_name.device.name = std::string(kMaxDeviceName + 1, 'n');
  for (const Recording* recording : {&negative, &control, &code, &long_name}) {
    std::ostringstream out;
    EXPECT_THROW(write_evemu(out, *recording), RecordingError);
    EXPECT_TRUE(out.str().empty()) << "nothing written before the error";
  }
}

// Found by the fuzzer: a name close to the line limit read, but the writer's "# Input device name" comment
// and its "N: " prefix made lines too long to read back. Names now have a limit of their own.
TEST(Evemu, LongestNameReadsWritesAndReadsBack) {
  const std::string longest(kMaxDeviceName, 'n');
  const Recording first = read_text("N:" + longest + "\nI: 0003 0001 0002 0003\n");
  EXPECT_EQ(first.device.name, longest);
  std::ostringstream out;
  write_evemu(out, first);
  std::istringstream written(out.str());
  EXPECT_EQ(read_evemu(written, "round trip").device.name, longest);

  const std::string message = read_error("N:" + longest + "n\n");
  EXPECT_NE(message.find("device name of 1025 characters"), std::string::npos) << message;
}

// Version 1.0 without a header line, CRLF line ends, tabs, comments after data and between lines, zero-based
// times, zero-padded values, 4-field (1.0) and 5-field A: lines, several P: lines, L: and S: lines.
const char* const kHandWritten =
    "N: Hand  Written # Mouse\r\n"
    "I:\t0003\t046D 0001   0100 \r\n"
    "P: 00 00 00 00 00 00 00 00\r\n"
    "P: 00 00 00 00 00 00 00 00\r\n"
    "B: 00 0f 00 00 00 00 00 00 00\r\n"
    "B: 01 00 00 00 00 00 00 00 00 # keys 0..63\r\n"
    "B: 01 00 00 00 00 00 00 00 00\r\n"
    "B: 01 00 00 00 00 00 00 00 00\r\n"
    "B: 01 00 00 00 00 00 00 00 00\r\n"
    "B: 01 00 00 07 00 00 00 00 00\r\n"
    "B: 02 03 09 00 00 00 00 00 00\r\n"
    "B: 03 03 00 00 00 00 00 00 00\r\n"
    "   # an indented comment\r\n"
    "\r\n"
    "A: 00 0 1023 0 0\r\n"
    "A: 01 -5 1023 4 8 40   # with resolution\r\n"
    "L: 01 1\r\n"
    "S: 00 0\r\n"
    "E: 0.000000 0002 0000 0001\t# EV_REL / REL_X\r\n"
    "E: 0.000000\t0002\t0001\t-001\r\n"
    "E: 0.000000 0000 0000 0000\r\n"
    "E: 0.010000 0001 0110 1\r\n"
    "E: 0.010000 0002 0008 -1\r\n"
    "E: 0.010000 0002 000b -120\r\n"
    "E: 0.010000 0000 0000 1 # old kernel\r\n"
    "E: 0.010500 0000 0003 0\r\n"
    "E: 0.009000 0001 0110 +0\r\n"
    "E: 0.009000 0000 0000 0";  // no final line end

TEST(Evemu, ReadsVersion10WithCrlfTabsAndComments) {
  const Recording recording = read_text(kHandWritten);
  const DeviceDescription& device = recording.device;
  EXPECT_EQ(device.name, "Hand  Written # Mouse");
  EXPECT_EQ(device.vendor, 0x046d);
  EXPECT_EQ(device.version, 0x0100);
  EXPECT_TRUE(device.has(ev::kKey, ev::kBtnLeft));
  EXPECT_TRUE(device.has(ev::kKey, ev::kBtnMiddle));
  EXPECT_TRUE(device.has(ev::kRel, ev::kRelWheel));
  EXPECT_TRUE(device.has(ev::kRel, ev::kRelWheelHiRes));
  EXPECT_EQ(device.codes[ev::kSyn].to_ulong() & 0xff, 0x0fUL);
  ASSERT_EQ(device.absinfo.size(), 2U);
  EXPECT_EQ(device.absinfo.at(0), (AbsInfo{0, 1023, 0, 0, 0}));
  EXPECT_EQ(device.absinfo.at(1), (AbsInfo{-5, 1023, 4, 8, 40}));
  EXPECT_EQ(device.leds.at(1), 1);
  EXPECT_EQ(device.switches.at(0), 0);
  const std::vector<InputEvent> expected{
      {0, ev::kRel, ev::kRelX, 1},          {0, ev::kRel, ev::kRelY, -1},
      {0, ev::kSyn, ev::kSynReport, 0},     {10000, ev::kKey, ev::kBtnLeft, 1},
      {10000, ev::kRel, ev::kRelWheel, -1}, {10000, ev::kRel, ev::kRelWheelHiRes, -120},
      {10000, ev::kSyn, ev::kSynReport, 1}, {10500, ev::kSyn, ev::kSynDropped, 0},
      {9000, ev::kKey, ev::kBtnLeft, 0},    {9000, ev::kSyn, ev::kSynReport, 0}};
  EXPECT_EQ(recording.events, expected);
  expect_round_trip(recording);
}

TEST(Evemu, HeaderVersionsAndDescriptionWithoutEvents) {
  EXPECT_EQ(read_text("# EVEMU 1.2\nN: a\n").device.name, "a");
  EXPECT_EQ(read_text("# EVEMU 1.3\r\nN: b\r\n").device.name, "b");
  EXPECT_EQ(read_text("N:\n").device.name, "");
  EXPECT_TRUE(read_text("# EVEMU 1.1\n# comment\nN: a\nI: 0 0 0 0\n").events.empty());
}

// ---------------------------------------------------------------------------------------------------------
// Mistakes: each names the line and says what was expected

struct Mistake {
  std::string text;
  std::size_t line;
  std::string says;
};

const std::string kName = "N: mouse\n";
const std::string kEvent = "E: 1.000000 0002 0000 1\n";

// All 768 key codes (0x2ff is KEY_MAX): a 13th line would hold codes from 0x300 on.
std::string twelve_empty_key_lines() {
  std::string lines;
  for (int i = 0; i < 12; ++i) lines += "B: 01 00 00 00 00 00 00 00 00\n";
  return lines;
}

TEST(Evemu, EveryMistakeNamesItsLine) {
  const std::vector<Mistake> mistakes{
      {kName + "X: 1\n", 2, "unknown line 'X: 1'"},
      {kName + "hello\n", 2, "unknown line"},
      {kName + "I: 00zz 0 0 0\n", 2, "bad bus type '00zz'"},
      {kName + "I: 0x3 0 0 0\n", 2, "expected a hex number"},
      {kName + "I: 10000 0 0 0\n", 2, "bus type '10000' out of range"},
      {kName + "I: 1 2 3\n", 2, "missing field; expected 'I:"},
      {kName + "I: 1 2 3 4 5\n", 2, "unexpected '5'"},
      {kName + "I: 1 2 3 4\nI: 1 2 3 4\n", 3, "second 'I:' line"},
      {kName + "N: other\n", 2, "second 'N:' line"},
      {kName + "P: 00 00 00 00 00 00 00\n", 2, "missing field"},
      {kName + "P: 00 00 00 00 00 00 00 00\nP: 01 00 00 00 00 00 00 00\n", 3, "input property bit 0x40 set"},
      {kName + "P: 00 00 00 00 01 00 00 00\n", 2, "input property bit 0x20 set"},
      {kName + "B: 20 00 00 00 00 00 00 00 00\n", 2, "event type '20' out of range"},
      {kName + "B: 02 00 00 00 00 00 00 00 100\n", 2, "byte '100' out of range"},
      {kName + "B: 02 00 00 00 00 00 00 00 00 00\n", 2, "unexpected '00'"},
      {kName + twelve_empty_key_lines() + "B: 01 01 00 00 00 00 00 00 00\n", 14, "type 0x01 code bit 0x300 set"},
      {kName + "A: 00 0 100 0\n", 2, "missing field; expected 'A:"},
      {kName + "A: 300 0 100 0 0\n", 2, "event code '300' out of range"},
      {kName + "A: 00 0 4294967296 0 0\n", 2, "maximum '4294967296' outside the 32-bit range"},
      {kName + "A: 00 0 1.5 0 0\n", 2, "bad maximum '1.5'"},
      {kName + "A: 00 0 1 0 0 1 1\n", 2, "unexpected '1'"},
      {kName + "L: 01\n", 2, "missing field; expected 'L: <code> <state>'"},
      {kName + "S: 01 x\n", 2, "bad state 'x'"},
      {kEvent, 1, "event before the device description"},
      {"I: 1 2 3 4\n" + kEvent, 2, "event before the device description"},
      {kName + kEvent + "B: 00 01 00 00 00 00 00 00 00\n", 3, "'B:' line after the first event"},
      {kName + kEvent + "N: again\n", 3, "'N:' line after the first event"},
      {kName + kEvent + "E: 1.000000 0020 0000 1\n", 3, "event type '0020' out of range"},
      {kName + kEvent + "E: 1.000000 0001 0300 1\n", 3, "event code '0300' out of range"},
      {kName + kEvent + "E: 1.000000 0001 g 1\n", 3, "bad event code 'g'"},
      {kName + kEvent + "E: 1.000000 0002 0000 2147483648\n", 3, "event value '2147483648' outside the 32-bit range"},
      {kName + kEvent + "E: 1.000000 0002 0000 -2147483649\n", 3, "outside the 32-bit range"},
      {kName + kEvent + "E: 1.000000 0002 0000 1x\n", 3, "bad event value '1x'"},
      {kName + kEvent + "E: 1.000000 0002 0000\n", 3, "missing field; expected 'E: <sec>.<usec>"},
      {kName + kEvent + "E: 1.000000 0002 0000 1 2\n", 3, "unexpected '2' after the last field"},
      {kName + kEvent + "E: 1.1000000 0002 0000 1\n", 3, "not below 1000000"},
      {kName + kEvent + "E: -1.000000 0002 0000 1\n", 3, "negative time '-1.000000'"},
      {kName + kEvent + "E: 12 0002 0000 1\n", 3, "bad time '12'; expected <sec>.<usec>"},
      {kName + kEvent + "E: 1.x 0002 0000 1\n", 3, "bad time '1.x'"},
      {kName + kEvent + "E: 9223372036854.775808 0002 0000 1\n", 3, "too large"},
      {kName + kEvent + "E: 99999999999999999999999.0 0002 0000 1\n", 3, "too large"},
      {kName + "\x01\x02garbage\n", 2, "binary data (byte 0x01)"},
      {kName + "N\r: x\n", 2, "a carriage return that does not end a line (old Mac line endings?)"},
      {kName + "E: 0.000000 0002 0000 1\rE: 0.000000 0000 0000 0\r", 2, "a carriage return that does not end"},
      {kName +
           [] {  // a whole file of old Mac line endings: one line longer than a line may be
             std::string lines;
             while (lines.size() < 6000) lines += "E: 0.000000 0002 0000 1\r";
             return lines;
           }(),
       2, "a carriage return that does not end"},
      {kName + "# a comment with a \x7f\n", 2, "binary data"},
      {"# EVEMU 2.0\nN: a\n", 1, "evemu format version 2.0 is not supported"},
      {"# EVEMU one\nN: a\n", 1, "bad version line"},
      {kName + kEvent + std::string(5000, 'x') + "\n", 3, "line longer than 4096 characters"},
      {kName + std::string(4097, ' ') + "\r\n", 2, "line longer than 4096 characters"},
  };
  for (const Mistake& mistake : mistakes) {
    SCOPED_TRACE(mistake.text.substr(0, 200));
    const std::string error = read_error(mistake.text);
    EXPECT_NE(error.find("test:" + std::to_string(mistake.line) + ": "), std::string::npos) << error;
    EXPECT_NE(error.find(mistake.says), std::string::npos) << error;
  }
}

TEST(Evemu, LongestLineIsAccepted) {
  const std::string longest_comment = "# " + std::string(kMaxEvemuLine - 2, 'c');
  EXPECT_EQ(read_text(longest_comment + "\r\nN: m\n").device.name, "m");
  EXPECT_NE(read_error(longest_comment + "c\r\nN: m\n").find("line longer than 4096"), std::string::npos);
}

TEST(Evemu, EmptyOrDescriptionlessInputIsRefused) {
  EXPECT_EQ(read_error(""), "test: empty recording");
  EXPECT_EQ(read_error("\n\n  \r\n"), "test: empty recording");
  EXPECT_EQ(read_error("# EVEMU 1.3\n# only comments\n"), "test: empty recording");
  EXPECT_EQ(read_error("I: 0003 0001 0001 0001\nB: 00 01 00 00 00 00 00 00 00\n"),
            "test: no device description (expected an 'N: <name>' line)");
}

// Serves 'E' and then `spaces` spaces, a few kilobytes at a time, counting what it served: a 1 GB line
// that is never in memory.
class EndlessLine final : public std::streambuf {
 public:
  explicit EndlessLine(std::uint64_t spaces) : left_(spaces + 1) {}
  std::uint64_t served() const { return served_; }

 protected:
  int_type underflow() override {
    if (left_ == 0) return traits_type::eof();
    const std::size_t size = static_cast<std::size_t>(std::min<std::uint64_t>(left_, block_.size()));
    std::fill(block_.begin(), block_.end(), ' ');
    if (served_ == 0) block_[0] = 'E';
    left_ -= size;
    served_ += size;
    setg(block_.data(), block_.data(), block_.data() + size);
    return traits_type::to_int_type(block_[0]);
  }

 private:
  std::array<char, 4096> block_{};
  std::uint64_t left_;
  std::uint64_t served_ = 0;
};

TEST(Evemu, GigabyteLineFailsFastWithoutReadingIt) {
  EndlessLine source(1'000'000'000);
  std::istream in(&source);
  const auto start = std::chrono::steady_clock::now();
  try {
    read_evemu(in, "test");
    FAIL() << "no error";
  } catch (const RecordingError& error) {
    EXPECT_NE(std::string(error.what()).find("test:1: line longer than 4096 characters"), std::string::npos)
        << error.what();
  }
  EXPECT_LT(source.served(), std::uint64_t{1} << 20) << "read far past the limit";
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
}

TEST(Evemu, RandomBytesAreRefused) {
  std::mt19937 random(7);
  for (int round = 0; round < 200; ++round) {
    std::string garbage(1 + random() % 20000, '\0');
    for (char& c : garbage) c = static_cast<char>(random() & 0xff);
    const std::string error = read_error(garbage);
    EXPECT_TRUE(error.starts_with("test:")) << "round " << round << ": " << error;
  }
  std::string bytes(4096, '\0');
  for (char& c : bytes) c = static_cast<char>(random() & 0xff);
  bytes[0] = '\x01';
  EXPECT_TRUE(read_error(bytes).starts_with("test:1: binary data")) << read_error(bytes);
}

}  // namespace
}  // namespace ph
