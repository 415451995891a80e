// Desktops of several outputs (core/engine/desktop_outputs.hpp): where the pointer may be, where it stops as X's
// RandR stops it, and the cursor model of the pipeline kept there (docs/SERVICE.md, "Absolute output").
#include "core/engine/desktop_outputs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "core/engine/default_scene.hpp"
#include "core/engine/pipeline.hpp"

namespace ph {
namespace {

// The commonest uneven desktop: a 2560 x 1440 monitor and a 1920 x 1080 one to its right, tops aligned. Below the
// smaller one lie 1920 x 360 px that no output shows.
const Rect kDesktop{0, 0, 4480, 1440};
const std::vector<Rect> kOutputs{{0, 0, 2560, 1440}, {2560, 0, 1920, 1080}};

TEST(DesktopOutputs, OnAnOutputExcludesTheFarEdgesAndTheDeadSpace) {
  EXPECT_TRUE(on_an_output(kOutputs, {0, 0}));
  EXPECT_TRUE(on_an_output(kOutputs, {2559.9, 1439.9}));
  EXPECT_TRUE(on_an_output(kOutputs, {4479.9, 1079.9}));
  EXPECT_FALSE(on_an_output(kOutputs, {4479.9, 1080}));
  EXPECT_FALSE(on_an_output(kOutputs, {3000, 1200}));
  EXPECT_FALSE(on_an_output(kOutputs, {-0.1, 10}));
}

TEST(DesktopOutputs, ThePointerStopsOnTheOutputItCameFrom) {
  // Down off the smaller output: at its bottom row, as X holds it (y 1079.x), not at the desktop's.
  const Vec2 down = stop_on_outputs(kOutputs, {3000, 1000}, {3000, 1300});
  EXPECT_EQ(down.x, 3000);
  EXPECT_EQ(std::floor(down.y), 1079);
  // Diagonally from the larger one past its corner into the dead space: on the larger one's right column.
  const Vec2 corner = stop_on_outputs(kOutputs, {2500, 1400}, {2700, 1420});
  EXPECT_EQ(std::floor(corner.x), 2559);
  EXPECT_EQ(corner.y, 1420);
  // From no output (a layout changed under it): the nearest point of the nearest output.
  const Vec2 nearest = stop_on_outputs(kOutputs, {3000, 1300}, {3000, 1300});
  EXPECT_EQ(nearest.x, 3000);
  EXPECT_EQ(std::floor(nearest.y), 1079);
  const Vec2 left = stop_on_outputs(kOutputs, {2600, 1430}, {2600, 1430});
  EXPECT_EQ(std::floor(left.x), 2559);
  EXPECT_EQ(left.y, 1430);
}

TEST(DesktopOutputs, CoverAndContiguity) {
  EXPECT_FALSE(outputs_cover(kOutputs, kDesktop));
  EXPECT_TRUE(outputs_cover({{0, 0, 1920, 1080}, {1920, 0, 1920, 1080}}, {0, 0, 3840, 1080}));
  EXPECT_TRUE(outputs_cover({{0, 0, 1920, 1080}, {0, 0, 1920, 1080}}, {0, 0, 1920, 1080}));  // mirrored
  EXPECT_TRUE(outputs_cover({{0, 0, 100, 100}, {50, 0, 100, 100}}, {0, 0, 150, 100}));       // overlapping
  EXPECT_FALSE(outputs_cover({{0, 0, 100, 100}, {101, 0, 100, 100}}, {0, 0, 201, 100}));     // a 1 px gap
  EXPECT_TRUE(outputs_contiguous(kOutputs));
  EXPECT_TRUE(outputs_contiguous({{0, 0, 100, 100}, {100, 100, 100, 100}}));  // corners touch: X's rule
  EXPECT_FALSE(outputs_contiguous({{0, 0, 100, 100}, {101, 0, 100, 100}}));
  EXPECT_FALSE(outputs_contiguous({{0, 0, 10, 10}, {10, 0, 10, 10}, {30, 0, 10, 10}}));
  EXPECT_TRUE(outputs_contiguous({{0, 0, 10, 10}, {20, 0, 10, 10}, {10, 5, 10, 10}}));  // joined by a third
}

TEST(DesktopOutputs, PointerOutputsAreNoneWhereTheySayNothingOrCannotBeSo) {
  EXPECT_EQ(pointer_outputs(kDesktop, kOutputs), kOutputs);
  EXPECT_TRUE(pointer_outputs({0, 0, 3840, 1080}, {{0, 0, 1920, 1080}, {1920, 0, 1920, 1080}}).empty());
  EXPECT_TRUE(pointer_outputs(kDesktop, {{0, 0, 2560, 1440}, {2560, 0, 1921, 1080}}).empty());  // past the desktop
  EXPECT_TRUE(pointer_outputs(kDesktop, {{0, 0, 2560, 1440}, {2560, 0, 0, 1080}}).empty());     // empty
  EXPECT_TRUE(pointer_outputs(kDesktop, std::vector<Rect>(kMaxOutputs + 1, Rect{0, 0, 10, 10})).empty());
  EXPECT_TRUE(pointer_outputs({0, 0, 5760, 1080}, {{0, 0, 1920, 1080}, {3840, 0, 1920, 1080}}).empty());  // a gap
}

// The embedded default scene lies on one monitor, the largest, not across a seam or where no monitor shows.
TEST(DesktopOutputs, TheDefaultSceneIsLaidOutOnTheLargestOutput) {
  EXPECT_EQ(default_scene_area(kDesktop, kOutputs), (Rect{0, 0, 2560, 1440}));
  EXPECT_EQ(default_scene_area(kDesktop, {}), kDesktop);
  const Rect laptop_below{0, 1440, 1920, 1080};
  EXPECT_EQ(default_scene_area({0, 0, 2560, 2520}, {{0, 0, 2560, 1440}, laptop_below}), (Rect{0, 0, 2560, 1440}));
  const Scene laid_out = default_scene(default_scene_area(kDesktop, kOutputs));
  ASSERT_EQ(laid_out.regions().size(), 3u);
  for (const Region& r : laid_out.regions()) {
    EXPECT_TRUE(r.rect.x >= 0 && r.rect.x + r.rect.w <= 2560 && r.rect.y >= 0 && r.rect.y + r.rect.h <= 1440) << r.name;
  }
}

Frame motion(TimeUs t, std::int32_t dx, std::int32_t dy) {
  Frame in;
  in.events = {{t, ev::kRel, ev::kRelX, dx}, {t, ev::kRel, ev::kRelY, dy}, {t, ev::kSyn, ev::kSynReport, 0}};
  return in;
}

// What a reviewer measured against a real Xorg: the model went on into the space below the smaller monitor while X
// held the pointer at its bottom row, and the hand then moved 360 px up before the cursor did.
TEST(DesktopOutputs, TheModelStopsAtTheEdgeOfItsOutputAndComesBackAtOnce) {
  PipelineConfig config;
  config.mode = OutputMode::absolute;
  config.desktop = kDesktop;
  config.outputs = kOutputs;
  config.start = Vec2{3000.5, 500.5};
  Pipeline pipeline(std::make_shared<const Scene>(), config);
  TimeUs t = 1'000'000;
  for (int i = 0; i < 20; ++i) pipeline.process(motion(t += 8000, 0, 60));
  EXPECT_EQ(pipeline.cursor().position.x, 3000.5);
  EXPECT_EQ(std::floor(pipeline.cursor().position.y), 1079);
  const Frame up = pipeline.process(motion(t += 8000, 0, -60));
  EXPECT_NEAR(pipeline.cursor().position.y, 1020, 1.0);  // at once
  const auto abs_y = std::find_if(up.events.begin(), up.events.end(),
                                  [](const InputEvent& e) { return e.type == ev::kAbs && e.code == ev::kAbsY; });
  ASSERT_NE(abs_y, up.events.end());
  EXPECT_EQ(abs_y->value, abs_value_of_pixel(static_cast<std::int32_t>(std::floor(pipeline.cursor().position.y))));
  // Across onto the larger monitor at a row the smaller one does not have: allowed, the endpoint is on an output.
  for (int i = 0; i < 10; ++i) pipeline.process(motion(t += 8000, -60, 30));
  EXPECT_LT(pipeline.cursor().position.x, 2560);
  EXPECT_GT(pipeline.cursor().position.y, 1080);
  // And right again below the smaller one: stopped at the larger one's right column.
  for (int i = 0; i < 10; ++i) pipeline.process(motion(t += 8000, 60, 0));
  EXPECT_EQ(std::floor(pipeline.cursor().position.x), 2559);
}

TEST(DesktopOutputs, ANewLayoutMovesTheModelOntoAnOutput) {
  PipelineConfig config;
  config.mode = OutputMode::absolute;
  config.desktop = kDesktop;
  config.start = Vec2{3000.5, 1300.5};  // where, with the outputs not yet told, nothing bounds the model
  Pipeline pipeline(std::make_shared<const Scene>(), config);
  EXPECT_EQ(pipeline.cursor().position, (Vec2{3000.5, 1300.5}));
  // Told: the model goes to the nearest point of the nearest output, the smaller one's bottom row.
  pipeline.set_desktop(kDesktop, kOutputs);
  EXPECT_EQ(pipeline.cursor().position.x, 3000.5);
  EXPECT_EQ(std::floor(pipeline.cursor().position.y), 1079);
  // The start of a pipeline made for an uneven desktop (its centre in the dead space) is on an output too.
  PipelineConfig uneven;
  uneven.desktop = kDesktop;
  uneven.outputs = kOutputs;
  uneven.start = Vec2{3500, 1300};
  const Pipeline p2(std::make_shared<const Scene>(), uneven);
  EXPECT_TRUE(on_an_output(kOutputs, p2.cursor().position));
}

}  // namespace
}  // namespace ph
