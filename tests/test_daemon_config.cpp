// The daemon's settings (config/daemon_config and the [daemon] table of the scene file): which devices
// match, the defaults, every key, and an error naming file, line and key for every kind of mistake.
#include "config/daemon_config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include "config/scene_file.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

const fs::path kOrigin = fs::path("etc") / "scene.toml";

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

DaemonSettings with(std::initializer_list<std::string_view> matchers) {
  DaemonSettings s;
  for (std::string_view m : matchers) {
    std::string error;
    const auto match = parse_device_match(m, error);
    EXPECT_TRUE(match.has_value()) << m << ": " << error;
    if (match) s.devices.push_back(*match);
  }
  return s;
}

std::string match_error(std::string_view text) {
  std::string error;
  EXPECT_FALSE(parse_device_match(text, error).has_value()) << text;
  return error;
}

void expect_error(std::string_view text, int line, std::string_view key, std::initializer_list<std::string_view> says) {
  SCOPED_TRACE(std::string(text));
  std::string message;
  try {
    parse_scene_text(text, kOrigin);
    ADD_FAILURE() << "no ConfigError";
    return;
  } catch (const ConfigError& e) {
    message = e.what();
  }
  const std::string where = kOrigin.string() + ":" + std::to_string(line) + ":";
  EXPECT_EQ(message.rfind(where, 0), 0u) << "expected it to start with '" << where << "': " << message;
  EXPECT_TRUE(contains(message, key)) << "expected the key '" << key << "': " << message;
  for (std::string_view part : says) EXPECT_TRUE(contains(message, part)) << "expected '" << part << "': " << message;
}

// ---------------------------------------------------------------------------------------------------------------
// device_matches

TEST(DeviceMatches, NoMatchersMeansAnyPointer) {
  const DaemonSettings any;
  EXPECT_TRUE(device_matches(any, "Logitech USB Optical Mouse", 0x046d, 0xc077));
  EXPECT_TRUE(device_matches(any, "", 0, 0));
}

TEST(DeviceMatches, NameGlobs) {
  const DaemonSettings s = with({"name:Logitech*", "name:?? Mouse", "name:Razer [DV]*"});
  EXPECT_TRUE(device_matches(s, "Logitech USB Optical Mouse", 1, 2));
  EXPECT_TRUE(device_matches(s, "Logitech", 1, 2));
  EXPECT_FALSE(device_matches(s, "logitech usb", 1, 2)) << "globs are case-sensitive";
  EXPECT_FALSE(device_matches(s, "A Logitech", 1, 2));
  EXPECT_TRUE(device_matches(s, "HP Mouse", 1, 2));
  EXPECT_FALSE(device_matches(s, "HPX Mouse", 1, 2));
  EXPECT_TRUE(device_matches(s, "Razer DeathAdder", 1, 2));
  EXPECT_TRUE(device_matches(s, "Razer Viper", 1, 2));
  EXPECT_FALSE(device_matches(s, "Razer Basilisk", 1, 2));
}

// A bracket in a device's name is a glob's bracket expression unless escaped, as pseudohapticd(8) says; the man page's
// example, as TOML's double quotes give it to the matcher.
TEST(DeviceMatches, ABracketInTheNameIsMatchedByItselfOnlyEscaped) {
  const std::string name = "Foo [USB] Mouse";
  EXPECT_FALSE(device_matches(with({"name:Foo [USB] Mouse"}), name, 1, 2));
  EXPECT_TRUE(device_matches(with({"name:Foo \\[USB\\]*"}), name, 1, 2));
  const SceneSpec spec = parse_scene_text("[daemon]\ndevices = [\"name:Foo \\\\[USB\\\\]*\"]\n", kOrigin);
  EXPECT_TRUE(device_matches(spec.daemon, name, 1, 2));
  EXPECT_FALSE(device_matches(spec.daemon, "Foo U Mouse", 1, 2));
}

