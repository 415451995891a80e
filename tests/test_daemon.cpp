// The daemon's pieces that need no device: its log lines, its configuration (file, embedded default,
// reload decisions) and its messages to systemd.
#include <fmt/core.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/un.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "common/unique_fd.hpp"
#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "daemon/configuration.hpp"
#include "daemon/log.hpp"
#include "daemon/service_notifier.hpp"
#include "tests/as_nobody.hpp"
#include "tests/geometry_printers.hpp"
#include "tests/scoped_env.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

// What a Logger writes, through a temporary FILE.
class CapturedLog {
 public:
  CapturedLog() : file_(std::tmpfile()) {}
  ~CapturedLog() { std::fclose(file_); }
  CapturedLog(const CapturedLog&) = delete;
  CapturedLog& operator=(const CapturedLog&) = delete;
  std::FILE* file() const { return file_; }
  std::string text() const {
    std::rewind(file_);
    std::string out;
    for (int c = std::fgetc(file_); c != EOF; c = std::fgetc(file_)) out.push_back(static_cast<char>(c));
    return out;
  }

 private:
  std::FILE* file_;
};

TEST(DaemonLog, PlainLinesNameTheProgramAndLevel) {
  const CapturedLog out;
  const Logger log(false, false, out.file());
  log.warning("{} is {}", "x", 3);
  log.info("two\nlines");
  log.debug("hidden without --verbose");
  EXPECT_EQ(out.text(), "pseudohapticd: warning: x is 3\npseudohapticd: info: two lines\n");
}

TEST(DaemonLog, JournalLinesCarryTheSyslogPriority) {
  const CapturedLog out;
  const Logger log(true, true, out.file());
  log.error("e");
  log.notice("n");
  log.debug("d");
  EXPECT_EQ(out.text(), "<3>e\n<5>n\n<7>d\n");
}

// A line that cannot be written is lost, not thrown: fmt's print throws on a failed write, and from a mouse reader
// thread that was std::terminate, the daemon aborted.
TEST(DaemonLog, ALineThatCannotBeWrittenIsLostNotThrown) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  std::FILE* full = std::fopen("/dev/full", "w");
  ASSERT_NE(full, nullptr);
  std::setvbuf(full, nullptr, _IONBF, 0);  // as stderr: each write goes out at once, and fails at once
  const Logger log(true, false, full);
  EXPECT_NO_THROW(log.warning("a reader's read error on {}", "/dev/input/event3"));
  EXPECT_NO_THROW(log.debug("and a debug line"));
  std::fclose(full);
}

TEST(DaemonLog, StderrIsTheJournalOnlyWhenJournalStreamNamesIt) {
  {
    const ScopedEnv none("JOURNAL_STREAM", std::nullopt);
    EXPECT_FALSE(Logger::stderr_is_journal());
  }
  const ScopedEnv other("JOURNAL_STREAM", "1:2");  // some other file
  EXPECT_FALSE(Logger::stderr_is_journal());
}

ConfigChoice choice_in(const ScratchDir& dir) {
  ConfigChoice choice;
  choice.default_file = dir / "scene.toml";  // absent unless a test writes it
  choice.drm_dir = dir / "drm";              // no displays
  return choice;
}

TEST(DaemonConfiguration, MissingDefaultFileMeansTheEmbeddedScene) {
  const ScratchDir dir("daemon-config");
  const Configuration c = load_configuration(choice_in(dir));
  EXPECT_EQ(c.source, "the embedded default scene");
  EXPECT_EQ(c.scene->regions().size(), 3u);
  ASSERT_EQ(c.notes.size(), 2u);
  EXPECT_NE(c.notes[0].find("no scene file at"), std::string::npos) << c.notes[0];
  EXPECT_EQ(c.notes[1],
            "the embedded default scene on the desktop 0,0 1920x1080 px: bump-gaussian-h1-r200 at 135,290, "
            "hole-polynomial-h1-r200 at 710,290, bump-linear-h1-r100 at 1285,290 (500x500 px each)");
  ASSERT_EQ(c.warnings.size(), 1u);  // no display found: 1920 x 1080 assumed
  EXPECT_EQ(c.pipeline.desktop, (Rect{0, 0, 1920, 1080}));
}

