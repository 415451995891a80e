// desktop = "auto": connected DRM connectors read from a sysfs tree (a fake one here).
#include <gtest/gtest.h>

#include <fstream>

#include "config/desktop_geometry.hpp"
#include "tests/geometry_printers.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

void connector(const ScratchDir& drm, const std::string& name, const std::string& status, const std::string& modes) {
  std::filesystem::create_directories(drm / name);
  std::ofstream(drm / name / "status") << status << "\n";
  std::ofstream(drm / name / "modes") << modes;
}

TEST(DesktopGeometry, ConnectedOutputsSideBySide) {
  const ScratchDir drm("drm");
  connector(drm, "card0-HDMI-A-1", "connected", "2560x1440\n1920x1080\n");
  connector(drm, "card0-DP-1", "connected", "1920x1200\n1280x1024\n");
  connector(drm, "card0-DP-2", "disconnected", "");
  connector(drm, "card0-eDP-1", "connected", "");           // no mode listed: skipped
  std::filesystem::create_directories(drm / "card0");       // the card itself
  std::filesystem::create_directories(drm / "renderD128");  // a render node
  const auto modes = connected_modes(drm.path());
  ASSERT_EQ(modes.size(), 2u);
  EXPECT_EQ(modes[0].connector, "card0-DP-1");
  EXPECT_EQ(modes[0].width, 1920);
  EXPECT_EQ(modes[1].height, 1440);
  EXPECT_EQ(desktop_from_modes(modes), (Rect{0, 0, 4480, 1440}));
}

TEST(DesktopGeometry, ConfiguredRectangleWinsAndNothingFallsBackWithAWarning) {
  const ScratchDir drm("drm-empty");
  std::string warning;
  EXPECT_EQ(resolve_desktop(Rect{10, 20, 800, 600}, drm.path(), warning), (Rect{10, 20, 800, 600}));
  EXPECT_TRUE(warning.empty());
  EXPECT_EQ(resolve_desktop(std::nullopt, drm.path(), warning), (Rect{0, 0, 1920, 1080}));
  EXPECT_NE(warning.find("1920x1080"), std::string::npos);
  EXPECT_EQ(resolve_desktop(std::nullopt, "/nonexistent/drm", warning), (Rect{0, 0, 1920, 1080}));
  connector(drm, "card1-HDMI-A-2", "connected", "3840x2160\n");
  EXPECT_EQ(resolve_desktop(std::nullopt, drm.path(), warning), (Rect{0, 0, 3840, 2160}));
  EXPECT_TRUE(warning.empty());
}

TEST(DesktopGeometry, MalformedModesAreSkipped) {
  const ScratchDir drm("drm-bad");
  connector(drm, "card0-VGA-1", "connected", "garbage\n");
  connector(drm, "card0-VGA-2", "connected", "0x0\n");
  connector(drm, "card0-VGA-3", "connected", "1024x768i\n");
  const auto modes = connected_modes(drm.path());
  ASSERT_EQ(modes.size(), 1u);
  EXPECT_EQ(modes[0].width, 1024);
}

}  // namespace
}  // namespace ph