TEST(DeviceMatches, VendorProductIds) {
  const DaemonSettings s = with({"usb:046d:c077", "id:1532:00A5"});
  EXPECT_TRUE(device_matches(s, "whatever", 0x046d, 0xc077));
  EXPECT_TRUE(device_matches(s, "whatever", 0x1532, 0x00a5)) << "hex digits in either case";
  EXPECT_FALSE(device_matches(s, "whatever", 0x046d, 0xc078));
  EXPECT_FALSE(device_matches(s, "whatever", 0xc077, 0x046d));
  EXPECT_EQ(format_device_match(s.devices[0]), "usb:046d:c077");  // said back as written
  EXPECT_EQ(format_device_match(s.devices[1]), "id:1532:00a5");
  // usb: and id: are the same matcher: vendor:product regardless of the bus.
  EXPECT_TRUE(device_matches(with({"id:046d:c077"}), "", 0x046d, 0xc077));
}

TEST(DeviceMatches, MixedListMatchesAny) {
  const DaemonSettings s = with({"name:Kensington*", "id:046d:c077"});
  EXPECT_TRUE(device_matches(s, "Kensington Expert", 0, 0));
  EXPECT_TRUE(device_matches(s, "Logitech", 0x046d, 0xc077));
  EXPECT_FALSE(device_matches(s, "Logitech", 0x046d, 0xc52b));
}

TEST(DeviceMatches, BadMatchers) {
  EXPECT_TRUE(contains(match_error("Logitech*"), "unknown matcher"));
  EXPECT_TRUE(contains(match_error("Logitech*"), "name:GLOB"));
  EXPECT_TRUE(contains(match_error("name:"), "empty"));
  EXPECT_TRUE(contains(match_error("name:Razer [DV"), "'['"));
  EXPECT_TRUE(contains(match_error("name:Mouse\\"), "backslash"));
  for (std::string_view bad : {"usb:46d:c077", "usb:046d", "id:046d:c0777", "id:046g:c077", "id:046d-c077", "id:"}) {
    EXPECT_TRUE(contains(match_error(bad), "4 hex digits")) << bad;
  }
  std::string error;
  EXPECT_TRUE(parse_device_match("name:a[]]b", error).has_value()) << "a leading ] is a bracket member: " << error;
}

// ---------------------------------------------------------------------------------------------------------------
// The [daemon] table

TEST(DaemonTable, DefaultsWithoutTheTable) {
  const SceneSpec spec = parse_scene_text("", kOrigin);
  EXPECT_TRUE(spec.daemon.devices.empty());
  EXPECT_EQ(spec.daemon.output, OutputMode::absolute);
  EXPECT_FALSE(spec.daemon.desktop.has_value());
  EXPECT_DOUBLE_EQ(spec.daemon.pointer_speed, 1.0);
  // Absolute output by default, with the desktop's default acceleration done by the daemon.
  const AccelSettings accel = acceleration_of(spec.daemon);
  EXPECT_EQ(accel.profile, AccelProfile::adaptive);
  EXPECT_EQ(accel.speed, 0.0);
  EXPECT_EQ(accel.dpi, 1000.0);
  EXPECT_EQ(kDefaultSceneFile, "/etc/pseudohaptic/scene.toml");
}

TEST(DaemonTable, DefaultsWithAnEmptyTable) {
  const SceneSpec spec =
      parse_scene_text("[daemon]\n[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n", kOrigin);
  EXPECT_TRUE(spec.daemon.devices.empty());
  EXPECT_EQ(spec.daemon.output, OutputMode::absolute);
  EXPECT_FALSE(spec.daemon.desktop.has_value());
  EXPECT_DOUBLE_EQ(spec.daemon.pointer_speed, 1.0);
  EXPECT_EQ(spec.regions.size(), 1u);
}