// A default file in a folder the service's user cannot search (made under a umask of 077) is not "no scene file": the
// daemon must say it cannot read it, not run the embedded scene in its place.
TEST(DaemonConfiguration, ADefaultFileItCannotReadIsAnErrorNotTheEmbeddedScene) {
  const ScratchDir dir("daemon-config");
  const std::filesystem::path folder = dir / "private";
  std::filesystem::create_directory(folder);
  std::ofstream(folder / "scene.toml") << "[daemon]\npointer_speed = 2.5\n";
  std::filesystem::permissions(dir.path(), std::filesystem::perms::all);  // nobody reaches `private`, no further
  std::filesystem::permissions(folder,
                               ::getuid() == 0 ? std::filesystem::perms::owner_all : std::filesystem::perms::none);
  ConfigChoice choice = choice_in(dir);
  choice.default_file = folder / "scene.toml";
  const int outcome = as_nobody([&] {
    try {
      load_configuration(choice);
      return 1;  // loaded: the test cannot be refused here
    } catch (const ConfigError& e) {
      return std::string(e.what()).find("cannot open the scene file: Permission denied") != std::string::npos ? 0 : 2;
    }
  });
  std::filesystem::permissions(folder, std::filesystem::perms::owner_all);  // for the scratch folder's removal
  EXPECT_EQ(outcome, 0) << "1: loaded (the embedded scene, or the file); 2: another error";
}

TEST(DaemonConfiguration, TheDefaultFileIsReadWhenItExists) {
  const ScratchDir dir("daemon-config");
  std::ofstream(dir / "scene.toml") << "[daemon]\noutput = \"absolute\"\ndesktop = [0, 0, 800, 600]\n"
                                       "pointer_speed = 2.5\n";
  const Configuration c = load_configuration(choice_in(dir));
  EXPECT_EQ(c.source, (dir / "scene.toml").string());
  EXPECT_TRUE(c.scene->regions().empty());
  EXPECT_TRUE(c.notes.empty());
  EXPECT_TRUE(c.warnings.empty());
  EXPECT_EQ(c.pipeline.mode, OutputMode::absolute);
  EXPECT_EQ(c.pipeline.desktop, (Rect{0, 0, 800, 600}));
  EXPECT_EQ(c.pipeline.pointer_gain, 2.5);
}

TEST(DaemonConfiguration, DefaultSceneFlagIgnoresTheFile) {
  const ScratchDir dir("daemon-config");
  std::ofstream(dir / "scene.toml") << "[daemon]\npointer_speed = 2.5\n";
  ConfigChoice choice = choice_in(dir);
  choice.default_scene = true;
  const Configuration c = load_configuration(choice);
  EXPECT_EQ(c.scene->regions().size(), 3u);
  EXPECT_EQ(c.pipeline.pointer_gain, 1.0);
}

TEST(DaemonConfiguration, AnExplicitFileMustExistAndBeValid) {
  const ScratchDir dir("daemon-config");
  ConfigChoice choice = choice_in(dir);
  choice.file = dir / "missing.toml";
  EXPECT_THROW(load_configuration(choice), ConfigError);
  std::ofstream(dir / "bad.toml") << "[daemon]\npointer_sped = 2\n";
  choice.file = dir / "bad.toml";
  try {
    load_configuration(choice);
    FAIL() << "no error for an unknown key";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:2"), std::string::npos) << e.what();
  }
}

