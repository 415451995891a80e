// The virtual output device, as far as a machine without /dev/uinput can check it: what it announces,
// which keys it must release on exit, and what a user is told when uinput is missing.
#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>

#include "core/pipeline.hpp"
#include "tests/recordings.hpp"
#include "uinput/uinput_sink.hpp"

namespace ph {
namespace {

TEST(Uinput, DescriptionAnnouncesTheSourceCapabilities) {
  const DeviceDescription mouse = testing::test_mouse();
  const LibevdevPtr dev = describe(mouse);
  EXPECT_STREQ(libevdev_get_name(dev.get()), mouse.name.c_str());
  EXPECT_EQ(libevdev_get_id_vendor(dev.get()), mouse.vendor);
  EXPECT_EQ(libevdev_get_id_product(dev.get()), mouse.product);
  for (std::uint16_t code : {ev::kRelX, ev::kRelY, ev::kRelWheel, ev::kRelWheelHiRes, ev::kRelHWheelHiRes}) {
    EXPECT_TRUE(libevdev_has_event_code(dev.get(), EV_REL, code)) << code;
  }
  EXPECT_TRUE(libevdev_has_event_code(dev.get(), EV_KEY, BTN_LEFT));
  EXPECT_TRUE(libevdev_has_event_code(dev.get(), EV_MSC, MSC_SCAN));
  EXPECT_FALSE(libevdev_has_event_type(dev.get(), EV_ABS));
}

TEST(Uinput, AbsoluteOutputIsATabletLikePointerWithoutRelativeMotion) {
  PipelineConfig config;
  config.mode = OutputMode::absolute;
  config.desktop = {0, 0, 2560, 1440};
  const LibevdevPtr dev = describe(output_device(testing::test_mouse(), config));
  EXPECT_FALSE(libevdev_has_event_code(dev.get(), EV_REL, REL_X));
  EXPECT_FALSE(libevdev_has_event_code(dev.get(), EV_REL, REL_Y));
  EXPECT_TRUE(libevdev_has_event_code(dev.get(), EV_REL, REL_WHEEL));  // wheels stay relative
  ASSERT_TRUE(libevdev_has_event_code(dev.get(), EV_ABS, ABS_X));
  EXPECT_EQ(libevdev_get_abs_minimum(dev.get(), ABS_X), 0);
  EXPECT_EQ(libevdev_get_abs_maximum(dev.get(), ABS_X), 5119);  // half pixels
  EXPECT_EQ(libevdev_get_abs_maximum(dev.get(), ABS_Y), 2879);
  EXPECT_TRUE(libevdev_has_event_code(dev.get(), EV_KEY, BTN_LEFT));
}

TEST(HeldKeysTest, ReleasesExactlyWhatIsStillDown) {
  HeldKeys held;
  EXPECT_TRUE(held.release_all(0).events.empty());
  held.observe({1, ev::kKey, ev::kBtnLeft, 1});
  held.observe({2, ev::kKey, ev::kBtnRight, 1});
  held.observe({3, ev::kKey, ev::kBtnLeft, 0});
  held.observe({4, ev::kKey, ev::kBtnMiddle, 2});  // autorepeat counts as held
  held.observe({5, ev::kRel, ev::kRelX, 1});       // not a key
  const Frame release = held.release_all(9);
  ASSERT_EQ(release.events.size(), 3u);
  EXPECT_EQ(release.events[0], (InputEvent{9, ev::kKey, ev::kBtnRight, 0}));
  EXPECT_EQ(release.events[1], (InputEvent{9, ev::kKey, ev::kBtnMiddle, 0}));
  EXPECT_EQ(release.events[2], (InputEvent{9, ev::kSyn, ev::kSynReport, 0}));
}

TEST(Uinput, ErrorMessagesSayWhatToDo) {
  EXPECT_NE(uinput_error_message(-ENOENT).find("modprobe uinput"), std::string::npos);
  EXPECT_NE(uinput_error_message(-EACCES).find("root"), std::string::npos);
  EXPECT_NE(uinput_error_message(-EINVAL).find("/dev/uinput"), std::string::npos);
}

TEST(Uinput, MissingUinputIsAClearErrorNotACrash) {
  if (std::filesystem::exists("/dev/uinput")) GTEST_SKIP() << "this machine has /dev/uinput (the VM tests cover it)";
  try {
    UinputSink sink(testing::test_mouse());
    FAIL() << "created a uinput device without /dev/uinput";
  } catch (const UinputError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/uinput"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ph
