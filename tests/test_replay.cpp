// The pipeline between source and sink, and `replay`, on generated and real recordings.
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <utility>

#include "core/engine/default_scene.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/replay.hpp"
#include "recording/evemu.hpp"
#include "recording/recording_file.hpp"
#include "tests/recordings.hpp"

namespace ph {
namespace {

using testing::add_frame;
using testing::rel;
using testing::scripted_stroke;

bool is_motion(const InputEvent& e) { return e.type == ev::kRel && (e.code == ev::kRelX || e.code == ev::kRelY); }
// What the absolute output mode emits in place of REL_X/REL_Y.
bool is_position(const InputEvent& e) { return e.type == ev::kAbs && (e.code == ev::kAbsX || e.code == ev::kAbsY); }

std::vector<Frame> frames_of(const std::vector<InputEvent>& events) {
  std::vector<Frame> frames(1);
  for (const InputEvent& e : events) {
    frames.back().events.push_back(e);
    if (e.type == ev::kSyn && e.code == ev::kSynReport) frames.emplace_back();
  }
  if (frames.back().events.empty()) frames.pop_back();
  return frames;
}

// Frame by frame (frames end at SYN_REPORT): the output has the input's frames, each ending in the same
// SYN_REPORT, with the same events other than motion (REL_X/REL_Y in; REL_X/REL_Y or ABS_X/ABS_Y out) in the
// same order, and a frame without motion is unchanged. Returns how many frames differ.
int expect_non_motion_kept_per_frame(const Recording& input, const Recording& output) {
  const std::vector<Frame> in_frames = frames_of(input.events), out_frames = frames_of(output.events);
  EXPECT_EQ(in_frames.size(), out_frames.size());
  int changed = 0;
  for (std::size_t f = 0; f < std::min(in_frames.size(), out_frames.size()); ++f) {
    const std::vector<InputEvent>& in = in_frames[f].events;
    const std::vector<InputEvent>& out = out_frames[f].events;
    std::vector<InputEvent> in_other, out_other;
    for (const InputEvent& e : in) {
      if (!is_motion(e)) in_other.push_back(e);
    }
    for (const InputEvent& e : out) {
      if (!is_motion(e) && !is_position(e)) out_other.push_back(e);
    }
    EXPECT_EQ(out.back(), in.back()) << "frame " << f;  // the same SYN_REPORT
    EXPECT_EQ(in_other, out_other) << "frame " << f;
    if (in_other.size() == in.size()) {
      EXPECT_EQ(out, in) << "frame " << f << " has no motion";
    }
    changed += in != out;
    if (::testing::Test::HasFailure()) break;  // one frame's report is enough
  }
  return changed;
}

Scene flat_region_scene() {
  std::vector<Region> regions(1);
  regions[0].name = "flat";
  regions[0].rect = {0, 0, 1920, 1080};
  regions[0].fields.gradient = GradientField(1920, 1080);
  regions[0].method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  return Scene(std::move(regions));
}

// A bump target at (600, 300); a stroke from the flat outside across its centre.
Scene bump_scene() {
  const auto& targets = all_targets();
  const TargetSpec spec = *std::find_if(targets.begin(), targets.end(),
                                        [](const TargetSpec& t) { return t.name() == "bump-gaussian-h1-r200"; });
  std::vector<Region> regions(1);
  regions[0].name = spec.name();
  regions[0].rect = {600, 300, spec.size, spec.size};
  regions[0].fields.gradient = target_gradient_field(spec);
  regions[0].method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  return Scene(std::move(regions));
}

PipelineConfig start_at(Vec2 start) {
  PipelineConfig config;
  config.start = start;
  return config;
}

TEST(Replay, FlatSceneIsBitIdentical) {
  const Recording input = scripted_stroke(400, 3, -2);
  const Scene empty;
  const Scene flat = flat_region_scene();
  for (const Scene* scene : {&empty, &flat}) {
    const Recording output = replay(input, *scene, PipelineConfig{});
    EXPECT_EQ(output.device, input.device);
    ASSERT_EQ(output.events.size(), input.events.size());
    for (std::size_t i = 0; i < input.events.size(); ++i) ASSERT_EQ(output.events[i], input.events[i]) << "event " << i;
  }
}

TEST(Replay, StrokeOverBumpMatchesTheEngine) {
  const Scene scene = bump_scene();
  const Vec2 start{560.5, 550.5};
  const Recording input = scripted_stroke(300, 2, 0);
  std::vector<FrameReport> reports;
  const Recording output = replay(input, scene, start_at(start), &reports);

  // The engine alone over the same motions (the dropped frame's motion is not applied).
  CursorState cursor = cursor_at(start);
  Vec2 engine_sum, output_sum;
  bool slowed = false, sped_up = false;
  std::size_t report_index = 0;
  for (const Frame& frame : frames_of(input.events)) {
    const FrameReport& report = reports.at(report_index++);
    if (report.dropped) continue;
    std::int32_t dx = 0;
    for (const InputEvent& e : frame.events) dx += is_motion(e) && e.code == ev::kRelX ? e.value : 0;
    if (dx == 0) continue;
    const FrameResult moved = advance(scene, cursor, {static_cast<double>(dx), 0.0});
    engine_sum = engine_sum + moved.display;
    output_sum = output_sum + Vec2{static_cast<double>(report.out_dx), static_cast<double>(report.out_dy)};
    ASSERT_EQ(report.cursor, cursor.position);
    ASSERT_LE(std::abs(output_sum.x - engine_sum.x), 0.5) << "frame at " << report.time;  // carry stays < 1/2
    ASSERT_EQ(output_sum.y, 0.0);
    slowed = slowed || report.out_dx < 2;
    sped_up = sped_up || report.out_dx > 2;
  }
  EXPECT_TRUE(slowed);   // up the bump
  EXPECT_TRUE(sped_up);  // down the other side
  // And the output events carry exactly the reported motion.
  std::int64_t emitted = 0;
  for (const InputEvent& e : output.events) emitted += is_motion(e) && e.code == ev::kRelX ? e.value : 0;
  std::int64_t reported = 0;
  for (const FrameReport& r : reports) reported += r.out_dx;
  EXPECT_EQ(emitted, reported);
}

TEST(Replay, NonMotionEventsPassThroughInTheirFrame) {
  const Scene scene = bump_scene();
  const Recording input = scripted_stroke(300, 3, 1);
  const Recording output = replay(input, scene, start_at({560.5, 520.5}));
  EXPECT_GT(expect_non_motion_kept_per_frame(input, output), 50);  // the texture did change the motion
}

TEST(Replay, NonMotionEventsPassThroughInTheirFrameInAbsoluteMode) {
  const Scene scene = bump_scene();
  for (const auto& [dx, dy] : {std::pair{3, 1}, std::pair{-2, 0}, std::pair{0, 0}}) {
    SCOPED_TRACE(::testing::PrintToString(std::pair{dx, dy}));
    const Recording input = scripted_stroke(300, dx, dy);
    PipelineConfig config = start_at({900.5, 520.5});
    config.mode = OutputMode::absolute;
    const Recording output = replay(input, scene, config);
    const int changed = expect_non_motion_kept_per_frame(input, output);
    // Every frame with motion now carries positions instead (the dropped frame's REL_X is removed).
    int moving = 0;
    for (const Frame& frame : frames_of(input.events)) {
      moving += std::any_of(frame.events.begin(), frame.events.end(), is_motion);
    }
    EXPECT_EQ(changed, moving);
  }
}

// A device without REL_X/REL_Y (a tablet) is not one the daemon takes: in absolute mode too its description stays its
// own, rather than the desktop's ranges over events in the tablet's.
TEST(Replay, ADeviceWithoutRelativeMotionKeepsItsDescriptionInAbsoluteMode) {
  Recording tablet;
  tablet.device.name = "Test Tablet";
  tablet.device.enable(ev::kAbs, ev::kAbsX);
  tablet.device.enable(ev::kAbs, ev::kAbsY);
  tablet.device.absinfo[ev::kAbsX] = AbsInfo{0, 15200, 0, 0, 100};
  tablet.device.absinfo[ev::kAbsY] = AbsInfo{0, 9500, 0, 0, 100};
  tablet.events = {{0, ev::kAbs, ev::kAbsX, 7600}, {0, ev::kAbs, ev::kAbsY, 4750}, {0, ev::kSyn, ev::kSynReport, 0}};
  PipelineConfig config = start_at({960.5, 540.5});
  config.mode = OutputMode::absolute;
  const Recording output = replay(tablet, bump_scene(), config);
  EXPECT_EQ(output.device, tablet.device);
  EXPECT_EQ(output.events, tablet.events);
  // A mouse is described as the daemon's absolute device.
  const Recording mouse = scripted_stroke(10, 3, 1);
  EXPECT_TRUE(replay(mouse, bump_scene(), config).device.has(ev::kAbs, ev::kAbsX));
}

TEST(Replay, DroppedFrameIsPassedThroughAndNotApplied) {
  Recording input;
  input.device = testing::test_mouse();
  add_frame(input, 1000, {rel(ev::kRelX, 5)});
  input.events.push_back({2000, ev::kSyn, ev::kSynDropped, 0});
  input.events.push_back({2001, ev::kRel, ev::kRelX, 40});
  input.events.push_back({2001, ev::kKey, ev::kBtnLeft, 1});
  input.events.push_back({2001, ev::kSyn, ev::kSynReport, 0});
  add_frame(input, 3000, {rel(ev::kRelX, 5)});
  std::vector<FrameReport> reports;
  const Recording output = replay(input, bump_scene(), start_at({100.5, 100.5}), &reports);
  EXPECT_EQ(output.events, input.events);
  ASSERT_EQ(reports.size(), 3u);
  EXPECT_TRUE(reports[1].dropped);
  EXPECT_EQ(reports[2].cursor.x, 110.5);  // 5 + 5, not the dropped 40
}

TEST(Replay, TrailingEventsWithoutSynReportAreKept) {
  Recording input;
  input.device = testing::test_mouse();
  add_frame(input, 1000, {rel(ev::kRelX, 5)});
  input.events.push_back({2000, ev::kKey, ev::kBtnLeft, 1});
  const Recording output = replay(input, Scene{}, PipelineConfig{});
  EXPECT_EQ(output.events, input.events);
}

// Cut off before its SYN_REPORT, the last frame is not applied, as a dropped frame; in absolute mode its motion is
// left out as a dropped frame's is: the absolute device has no REL_X/REL_Y, and a file that had them would replay
// on no device.
TEST(Replay, AFinalFrameWithoutSynReportKeepsNoMotionInAbsoluteMode) {
  Recording input;
  input.device = testing::test_mouse();
  add_frame(input, 1000, {rel(ev::kRelX, 5)});
  input.events.push_back({2000, ev::kRel, ev::kRelX, 5});
  input.events.push_back({2000, ev::kKey, ev::kBtnLeft, 1});
  PipelineConfig config = start_at({100.5, 100.5});
  config.mode = OutputMode::absolute;
  const Recording output = replay(input, bump_scene(), config);
  ASSERT_FALSE(output.events.empty());
  for (const InputEvent& e : output.events) EXPECT_NE(e.type, ev::kRel) << e.code << " " << e.value;
  EXPECT_EQ(output.events.back(), (InputEvent{2000, ev::kKey, ev::kBtnLeft, 1}));
}

// A device that does not declare REL_X and REL_Y is not one the daemon takes: every event passes through unchanged,
// as the tool says, even motion it carries (it used to be rescaled over the scene, into events its description did
// not have).
TEST(Replay, ADeviceWithoutRelativeAxesPassesThroughUnchanged) {
  Recording input = scripted_stroke(30, 4, 0);
  input.device.codes[ev::kRel].reset(ev::kRelY);
  ASSERT_FALSE(input.device.has(ev::kRel, ev::kRelY));
  for (const OutputMode mode : {OutputMode::relative, OutputMode::absolute}) {
    PipelineConfig config = start_at({100.5, 250.5});
    config.mode = mode;
    const Recording output = replay(input, bump_scene(), config);
    EXPECT_EQ(output.device, input.device);
    EXPECT_EQ(output.events, input.events);
  }
}

TEST(Replay, AbsoluteModeEmitsPositionsOnlyWithinTheDesktop) {
  PipelineConfig config = start_at({10.5, 10.5});
  config.mode = OutputMode::absolute;
  config.desktop = {0, 0, 800, 600};
  const Recording input = scripted_stroke(400, -3, 2);
  const Recording output = replay(input, bump_scene(), config);
  EXPECT_FALSE(output.device.has(ev::kRel, ev::kRelX));
  EXPECT_FALSE(output.device.has(ev::kRel, ev::kRelY));
  EXPECT_TRUE(output.device.has(ev::kRel, ev::kRelWheel));
  EXPECT_TRUE(output.device.has(ev::kAbs, ev::kAbsX));
  EXPECT_EQ(output.device.absinfo.at(ev::kAbsX).maximum, 1599);  // half pixels
  int positions = 0;
  for (const InputEvent& e : output.events) {
    ASSERT_FALSE(is_motion(e));
    if (e.type != ev::kAbs) continue;
    ++positions;
    ASSERT_GE(e.value, 0);
    ASSERT_LE(e.value, e.code == ev::kAbsX ? 1599 : 1199);
  }
  EXPECT_GT(positions, 300);
  // Pushed against the left edge, the model sits on it.
  Pipeline pipeline(std::make_shared<const Scene>(), config);
  Frame f;
  f.events = {{0, ev::kRel, ev::kRelX, -50}, {0, ev::kSyn, ev::kSynReport, 0}};
  const Frame out = pipeline.process(f);
  EXPECT_EQ(out.events.front().type, ev::kAbs);
  EXPECT_EQ(out.events.front().value, abs_value_of_pixel(0));  // the centre of the first pixel
}

TEST(Replay, RelativeModeWritesEachAxisOnceAFrame) {
  // Diagonally across the bump: in some frames one axis comes out as it came in and the other changed.
  // The unchanged axis' event is kept and must not be written a second time (a reader would add both).
  const Scene scene = bump_scene();
  const Recording input = scripted_stroke(300, 3, 2);
  std::vector<FrameReport> reports;
  const Recording output = replay(input, scene, start_at({560.5, 300.5}), &reports);
  int one_axis_kept = 0;
  std::int64_t emitted_x = 0, emitted_y = 0, reported_x = 0, reported_y = 0;
  for (const Frame& frame : frames_of(output.events)) {
    int xs = 0, ys = 0;
    for (const InputEvent& e : frame.events) {
      if (!is_motion(e)) continue;
      (e.code == ev::kRelX ? xs : ys) += 1;
      (e.code == ev::kRelX ? emitted_x : emitted_y) += e.value;
    }
    EXPECT_LE(xs, 1);
    EXPECT_LE(ys, 1);
  }
  for (const FrameReport& r : reports) {
    reported_x += r.out_dx;
    reported_y += r.out_dy;
    one_axis_kept += !r.dropped && ((r.out_dx == 3) != (r.out_dy == 2));
  }
  EXPECT_GT(one_axis_kept, 10);  // the case this test is about did occur
  EXPECT_EQ(emitted_x, reported_x);
  EXPECT_EQ(emitted_y, reported_y);
}

TEST(Replay, RelativeModeCarriesFractions) {
  // Uphill at a constant C/D of about 2.34, 1 count per frame: the output alternates so that its sum
  // follows the engine within half a count.
  std::vector<Region> regions(1);
  regions[0].name = "slope";
  regions[0].rect = {0, 0, 1920, 1080};
  regions[0].fields.gradient = GradientField(1920, 1080, Gradient{0.5f, 0.0f});
  regions[0].method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  const Scene scene(std::move(regions));
  Recording input;
  input.device = testing::test_mouse();
  for (int i = 0; i < 1000; ++i) add_frame(input, i * 1000, {rel(ev::kRelX, 1)});
  std::vector<FrameReport> reports;
  replay(input, scene, start_at({100.5, 100.5}), &reports);
  int ones = 0, zeros = 0;
  for (const FrameReport& r : reports) (r.out_dx == 1 ? ones : zeros) += 1;
  const double cd = 1.0 + 0.5 / std::sqrt(1.25) * 3.0;
  EXPECT_NEAR(ones, 1000 / cd, 1.0);
  EXPECT_EQ(ones + zeros, 1000);
}

TEST(Replay, IsDeterministic) {
  const Recording input = scripted_stroke(500, 4, 3);
  const Scene scene = default_scene();
  std::ostringstream a, b;
  write_evemu(a, replay(input, scene, PipelineConfig{}));
  write_evemu(b, replay(input, default_scene(), PipelineConfig{}));
  EXPECT_EQ(a.str(), b.str());
  EXPECT_GT(a.str().size(), 1000u);
}

TEST(Replay, RealRecordingsOnFlatSceneAreBitIdentical) {
  const auto files = testing::recorded_mice();
  ASSERT_EQ(testing::missing_file(files), "");
  for (const auto& file : files) {
    const Recording input = read_recording_file(file.string());
    ASSERT_GT(input.events.size(), 100u);
    const Recording output = replay(input, Scene{}, PipelineConfig{});
    EXPECT_EQ(output.events, input.events) << file;
  }
}

// Over the default scene, in both output modes, every non-motion event of the real recordings stays in its
// frame, in order; the cursor model starts on each target in turn so that the texture changes the motion.
TEST(Replay, RealRecordingsKeepNonMotionEventsInTheirFrame) {
  const auto files = testing::recorded_mice();
  ASSERT_EQ(testing::missing_file(files), "");
  const Scene scene = default_scene();
  for (const auto& file : files) {
    const Recording input = read_recording_file(file.string());
    ASSERT_GT(input.events.size(), 100u);
    for (const OutputMode mode : {OutputMode::relative, OutputMode::absolute}) {
      for (const Vec2 start : {Vec2{385.5, 540.5}, Vec2{960.5, 540.5}, Vec2{1535.5, 540.5}}) {
        SCOPED_TRACE(file.filename().string() + (mode == OutputMode::relative ? " relative" : " absolute") +
                     " from x = " + std::to_string(start.x));
        PipelineConfig config = start_at(start);
        config.mode = mode;
        const Recording output = replay(input, scene, config);
        const int changed = expect_non_motion_kept_per_frame(input, output);
        EXPECT_GT(changed, 0);
        if (::testing::Test::HasFailure()) return;
      }
    }
  }
}

}  // namespace
}  // namespace ph