TEST(DaemonTable, EveryKey) {
  const SceneSpec spec = parse_scene_text(R"([daemon]
devices = ["name:Logitech*", "usb:046d:c077", "id:1532:00a5"]
output = "absolute"
desktop = [-1920, 0, 3840, 1080]
acceleration = "flat"
speed = -0.5
mouse_dpi = 1600
pointer_speed = 2.5
)",
                                          kOrigin);
  const DaemonSettings& d = spec.daemon;
  ASSERT_EQ(d.devices.size(), 3u);
  EXPECT_EQ(d.devices[0].name_glob, "Logitech*");
  EXPECT_FALSE(d.devices[0].vendor.has_value());
  EXPECT_EQ(d.devices[1].vendor, 0x046d);
  EXPECT_EQ(d.devices[1].product, 0xc077);
  EXPECT_EQ(d.devices[2].vendor, 0x1532);
  EXPECT_EQ(d.devices[2].product, 0x00a5);
  EXPECT_EQ(d.output, OutputMode::absolute);
  ASSERT_TRUE(d.desktop.has_value());
  EXPECT_EQ(d.desktop->x, -1920);
  EXPECT_EQ(d.desktop->y, 0);
  EXPECT_EQ(d.desktop->w, 3840);
  EXPECT_EQ(d.desktop->h, 1080);
  EXPECT_DOUBLE_EQ(d.pointer_speed, 2.5);
  EXPECT_EQ(d.acceleration, AccelProfile::flat);
  EXPECT_EQ(acceleration_of(d).speed, -0.5);
  EXPECT_EQ(acceleration_of(d).dpi, 1600.0);
}

TEST(DaemonTable, RelativeOutputLeavesAccelerationToTheDesktop) {
  const DaemonSettings relative = parse_scene_text("[daemon]\noutput = \"relative\"\n", kOrigin).daemon;
  EXPECT_EQ(acceleration_of(relative).profile, AccelProfile::flat);
  EXPECT_EQ(acceleration_of(relative).speed, 0.0);
  const DaemonSettings chosen =
      parse_scene_text("[daemon]\noutput = \"relative\"\nacceleration = \"adaptive\"\n", kOrigin).daemon;
  EXPECT_EQ(acceleration_of(chosen).profile, AccelProfile::adaptive);
}

TEST(DaemonTable, ExplicitDefaultsAndInlineTable) {
  const SceneSpec spec = parse_scene_text(
      "daemon = { devices = \"any\", output = \"relative\", desktop = \"auto\", pointer_speed = 1 }\n", kOrigin);
  EXPECT_TRUE(spec.daemon.devices.empty());
  EXPECT_EQ(spec.daemon.output, OutputMode::relative);
  EXPECT_FALSE(spec.daemon.desktop.has_value());
  EXPECT_DOUBLE_EQ(spec.daemon.pointer_speed, 1.0);
  EXPECT_DOUBLE_EQ(parse_scene_text("[daemon]\npointer_speed = 100\n", kOrigin).daemon.pointer_speed, 100.0);
}

TEST(DaemonTableErrors, TableItself) {
  expect_error("daemon = 3\n", 1, "daemon", {"must be a table"});
  expect_error("[[daemon]]\noutput = \"relative\"\n", 1, "daemon", {"must be a table"});
  expect_error("[daemon]\noutput = \"relative\"\nsped = 2\n", 3, "daemon.sped",
               {"unknown key", "devices", "output", "desktop", "acceleration", "speed", "pointer_speed"});
  expect_error("[deamon]\noutput = \"relative\"\n", 1, "deamon", {"unknown key", "daemon", "region"});
}

TEST(DaemonTableErrors, Acceleration) {
  expect_error("[daemon]\nacceleration = \"linear\"\n", 2, "daemon.acceleration", {"\"adaptive\"", "\"flat\""});
  expect_error("[daemon]\nspeed = 1.5\n", 2, "daemon.speed", {"from -1 to 1"});
  expect_error("[daemon]\nspeed = nan\n", 2, "daemon.speed", {"from -1 to 1"});
  expect_error("[daemon]\nmouse_dpi = 10\n", 2, "daemon.mouse_dpi", {"from 100 to 100000"});
}

