// The frame-effect layer of the traversal (core/effect.hpp): effects of the region under the cursor
// rescale a frame's motor travel before the walk, keep their state in the cursor, see the frame's time,
// and can never make the cursor's motion non-finite or larger than they promise.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "core/effect.hpp"
#include "core/method_flat.hpp"
#include "core/pipeline.hpp"
#include "core/scene.hpp"
#include "core/traversal.hpp"

namespace ph {
namespace {

// Scales the motor by a fixed gain and counts its frames in the state; remembers the last time seen.
class ScaleEffect final : public Effect {
 public:
  explicit ScaleEffect(double gain, Vec2 forced = {}) : gain_(gain), forced_(forced) {}
  std::string_view name() const override { return "scale"; }
  Vec2 apply(const EffectInput& in, EffectState& state) const override {
    state.travel_px += 1.0;  // frames seen
    state.last_motion = in.time;
    if (forced_.x != 0.0 || forced_.y != 0.0) return forced_;
    return in.motor * gain_;
  }
  double min_gain() const override { return std::min(gain_, 1.0); }
  double max_gain() const override { return std::max(gain_, 1.0); }
  std::size_t bytes() const override { return 0; }

 private:
  double gain_;
  Vec2 forced_;
};

Region effect_region(Rect rect, std::vector<EffectPtr> effects) {
  Region region;
  region.name = "effects";
  region.rect = rect;
  region.method = std::make_shared<FlatMethod>();
  region.effects = std::move(effects);
  return region;
}

TEST(Effects, AFrameStartingInTheRegionIsRescaled) {
  const Scene scene({effect_region({100, 100, 200, 200}, {std::make_shared<ScaleEffect>(0.5)})});
  ASSERT_TRUE(scene.has_effects());
  CursorState cursor = cursor_at({150.5, 150.5});
  const FrameResult result = advance(scene, cursor, {10.0, -4.0}, TimeUs{1000});
  EXPECT_DOUBLE_EQ(result.display.x, 5.0);
  EXPECT_DOUBLE_EQ(result.display.y, -2.0);
  EXPECT_DOUBLE_EQ(cursor.position.x, 155.5);
  EXPECT_DOUBLE_EQ(result.cd_min, 2.0);  // the hand moved twice as far as the cursor
  EXPECT_DOUBLE_EQ(result.cd_max, 2.0);
  EXPECT_EQ(cursor.effects[0].last_motion, 1000);
}

TEST(Effects, AFrameStartingOutsideIsNotRescaledEvenIfItEntersTheRegion) {
  const Scene scene({effect_region({100, 100, 200, 200}, {std::make_shared<ScaleEffect>(0.5)})});
  CursorState cursor = cursor_at({90.5, 150.5});
  const FrameResult result = advance(scene, cursor, {20.0, 0.0}, TimeUs{0});
  EXPECT_EQ(result.display.x, 20.0);
  EXPECT_EQ(cursor.effects[0].travel_px, 0.0);
  // The next frame starts inside: now it is.
  EXPECT_DOUBLE_EQ(advance(scene, cursor, {20.0, 0.0}, TimeUs{8000}).display.x, 10.0);
}

TEST(Effects, StateStaysInTheCursorAndStartsAfreshInAnotherEffect) {
  const auto first = std::make_shared<ScaleEffect>(0.5);
  const auto second = std::make_shared<ScaleEffect>(2.0);
  const Scene scene({effect_region({0, 0, 100, 100}, {first}), effect_region({100, 0, 100, 100}, {second})});
  CursorState cursor = cursor_at({10.5, 50.5});
  for (int i = 0; i < 3; ++i) advance(scene, cursor, {1.0, 0.0}, TimeUs{i * 1000});
  EXPECT_EQ(cursor.effects[0].owner, first.get());
  EXPECT_EQ(cursor.effects[0].travel_px, 3.0);
  cursor = [&] {
    CursorState c = cursor_at({150.5, 50.5});
    c.effects = cursor.effects;  // carried over from the first region
    return c;
  }();
  advance(scene, cursor, {1.0, 0.0}, TimeUs{5000});
  EXPECT_EQ(cursor.effects[0].owner, second.get());
  EXPECT_EQ(cursor.effects[0].travel_px, 1.0) << "a new effect's state starts afresh";
}

TEST(Effects, LayeredEffectsEachKeepTheirOwnStateAndEachScalesWhatTheOneBeforeHandedOn) {
  const auto first = std::make_shared<ScaleEffect>(0.5);
  const auto second = std::make_shared<ScaleEffect>(0.5);
  const Scene scene({effect_region({0, 0, 100, 100}, {first, second})});
  CursorState cursor = cursor_at({10.5, 50.5});
  for (int i = 0; i < 3; ++i) {
    // 0.25 of the motor: below the first effect's bound of the hand's travel, within the second's of its input.
    EXPECT_DOUBLE_EQ(advance(scene, cursor, {4.0, 0.0}, TimeUs{i * 1000}).display.x, 1.0) << i;
  }
  EXPECT_EQ(cursor.effects[0].owner, first.get());
  EXPECT_EQ(cursor.effects[1].owner, second.get());
  EXPECT_EQ(cursor.effects[0].travel_px, 3.0) << "neither effect started the other afresh";
  EXPECT_EQ(cursor.effects[1].travel_px, 3.0);
}

TEST(Effects, ARegionWithMoreEffectsThanTheCursorHoldsStatesForIsRefused) {
  std::vector<EffectPtr> effects(kMaxEffectsPerRegion, std::make_shared<ScaleEffect>(1.0));
  EXPECT_NO_THROW(Scene({effect_region({0, 0, 10, 10}, effects)}));
  effects.push_back(std::make_shared<ScaleEffect>(1.0));
  EXPECT_THROW(Scene({effect_region({0, 0, 10, 10}, effects)}), std::invalid_argument);
}

TEST(Effects, FramesWithoutTimeSeeNoTime) {
  const Scene scene({effect_region({0, 0, 100, 100}, {std::make_shared<ScaleEffect>(0.5)})});
  CursorState cursor = cursor_at({50.5, 50.5});
  advance(scene, cursor, {1.0, 0.0});
  EXPECT_EQ(cursor.effects[0].last_motion, kNoTime);
}

TEST(Effects, WhatBreaksAnEffectsPromiseIsIgnored) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Vec2 forced : {Vec2{nan, 1.0}, Vec2{1e6, 0.0}}) {
    const Scene scene({effect_region({0, 0, 100, 100}, {std::make_shared<ScaleEffect>(0.5, forced)})});
    CursorState cursor = cursor_at({50.5, 50.5});
    const FrameResult result = advance(scene, cursor, {4.0, 0.0}, TimeUs{0});
    EXPECT_EQ(result.display.x, 4.0) << "motor kept when an effect returns " << forced.x;
    EXPECT_TRUE(std::isfinite(cursor.position.x));
  }
}

TEST(Effects, ThePipelinePassesTheFrameTimeAndKeepsTheStateAtTheDesktopEdge) {
  auto scene = std::make_shared<const Scene>(
      std::vector<Region>{effect_region({0, 0, 100, 100}, {std::make_shared<ScaleEffect>(0.5)})});
  PipelineConfig config;
  config.desktop = {0, 0, 100, 100};
  config.start = Vec2{95.5, 50.5};
  Pipeline pipeline(scene, config);
  Frame frame;
  frame.events = {{7000, ev::kRel, ev::kRelX, 20}, {7000, ev::kSyn, ev::kSynReport, 0}};
  const Frame out = pipeline.process(frame);
  EXPECT_EQ(pipeline.cursor().effects[0].last_motion, 7000);
  EXPECT_EQ(pipeline.cursor().effects[0].travel_px, 1.0) << "kept through the clamp at the desktop's edge";
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events[0].value, 10);  // half the motion was emitted
}

}  // namespace
}  // namespace ph
