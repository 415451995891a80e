// core/engine/event.hpp restates the kernel's evdev codes so that the core includes no Linux header; this test
// holds them to the real header.
#include <gtest/gtest.h>
#include <linux/input-event-codes.h>

#include "core/engine/event.hpp"

namespace ph {
namespace {

static_assert(ev::kSyn == EV_SYN && ev::kKey == EV_KEY && ev::kRel == EV_REL && ev::kAbs == EV_ABS &&
              ev::kMsc == EV_MSC && ev::kMaxType == EV_MAX);
static_assert(ev::kSynReport == SYN_REPORT && ev::kSynConfig == SYN_CONFIG && ev::kSynMtReport == SYN_MT_REPORT &&
              ev::kSynDropped == SYN_DROPPED);
static_assert(ev::kRelX == REL_X && ev::kRelY == REL_Y && ev::kRelHWheel == REL_HWHEEL && ev::kRelWheel == REL_WHEEL);
static_assert(ev::kRelWheelHiRes == REL_WHEEL_HI_RES && ev::kRelHWheelHiRes == REL_HWHEEL_HI_RES);
static_assert(ev::kAbsX == ABS_X && ev::kAbsY == ABS_Y && ev::kMscScan == MSC_SCAN);
static_assert(ev::kBtnMouse == BTN_MOUSE && ev::kBtnLeft == BTN_LEFT && ev::kBtnRight == BTN_RIGHT &&
              ev::kBtnMiddle == BTN_MIDDLE);
static_assert(ev::kMaxCode == KEY_MAX);

TEST(EventCodes, MatchTheKernelHeader) {
  // The checks are the static_asserts above; this records that the file was compiled into the suite.
  EXPECT_EQ(ev::kMaxCode, KEY_MAX);
  EXPECT_EQ(ev::kSynDropped, SYN_DROPPED);
}

}  // namespace
}  // namespace ph