TEST(DaemonConfiguration, ReloadKeepsThePipelineWhenOnlyTheSceneChanged) {
  const ScratchDir dir("daemon-config");
  const Configuration base = load_configuration(choice_in(dir));
  Configuration other_scene = base;
  other_scene.scene = std::make_shared<const Scene>();
  EXPECT_TRUE(only_scene_differs(base, other_scene));
  Configuration faster = base;
  faster.pipeline.pointer_gain = 2.0;
  EXPECT_FALSE(only_scene_differs(base, faster));
  Configuration relative = base;
  relative.pipeline.mode = OutputMode::relative;  // absolute is the default
  EXPECT_FALSE(only_scene_differs(base, relative));
  Configuration flat = base;
  flat.pipeline.acceleration.profile = AccelProfile::flat;
  EXPECT_FALSE(only_scene_differs(base, flat));
  Configuration quicker = base;
  quicker.pipeline.acceleration.speed = 0.5;
  EXPECT_FALSE(only_scene_differs(base, quicker));
  Configuration wider = base;
  wider.pipeline.desktop.w = 3840;
  EXPECT_FALSE(only_scene_differs(base, wider));
  // The same desktop with its outputs told (monitors of different sizes): the pipeline must take them too.
  Configuration uneven = base;
  uneven.pipeline.outputs = {{0, 0, 100, 100}};
  EXPECT_FALSE(only_scene_differs(base, uneven));
  Configuration pickier = base;
  std::string error;
  pickier.settings.devices.push_back(*parse_device_match("name:Logitech*", error));
  EXPECT_FALSE(only_scene_differs(base, pickier));
  // The same devices written another way (usb: and id: are one matcher): the mice need not be taken again.
  Configuration by_usb = base, by_id = base;
  by_usb.settings.devices.push_back(*parse_device_match("usb:046d:c077", error));
  by_id.settings.devices.push_back(*parse_device_match("id:046D:C077", error));
  EXPECT_TRUE(only_scene_differs(by_usb, by_id));
  Configuration other_mouse = by_usb;
  other_mouse.settings.devices.back().product = 0xc078;
  EXPECT_FALSE(only_scene_differs(by_usb, other_mouse));
}