TEST(DaemonTableErrors, Devices) {
  expect_error("[daemon]\ndevices = \"all\"\n", 2, "daemon.devices", {"\"any\"", "name:Logitech*"});
  expect_error("[daemon]\ndevices = 3\n", 2, "daemon.devices", {"\"any\"", "list of matchers"});
  expect_error("[daemon]\ndevices = []\n", 2, "daemon.devices", {"empty", "\"any\""});
  expect_error("[daemon]\ndevices = [\n  \"name:Logitech*\",\n  3,\n]\n", 4, "daemon.devices[1]", {"must be a string"});
  expect_error("[daemon]\ndevices = [\"Logitech*\"]\n", 2, "daemon.devices[0]",
               {"'Logitech*'", "unknown matcher", "name:GLOB", "usb:VVVV:PPPP", "id:VVVV:PPPP"});
  expect_error("[daemon]\ndevices = [\"usb:46d:c077\"]\n", 2, "daemon.devices[0]", {"4 hex digits", "usb:046d:c077"});
  expect_error("[daemon]\ndevices = [\"id:046d:zzzz\"]\n", 2, "daemon.devices[0]", {"4 hex digits"});
  expect_error("[daemon]\ndevices = [\"name:\"]\n", 2, "daemon.devices[0]", {"empty"});
  expect_error("[daemon]\ndevices = [\"name:Razer [DV\"]\n", 2, "daemon.devices[0]", {"'['", "']'"});
}

TEST(DaemonTableErrors, Output) {
  expect_error("[daemon]\noutput = \"abs\"\n", 2, "daemon.output", {"\"relative\"", "\"absolute\""});
  expect_error("[daemon]\noutput = 1\n", 2, "daemon.output", {"must be a string"});
  // Unquoted: TOML cannot tell what it is; the message says what to write.
  expect_error("[daemon]\noutput = absolute\n", 2, "", {"text needs quotes: key = \"value\""});
}

TEST(DaemonTableErrors, Desktop) {
  const std::initializer_list<std::string_view> shape = {"\"auto\"", "[x, y, width, height]"};
  expect_error("[daemon]\ndesktop = \"full\"\n", 2, "daemon.desktop", shape);
  expect_error("[daemon]\ndesktop = 1920\n", 2, "daemon.desktop", shape);
  expect_error("[daemon]\ndesktop = [0, 0, 1920]\n", 2, "daemon.desktop", shape);
  expect_error("[daemon]\ndesktop = [0, 0, 1920.5, 1080]\n", 2, "daemon.desktop", shape);
  expect_error("[daemon]\ndesktop = [0, 0, \"1920\", 1080]\n", 2, "daemon.desktop[2]", shape);
  // Over several lines: the line of the element that is wrong, and which it is.
  expect_error("[daemon]\ndesktop = [\n  0,\n  0,\n  1920,\n  \"1080\",\n]\n", 6, "daemon.desktop[3]",
               {"height must be a whole number"});
  expect_error("[daemon]\ndesktop = [0, 0, 0, 1080]\n", 2, "daemon.desktop", {"width and height", "between 1 and"});
  expect_error("[daemon]\ndesktop = [0, 0, 1920, -1080]\n", 2, "daemon.desktop", {"width and height", "-1080"});
  expect_error("[daemon]\ndesktop = [0, 0, 1920, 1080000000]\n", 2, "daemon.desktop", {"width and height"});
  expect_error("[daemon]\ndesktop = [99999999, 0, 1920, 1080]\n", 2, "daemon.desktop", {"x and y", "between"});
}

TEST(DaemonTableErrors, PointerSpeed) {
  for (std::string_view bad : {"0", "-1", "1e-300", "0.0099", "100.5", "inf", "nan"}) {
    expect_error("[daemon]\n\npointer_speed = " + std::string(bad) + "\n", 3, "daemon.pointer_speed",
                 {"finite number from 0.01 to 100"});
  }
  EXPECT_DOUBLE_EQ(parse_scene_text("[daemon]\npointer_speed = 0.01\n", kOrigin).daemon.pointer_speed, 0.01);
  expect_error("[daemon]\npointer_speed = \"fast\"\n", 2, "daemon.pointer_speed", {"must be a number"});
}

}  // namespace
}  // namespace ph