// Invalid texels are reported at load (docs/METHODS.md, "Screen, regions and fields"): the daemon logs every
// Configuration warning (Daemon::log_notes), one per region and map that had any, naming both.
TEST(DaemonConfiguration, InvalidTexelsAreWarnedPerRegionAndMap) {
  const ScratchDir dir("daemon-config");
  NormalImage holes(4, 4);  // flat, but 3 texels face away from the viewer (n_z <= 0) and 1 has no length
  holes.at(0, 0) = {0.0f, 0.0f, -1.0f};
  holes.at(1, 2) = {0.6f, 0.0f, -0.8f};
  holes.at(3, 3) = {0.0f, 0.0f, -1.0f};
  holes.at(2, 1) = {0.0f, 0.0f, 0.0f};
  write_normal_png16(dir / "holes.png", holes);
  write_normal_png16(dir / "clean.png", NormalImage(4, 4));
  Grid<float> depth(4, 2, 0.5f);  // 2 of 8 depth texels not finite
  depth.at(1, 0) = std::numeric_limits<float>::quiet_NaN();
  depth.at(2, 1) = std::numeric_limits<float>::infinity();
  write_float_exr(dir / "deep.exr", depth);
  std::ofstream(dir / "scene.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n\n"
                                       "[[region]]\nname = \"clean\"\nx = 0\ny = 0\nwidth = 8\nheight = 8\n"
                                       "normal_map = \"clean.png\"\n\n"
                                       "[[region]]\nname = \"holes\"\nx = 10\ny = 0\nwidth = 8\nheight = 8\n"
                                       "normal_map = \"holes.png\"\n\n"
                                       "[[region]]\nname = \"deep\"\nx = 20\ny = 0\nwidth = 4\nheight = 2\n"
                                       "method = \"depth\"\ndepth_map = \"deep.exr\"\n";
  const Configuration c = load_configuration(choice_in(dir));
  ASSERT_EQ(c.warnings.size(), 2u);  // nothing for the clean region, nothing about the desktop
  const std::string scene = (dir / "scene.toml").string();
  const std::string& normals = c.warnings[0];
  EXPECT_EQ(normals.rfind(scene + ":12: region 'holes': normal map " + (dir / "holes.png").string() + ": ", 0), 0u)
      << normals;
  EXPECT_NE(normals.find("4 of 16 texels invalid"), std::string::npos) << normals;
  const std::string& heights = c.warnings[1];
  EXPECT_EQ(heights.rfind(scene + ":20: region 'deep': depth map " + (dir / "deep.exr").string() + ": ", 0), 0u)
      << heights;
  EXPECT_NE(heights.find("2 of 8 texels invalid"), std::string::npos) << heights;
  // The repaired texels took their neighbours' (flat) values.
  EXPECT_EQ(c.scene->regions().size(), 3u);
  for (const Gradient g : c.scene->regions()[1].fields.gradient->values) {
    EXPECT_EQ(g.x, 0.0f);
    EXPECT_EQ(g.y, 0.0f);
  }
}

// A map resampled to a region of other proportions shows its relief stretched on the screen: warned of, naming the
// map's size and the stretch; a map enlarged in proportion, or a pixel off it, is not.
TEST(DaemonConfiguration, MapsStretchedOutOfProportionAreWarned) {
  const ScratchDir dir("daemon-config-stretch");
  write_normal_png16(dir / "square.png", NormalImage(200, 200));
  Grid<float> heights(40, 20, 0.5f);
  write_gray_png16(dir / "flat.png", heights);
  const auto region = [](const char* name, int x, int w, int h, const char* map) {
    return fmt::format("\n[[region]]\nname = \"{}\"\nx = {}\ny = 0\nwidth = {}\nheight = {}\n{}\n", name, x, w, h, map);
  };
  std::ofstream(dir / "scene.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n"
                                    << region("twice", 0, 400, 400, "normal_map = \"square.png\"")
                                    << region("a-pixel-off", 500, 201, 200, "normal_map = \"square.png\"")
                                    << region("wide", 0, 400, 100, "normal_map = \"square.png\"")
                                    << region("tall", 500, 40, 40, "method = \"depth\"\ndepth_map = \"flat.png\"");
  const Configuration c = load_configuration(choice_in(dir));
  std::string all;
  for (const std::string& w : c.warnings) all += w + "\n";
  ASSERT_EQ(c.warnings.size(), 2u) << all;
  const std::string scene = (dir / "scene.toml").string();
  EXPECT_EQ(c.warnings[0],
            scene + ":20: region 'wide': normal map " + (dir / "square.png").string() +
                ": 200x200 px, resampled to the region's 400x100; out of proportion: stretched by 2 across and "
                "0.5 down");
  EXPECT_EQ(c.warnings[1],
            scene + ":28: region 'tall': depth map " + (dir / "flat.png").string() +
                ": 40x20 px, resampled to the region's 40x40; out of proportion: stretched by 1 across and "
                "2 down");
}

// Settings that flatten what a map holds are warned of at load: normal_encoding = "signed" on a PNG, whose codes are
// all >= 0 (no normal leans left or up), and relief_px = 0 on a map whose heights a method reads.
TEST(DaemonConfiguration, SettingsThatFlattenAMapAreWarned) {
  const ScratchDir dir("daemon-config-flatten");
  write_normal_png16(dir / "bump.png", NormalImage(10, 10));
  write_gray_png16(dir / "heights.png", Grid<float>(10, 10, 0.5f));
  std::ofstream(dir / "scene.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n"
                                       "[[region]]\nname = \"signed\"\nwidth = 10\nheight = 10\n"
                                       "normal_map = \"bump.png\"\nnormal_encoding = \"signed\"\n"
                                       "[[region]]\nname = \"unorm\"\nx = 20\nwidth = 10\nheight = 10\n"
                                       "normal_map = \"bump.png\"\nnormal_encoding = \"unorm\"\n"
                                       "[[region]]\nname = \"level\"\nx = 40\nwidth = 10\nheight = 10\n"
                                       "method = \"depth\"\ndepth_map = \"heights.png\"\nrelief_px = 0\n";
  const Configuration c = load_configuration(choice_in(dir));
  std::string all;
  for (const std::string& w : c.warnings) all += w + "\n";
  ASSERT_EQ(c.warnings.size(), 2u) << all;
  const std::string scene = (dir / "scene.toml").string();
  EXPECT_EQ(c.warnings[0].rfind(scene + ":3: region 'signed': normal map " + (dir / "bump.png").string() +
                                    ": normal_encoding = \"signed\" reads this image's unsigned codes",
                                0),
            0u)
      << all;
  EXPECT_EQ(c.warnings[1].rfind(scene + ":16: region 'level': depth map " + (dir / "heights.png").string() +
                                    ": relief_px = 0 makes every height 0",
                                0),
            0u)
      << all;
}

// Gravity wells whose pattern is empty do nothing: contour levels that miss the heights (a relief_px off by ten), and
// levels = 0, are warned of at load; levels within them are not.
TEST(DaemonConfiguration, WellsWithAnEmptyPatternAreWarned) {
  const ScratchDir dir("daemon-config-wells");
  Grid<float> ramp(20, 20, 0.0f);
  for (std::int32_t y = 0; y < 20; ++y)
    for (std::int32_t x = 0; x < 20; ++x) ramp.at(x, y) = static_cast<float>(x) / 19.0f;
  write_gray_png16(dir / "ramp.png", ramp);
  const auto region = [](const char* name, int x, const char* levels) {
    return fmt::format(
        "\n[[region]]\nname = \"{}\"\nx = {}\nwidth = 20\nheight = 20\nmethod = \"depth\"\n"
        "depth_map = \"ramp.png\"\nrelief_px = 10\n[region.wells]\npattern = \"contours\"\nlevels = {}\n",
        name, x, levels);
  };
  std::ofstream(dir / "scene.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n"
                                    << region("missed", 0, "[50.0, 90.0]") << region("met", 40, "[4.5]")
                                    << region("none", 80, "0");
  const Configuration c = load_configuration(choice_in(dir));
  std::string all;
  for (const std::string& w : c.warnings) all += w + "\n";
  ASSERT_EQ(c.warnings.size(), 2u) << all;
  // A count of 0 is no level at all, not levels that miss the heights.
  EXPECT_NE(c.warnings[1].find("region 'none': wells: levels = 0 asks for no contour, so the pattern is empty"),
            std::string::npos)
      << all;
  EXPECT_EQ(c.warnings[0].rfind((dir / "scene.toml").string() +
                                    ":4: region 'missed': wells: no contour level lies within the region's heights",
                                0),
            0u)
      << all;
  EXPECT_NE(c.warnings[0].find("the wells do nothing"), std::string::npos) << all;
}

// A region off the configured desktop is logged at load (config/scene_file.hpp, desktop_warnings).
TEST(DaemonConfiguration, ARegionOffTheDesktopIsWarned) {
  const ScratchDir dir("daemon-config-off");
  write_normal_png16(dir / "flat.png", NormalImage(10, 10));
  std::ofstream(dir / "scene.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n[[region]]\nname = \"away\"\nx = 900\n"
                                       "y = 0\nwidth = 10\nheight = 10\nnormal_map = \"flat.png\"\n";
  const Configuration c = load_configuration(choice_in(dir));
  ASSERT_EQ(c.warnings.size(), 1u);
  EXPECT_EQ(c.warnings[0].rfind((dir / "scene.toml").string() + ":3: region 'away' at 900,0 (10x10 px) lies outside "
                                                                "the desktop 0,0 800x600 px",
                                0),
            0u)
      << c.warnings[0];
}

// With desktop = "auto" the connected displays give the desktop, and the embedded default scene is laid out for it:
// on a 1366 x 768 laptop, two of its targets side by side in the middle, nothing off the desktop. On a screen
// smaller than a target, the one target left is cut, and the daemon says so at start.
TEST(DaemonConfiguration, TheEmbeddedSceneIsLaidOutForTheDisplaysDesktop) {
  for (const bool tiny : {false, true}) {
    const ScratchDir dir(tiny ? "daemon-config-tiny" : "daemon-config-laptop");
    ConfigChoice choice = choice_in(dir);
    std::filesystem::create_directories(choice.drm_dir / "card0-eDP-1");
    std::ofstream(choice.drm_dir / "card0-eDP-1" / "status") << "connected\n";
    std::ofstream(choice.drm_dir / "card0-eDP-1" / "modes") << (tiny ? "800x480\n" : "1366x768\n");
    const Configuration c = load_configuration(choice);
    if (!tiny) {
      EXPECT_EQ(c.pipeline.desktop, (Rect{0, 0, 1366, 768}));
      ASSERT_EQ(c.scene->regions().size(), 2u);
      EXPECT_EQ(c.scene->regions()[0].rect, (Rect{145, 134, 500, 500}));
      EXPECT_EQ(c.scene->regions()[1].rect, (Rect{720, 134, 500, 500}));
      EXPECT_EQ(c.notes.back(),
                "the embedded default scene on the desktop 0,0 1366x768 px: bump-gaussian-h1-r200 at 145,134, "
                "hole-polynomial-h1-r200 at 720,134 (500x500 px each)");
      EXPECT_TRUE(c.warnings.empty()) << c.warnings.front();
    } else {
      ASSERT_EQ(c.scene->regions().size(), 1u);
      EXPECT_EQ(c.scene->regions()[0].rect, (Rect{150, -10, 500, 500}));
      ASSERT_EQ(c.warnings.size(), 1u);
      EXPECT_EQ(c.warnings[0],
                "the embedded default scene: region 'bump-gaussian-h1-r200' at 150,-10 (500x500 px): only 500x480 px "
                "of it lie on the desktop 0,0 800x480 px (desktop = \"auto\": the connected displays side by side)");
    }
  }
}

// A hybrid region whose depth map holds its relief at half the scale of its normal map (relief_px 50 where the normals
// were made for 100) is warned of, with the relief_px that makes them agree; one whose maps agree is not.
TEST(DaemonConfiguration, MismatchedReliefScalesOfAHybridRegionAreWarned) {
  const ScratchDir dir("daemon-config-scale");
  Grid<float> image(48, 48);  // a dome 0.2 of the relief high, as a 16-bit grey image
  NormalImage normals(48, 48);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 48; ++x) {
      const double dx = x + 0.5 - 24.0, dy = y + 0.5 - 24.0, e = std::exp(-(dx * dx + dy * dy) / 120.0);
      image.at(x, y) = static_cast<float>(0.5 + 0.2 * e);
      const double h = 100.0 * 0.2 * e;  // px, at relief_px 100
      normals.at(x, y) =
          normal_from_gradient({static_cast<float>(-2.0 * dx / 120.0 * h), static_cast<float>(-2.0 * dy / 120.0 * h)});
    }
  }
  write_gray_png16(dir / "dome_depth.png", image);
  write_normal_png16(dir / "dome_normals.png", normals);
  const std::string region = "method = \"hybrid\"\nnormal_map = \"dome_normals.png\"\ndepth_map = \"dome_depth.png\"\n";
  std::ofstream(dir / "scene.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n\n"
                                       "[[region]]\nname = \"agreed\"\nx = 0\ny = 0\nwidth = 48\nheight = 48\n"
                                    << region
                                    << "\n[[region]]\nname = \"halved\"\nx = 100\ny = 0\nwidth = 48\nheight = 48\n"
                                    << region << "relief_px = 50\n";
  const Configuration c = load_configuration(choice_in(dir));
  ASSERT_EQ(c.warnings.size(), 1u);
  const std::string& w = c.warnings[0];
  EXPECT_EQ(w.rfind((dir / "scene.toml").string() + ":14: region 'halved': ", 0), 0u) << w;
  EXPECT_NE(w.find("the normal map's slopes are 2 times the depth map's"), std::string::npos) << w;
  EXPECT_NE(w.find("relief_px = 100 (now 50) makes them agree"), std::string::npos) << w;

  // Where the ratio said nothing: heights upside down, the other green convention, a relief_px far too small. Each
  // made the hybrid read steps everywhere, or none, without a word.
  std::ofstream(dir / "wrong.toml") << "[daemon]\ndesktop = [0, 0, 800, 600]\n\n"
                                       "[[region]]\nname = \"reversed\"\nx = 0\ny = 0\nwidth = 48\nheight = 48\n"
                                    << region << "relief_px = -100\n"
                                    << "\n[[region]]\nname = \"green\"\nx = 100\ny = 0\nwidth = 48\nheight = 48\n"
                                    << region << "normal_green = \"directx\"\n"
                                    << "\n[[region]]\nname = \"flattened\"\nx = 200\ny = 0\nwidth = 48\nheight = 48\n"
                                    << region << "relief_px = 1\n";
  ConfigChoice wrong = choice_in(dir);
  wrong.file = dir / "wrong.toml";
  const Configuration c2 = load_configuration(wrong);
  ASSERT_EQ(c2.warnings.size(), 3u);
  EXPECT_NE(c2.warnings[0].find("region 'reversed': the normal map's slopes are of the opposite sign to the depth "
                                "map's (100 % along x, 100 % along y"),
            std::string::npos)
      << c2.warnings[0];
  EXPECT_NE(c2.warnings[0].find("relief_px = 100 (now -100) makes them agree"), std::string::npos) << c2.warnings[0];
  EXPECT_NE(c2.warnings[1].find("region 'green': along y the normal map's slopes are of the opposite sign to the depth "
                                "map's (100 % of those both show), along x of one sign: normal_green = \"opengl\" "
                                "(now \"directx\") makes them agree"),
            std::string::npos)
      << c2.warnings[1];
  EXPECT_NE(c2.warnings[2].find("region 'flattened': the depth map is all but flat where the normal map shows the "
                                "relief sloping"),
            std::string::npos)
      << c2.warnings[2];
}

// A datagram socket standing in for systemd's notification socket.
class NotifySocket {
 public:
  explicit NotifySocket(const ScratchDir& dir) : path_((dir / "notify").string()) {
    socket_ = UniqueFd(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    path_.copy(address.sun_path, sizeof address.sun_path - 1);
    EXPECT_EQ(::bind(socket_.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
    ::setenv("NOTIFY_SOCKET", path_.c_str(), 1);
  }
  ~NotifySocket() { ::unsetenv("NOTIFY_SOCKET"); }
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  std::string next() const {
    char buffer[1024];
    const ssize_t n = ::recv(socket_.get(), buffer, sizeof buffer, MSG_DONTWAIT);
    return n > 0 ? std::string(buffer, static_cast<std::size_t>(n)) : std::string("(nothing)");
  }

 private:
  std::string path_;
  UniqueFd socket_;
};

TEST(DaemonNotifier, SendsTheStatesSystemdWaitsFor) {
  const ScratchDir dir("notify");
  const NotifySocket socket(dir);
  const ServiceNotifier notifier;
  notifier.ready("1 mice: M\nX");
  EXPECT_EQ(socket.next(), "READY=1\nSTATUS=1 mice: M X");
  notifier.reloading();
  const std::string reloading = socket.next();
  EXPECT_EQ(reloading.rfind("RELOADING=1\nMONOTONIC_USEC=", 0), 0u) << reloading;
  notifier.watchdog();
  EXPECT_EQ(socket.next(), "WATCHDOG=1");
  notifier.stopping();
  EXPECT_EQ(socket.next().rfind("STOPPING=1", 0), 0u);
}

TEST(DaemonNotifier, WatchdogPingsAtHalfTheInterval) {
  const ScopedEnv pid("WATCHDOG_PID", std::nullopt);
  {
    const ScopedEnv none("WATCHDOG_USEC", std::nullopt);
    EXPECT_FALSE(ServiceNotifier::watchdog_interval().has_value());
  }
  const ScopedEnv usec("WATCHDOG_USEC", "10000000");
  const auto interval = ServiceNotifier::watchdog_interval();
  ASSERT_TRUE(interval.has_value());
  EXPECT_EQ(interval->count(), 5'000'000);
}

}  // namespace
}  // namespace ph
