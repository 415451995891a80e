// End-to-end tests of `pseudohaptic replay` (tools/cmd_replay.cpp): run the built binary as a user would and
// compare what it writes with the pipeline run in this process. Its flags, standard input and output, what
// is (not) left behind on an error, FIFOs and symbolic links as outputs, the device of a multi-device
// libinput record file, and determinism across processes.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/replay.hpp"
#include "recording/evemu.hpp"
#include "recording/libinput_record.hpp"
#include "recording/recording_file.hpp"
#include "tests/recordings.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/tool_runner.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = PH_TEST_DATA_DIR;
constexpr std::string_view kTraceHeader = "time_us,in_dx,in_dy,out_dx,out_dy,cursor_x,cursor_y,cd_min,cd_max,dropped\n";

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

std::string evemu_text(const Recording& recording) {
  std::ostringstream out;
  write_evemu(out, recording);
  return out.str();
}

Recording evemu_of(const std::string& text) {
  std::istringstream in(text);
  return read_evemu(in, "output");
}

void write_file(const fs::path& path, std::string_view text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  ASSERT_TRUE(out.good()) << path;
}

// The trace the tool should write for these reports (its format, column by column).
std::string trace_of(const std::vector<FrameReport>& reports) {
  std::string text(kTraceHeader);
  for (const FrameReport& r : reports) {
    text += fmt::format("{},{},{},{},{},{:.4f},{:.4f},{:.6g},{:.6g},{}\n", r.time, r.in_dx, r.in_dy, r.out_dx, r.out_dy,
                        r.cursor.x, r.cursor.y, r.cd_min, r.cd_max, r.dropped ? 1 : 0);
  }
  return text;
}

// The names in a directory, except the files run_tool writes.
std::set<std::string> listing(const ScratchDir& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    const std::string name = entry.path().filename().string();
    if (name != "stdout.txt" && name != "stderr.txt") names.insert(name);
  }
  return names;
}

std::size_t frames_in(const Recording& r) {
  std::size_t n = 0;
  for (const InputEvent& e : r.events) n += e.type == ev::kSyn && e.code == ev::kSynReport;
  return n;
}

PipelineConfig start_at(Vec2 start) {
  PipelineConfig config;
  config.start = start;
  return config;
}

// A scripted stroke (buttons, wheels, MSC_SCAN, a SYN_DROPPED) written to `name` in the scratch directory.
fs::path stroke_file(const ScratchDir& dir, const std::string& name = "in.evemu", int frames = 300, std::int32_t dx = 3,
                     std::int32_t dy = 1) {
  const fs::path path = dir / name;
  write_file(path, evemu_text(testing::scripted_stroke(frames, dx, dy)));
  return path;
}

// Reads a FIFO in a thread while the tool writes into it.
class FifoReader {
 public:
  explicit FifoReader(fs::path path) : path_(std::move(path)) {
    thread_ = std::thread([this] {
      const int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);  // waits for a writer
      if (fd >= 0) {
        char buffer[1 << 16];
        for (;;) {
          const ssize_t n = ::read(fd, buffer, sizeof buffer);
          if (n < 0 && errno == EINTR) continue;
          if (n <= 0) break;
          text_.append(buffer, static_cast<std::size_t>(n));
        }
        ::close(fd);
      }
      done_ = true;
    });
  }
  FifoReader(const FifoReader&) = delete;
  FifoReader& operator=(const FifoReader&) = delete;
  ~FifoReader() {
    if (thread_.joinable()) finish();
  }

  // Once the tool has exited: what it wrote. A writer of our own, opened and closed, ends a reader that is
  // still waiting because the tool never opened the FIFO.
  std::string finish() {
    while (!done_) {
      const int fd = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
      if (fd >= 0) ::close(fd);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    thread_.join();
    return text_;
  }

 private:
  fs::path path_;
  std::string text_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

void make_fifo(const fs::path& path) { ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0) << path << ": " << errno; }

TEST(ReplayTool, HelpNamesEveryFlag) {
  ScratchDir dir;
  const ToolResult r = run_tool("replay --help", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  for (std::string_view flag :
       {"INPUT", "OUTPUT", "--scene", "--method", "--trace", "--start", "--output-mode", "--desktop", "--gain",
        "--device", "--as-daemon", "bump-gaussian-h1-r200", "FIFO", "symbolic link"}) {
    EXPECT_TRUE(contains(r.out, flag)) << "expected '" << flag << "' in: " << r.out;
  }
}

// Without --scene: the embedded default scene, the cursor model at the desktop's centre (on the hole target).
TEST(ReplayTool, DefaultSceneRescalesMotionAndKeepsTheRest) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  const ToolResult r = run_tool("replay " + quote(in) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "replayed")) << r.err;
  const Recording input = testing::scripted_stroke(300, 3, 1);
  const std::string expected = evemu_text(replay(input, default_scene(), PipelineConfig{}));
  const std::string output = read_text(dir / "out.evemu");
  EXPECT_EQ(output, expected);
  EXPECT_NE(output, read_text(in));  // the texture changed the motion
  EXPECT_EQ(evemu_of(output).device, input.device);
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "out.evemu"}));  // no temporary file left
}

// --method replays one recording under another method: every region's, the embedded scene's or a scene file's.
TEST(ReplayTool, MethodReplacesEveryRegionsMethod) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  const Recording input = testing::scripted_stroke(300, 3, 1);
  auto run = [&](const std::string& flags, const std::string& out) {
    const ToolResult r = run_tool("replay " + flags + " " + quote(in) + " " + quote(dir / out), dir);
    EXPECT_EQ(r.rc, 0) << r.err;
    return read_text(dir / out);
  };
  const std::string curvature = run("", "default.evemu");
  EXPECT_EQ(run("--method curvature", "curvature.evemu"), curvature);  // the embedded scene's own
  EXPECT_EQ(run("--method none", "none.evemu"), read_text(in));        // C/D 1: the input, byte for byte
  const std::string depth = run("--method depth", "depth.evemu");
  RegionSpec depth_method;
  depth_method.method = "depth";
  EXPECT_EQ(depth, evemu_text(replay(input, default_scene(make_method(depth_method)), PipelineConfig{})));
  EXPECT_NE(depth, curvature);
  {
    SCOPED_TRACE("a scene file's regions");
    const TargetSpec bump = all_targets().front();
    write_target_files(dir.path(), {bump});
    const fs::path scene = target_file_paths(dir.path(), bump).scene;
    SceneSpec spec = parse_scene_file(scene);
    ASSERT_NE(spec.regions.front().method, "depth");
    spec.regions.front().method = "depth";
    EXPECT_EQ(run("--method depth --start 20.5,250.5 --scene " + quote(scene), "scene-depth.evemu"),
              evemu_text(replay(input, load_scene(spec), start_at({20.5, 250.5}))));
  }
  expect_clean_failure(run_tool("replay --method bogus " + quote(in) + " " + quote(dir / "x.evemu"), dir),
                       {"--method", "bogus"});
  EXPECT_FALSE(fs::exists(dir / "x.evemu"));
}

TEST(ReplayTool, SceneFileIsUsed) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir, "in.evemu", 200, 3, 0);
  const Recording input = testing::scripted_stroke(200, 3, 0);
  const std::string start = " --start 20.5,250.5 ";
  {
    SCOPED_TRACE("a target's scene file: the bump at (0, 0)");
    const auto& targets = all_targets();
    const auto found = std::find_if(targets.begin(), targets.end(),
                                    [](const TargetSpec& t) { return t.name() == "bump-gaussian-h1-r200"; });
    ASSERT_NE(found, targets.end());
    const TargetSpec bump = *found;
    write_target_files(dir.path(), {bump});
    const fs::path scene = target_file_paths(dir.path(), bump).scene;
    const ToolResult r =
        run_tool("replay --scene " + quote(scene) + start + quote(in) + " " + quote(dir / "bump.evemu"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    const std::string expected =
        evemu_text(replay(input, load_scene(parse_scene_file(scene)), start_at({20.5, 250.5})));
    EXPECT_EQ(read_text(dir / "bump.evemu"), expected);
    EXPECT_NE(expected, read_text(in));
  }
  {
    SCOPED_TRACE("a scene file without regions: the output is the input, byte for byte");
    write_file(dir / "flat.toml", "[daemon]\noutput = \"relative\"\n");
    const ToolResult r = run_tool(
        "replay --scene " + quote(dir / "flat.toml") + start + quote(in) + " " + quote(dir / "flat.evemu"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(read_text(dir / "flat.evemu"), read_text(in));
  }
  {
    SCOPED_TRACE("a scene file that does not load");
    write_file(dir / "bad.toml", "[[region]]\nname = \"x\"\nwidth = -1\n");
    const ToolResult r =
        run_tool("replay --scene " + quote(dir / "bad.toml") + " " + quote(in) + " " + quote(dir / "bad.evemu"), dir);
    expect_clean_failure(r, {"bad.toml"});
    EXPECT_FALSE(fs::exists(dir / "bad.evemu"));
  }
}

TEST(ReplayTool, WarnsOfInvalidTexelsInTheScene) {
  ScratchDir dir;
  NormalImage holes(4, 4);  // flat, with 2 texels facing away from the viewer (repaired from their neighbours)
  holes.at(1, 1) = {0.0f, 0.0f, -1.0f};
  holes.at(3, 0) = {0.6f, 0.0f, -0.8f};
  write_normal_png16(dir / "holes.png", holes);
  write_file(dir / "scene.toml", "[[region]]\nname = \"holes\"\nwidth = 4\nheight = 4\nnormal_map = \"holes.png\"\n");
  const fs::path in = stroke_file(dir, "in.evemu", 20, 1, 0);
  const ToolResult r =
      run_tool("replay --scene " + quote(dir / "scene.toml") + " " + quote(in) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "pseudohaptic: warning: " + (dir / "scene.toml").string() +
                                  ":1: region 'holes': normal map " + (dir / "holes.png").string() +
                                  ": 2 of 16 texels invalid"))
      << r.err;
}

// A scene file fine with its own method may not be with the one --method asks for: the error says whose it was.
TEST(ReplayTool, AnErrorOfTheMethodFromTheCommandLineSaysSo) {
  ScratchDir dir;
  write_normal_png16(dir / "flat.png", NormalImage(4, 4));
  write_file(dir / "scene.toml", "[[region]]\nname = \"n\"\nwidth = 4\nheight = 4\nnormal_map = \"flat.png\"\n");
  const fs::path in = stroke_file(dir, "in.evemu", 20, 1, 0);
  const ToolResult r = run_tool(
      "replay --scene " + quote(dir / "scene.toml") + " --method depth " + quote(in) + " " + quote(dir / "out.evemu"),
      dir);
  expect_clean_failure(r, {"the depth method needs a depth map", "(the method --method depth gives every region)"});
  EXPECT_FALSE(fs::exists(dir / "out.evemu"));
}

// Gravity wells whose pattern is empty (levels above every height) are warned of, as the daemon warns at load; and
// trace, which loads the scene as replay does, warns alike.
TEST(ReplayTool, WarnsOfWellsWithAnEmptyPatternAsTraceDoes) {
  ScratchDir dir;
  Grid<float> ramp(20, 20, 0.0f);
  for (std::int32_t y = 0; y < 20; ++y)
    for (std::int32_t x = 0; x < 20; ++x) ramp.at(x, y) = static_cast<float>(x) / 19.0f;
  write_gray_png16(dir / "ramp.png", ramp);
  const auto scene = [&](const std::string& file, const std::string& levels) {
    write_file(dir / file,
               "[[region]]\nname = \"ramp\"\nwidth = 20\nheight = 20\nmethod = \"depth\"\n"
               "depth_map = \"ramp.png\"\nrelief_px = 10\n[region.wells]\npattern = \"contours\"\n"
               "levels = " +
                   levels + "\n");
    return dir / file;
  };
  const fs::path missed = scene("missed.toml", "[50.0, 90.0]");
  const fs::path met = scene("met.toml", "[4.5]");
  const fs::path in = stroke_file(dir, "in.evemu", 20, 1, 0);
  const std::string warning = "pseudohaptic: warning: " + missed.string() +
                              ":1: region 'ramp': wells: no contour level lies within the region's heights";
  const ToolResult r =
      run_tool("replay --scene " + quote(missed) + " " + quote(in) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(contains(r.err, warning)) << r.err;
  const ToolResult t = run_tool("trace --scene " + quote(missed) + " -o " + quote(dir / "t.csv"), dir);
  ASSERT_EQ(t.rc, 0) << t.err;
  EXPECT_TRUE(contains(t.err, warning)) << t.err;
  for (const std::string& command : {"replay --scene " + quote(met) + " " + quote(in) + " " + quote(dir / "out.evemu"),
                                     "trace --scene " + quote(met) + " -o " + quote(dir / "t.csv")}) {
    const ToolResult quiet = run_tool(command, dir);
    ASSERT_EQ(quiet.rc, 0) << command << "\n" << quiet.err;
    EXPECT_FALSE(contains(quiet.err, "warning")) << command << "\n" << quiet.err;
  }
}

TEST(ReplayTool, TraceHasItsHeaderAndOneRowPerFrame) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  const Recording input = testing::scripted_stroke(300, 3, 1);
  const ToolResult r = run_tool("replay --start 100.5,100.5 --trace " + quote(dir / "frames.csv") + " " + quote(in) +
                                    " " + quote(dir / "out.evemu"),
                                dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::string trace = read_text(dir / "frames.csv");
  ASSERT_EQ(trace.substr(0, kTraceHeader.size()), kTraceHeader);

  std::vector<FrameReport> reports;
  const Recording output = replay(input, default_scene(), start_at({100.5, 100.5}), &reports);
  EXPECT_EQ(trace, trace_of(reports));
  EXPECT_EQ(read_text(dir / "out.evemu"), evemu_text(output));

  // One row per frame, the SYN_DROPPED one marked; the first frame moved the model by (3, 1) on the flat.
  std::istringstream lines(trace);
  std::string line;
  std::vector<std::string> rows;
  std::getline(lines, line);
  while (std::getline(lines, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), frames_in(input));
  EXPECT_EQ(rows.front(), "1000000,3,1,3,1,103.5000,101.5000,1,1,0");
  int dropped = 0;
  for (const std::string& row : rows) dropped += row.back() == '1';
  EXPECT_EQ(dropped, 1);
  // The rows' output motion is what the output's events carry.
  std::int64_t emitted = 0, reported = 0;
  for (const InputEvent& e : evemu_of(read_text(dir / "out.evemu")).events) {
    emitted += e.type == ev::kRel && e.code == ev::kRelX ? e.value : 0;
  }
  for (const FrameReport& f : reports) reported += f.out_dx;
  EXPECT_EQ(emitted, reported);
  bool slowed = false;
  for (const FrameReport& f : reports) slowed = slowed || f.cd_max > 1.0;
  EXPECT_TRUE(slowed);  // the stroke reached a target
}

TEST(ReplayTool, StartPlacesTheCursorModel) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir, "in.evemu", 100, 3, 0);
  auto run = [&](const std::string& start, const std::string& out) {
    const ToolResult r = run_tool("replay --start" + (start.starts_with('=') ? start : " " + start) + " --trace " +
                                      quote(dir / (out + ".csv")) + " " + quote(in) + " " + quote(dir / out),
                                  dir);
    EXPECT_EQ(r.rc, 0) << r.err;
  };
  run("10.5,10.5", "top.evemu");     // a horizontal stroke above every target: nothing changes
  run("385.5,540.5", "bump.evemu");  // from the centre of the Gaussian bump
  EXPECT_EQ(read_text(dir / "top.evemu"), read_text(in));
  EXPECT_NE(read_text(dir / "bump.evemu"), read_text(in));
  EXPECT_TRUE(contains(read_text(dir / "top.evemu.csv"), "\n1000000,3,0,3,0,13.5000,10.5000,1,1,0\n"));
  EXPECT_TRUE(contains(read_text(dir / "bump.evemu.csv"), "\n1000000,3,0,"));
  EXPECT_TRUE(contains(read_text(dir / "bump.evemu.csv"), ",540.5000,"));
  {
    SCOPED_TRACE("a start outside the desktop is kept inside it");
    run("=-50,-50", "corner.evemu");
    EXPECT_TRUE(contains(read_text(dir / "corner.evemu.csv"), "\n1000000,3,0,3,0,3.0000,0.0000,1,1,0\n"));
  }
  {
    SCOPED_TRACE("a malformed start");
    const ToolResult r = run_tool("replay --start 1 " + quote(in) + " " + quote(dir / "x.evemu"), dir);
    expect_clean_failure(r, {"--start: expected X,Y (two numbers separated by a comma)"});
    EXPECT_FALSE(fs::exists(dir / "x.evemu"));
  }
  {
    SCOPED_TRACE("a start that is not a finite number: refused with the command line (exit 2 or more)");
    for (const char* start : {"nan,3", "1e400,3"}) {
      const ToolResult r =
          run_tool("replay --start " + std::string(start) + " " + quote(in) + " " + quote(dir / "x.evemu"), dir);
      expect_clean_failure(r, {"--start: must be a finite number"});
      EXPECT_GE(r.rc, 2) << start;
      EXPECT_FALSE(fs::exists(dir / "x.evemu"));
    }
  }
}

// --start and --desktop take their one argument wherever they stand. Before INPUT and OUTPUT with an option after
// them, CLI11 took INPUT and OUTPUT for more numbers ("--start: At Most 2 required but received 4"), even from
// --start=X,Y.
TEST(ReplayTool, CommaOptionsBeforeThePositionalsLeaveThemAlone) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir, "in.evemu", 100, 3, 0);
  auto run = [&](const std::string& before, const std::string& out, const std::string& after) {
    const ToolResult r = run_tool("replay " + before + " " + quote(in) + " " + quote(dir / out) + " " + after, dir);
    EXPECT_EQ(r.rc, 0) << before << " IN OUT " << after << ": " << r.err;
  };
  const std::string options = "--start 385.5,540.5 --desktop 0,0,1920,1080";
  run("", "after.evemu", options + " --trace " + quote(dir / "after.csv"));
  run(options, "before.evemu", "--trace " + quote(dir / "before.csv"));
  run("--start=385.5,540.5 --desktop=0,0,1920,1080", "equals.evemu", "--trace " + quote(dir / "equals.csv"));
  const std::string replayed = read_text(dir / "after.evemu");
  EXPECT_NE(replayed, read_text(in));  // from the centre of the Gaussian bump: slowed
  for (const char* name : {"before", "equals"}) {
    EXPECT_EQ(read_text(dir / (std::string(name) + ".evemu")), replayed) << name;
    EXPECT_EQ(read_text(dir / (std::string(name) + ".csv")), read_text(dir / "after.csv")) << name;
  }
  run("--start=400,300", "daemon.evemu", "--as-daemon");
  EXPECT_TRUE(fs::exists(dir / "daemon.evemu"));
}

// --desktop takes what a scene file's desktop takes: one of 2e9 px gave absolute output an axis range that
// overflowed ("A: 00 0 -294967297") without a word. It is a command-line error (exit 105), found before the
// recording is read: a missing recording is not what is reported.
TEST(ReplayTool, DesktopIsRefusedWhereASceneFileRefusesIt) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir, "in.evemu", 10, 3, 0);
  for (std::string_view desktop : {"0,0,0,100", "0,0,2000000000,100", "2000000000,0,100,100", "0,-1048577,10,10"}) {
    SCOPED_TRACE(desktop);
    const ToolResult r = run_tool("replay --output-mode absolute --desktop " + std::string(desktop) + " " + quote(in) +
                                      " " + quote(dir / "x.evemu"),
                                  dir);
    expect_clean_failure(r, {"--desktop: W and H must be from 1 to 1048576, X and Y within ±1048576"});
    EXPECT_EQ(r.rc, 105) << r.err;
    EXPECT_FALSE(fs::exists(dir / "x.evemu"));
  }
  const ToolResult early =
      run_tool("replay --desktop 0,0,0,100 " + quote(dir / "missing.evemu") + " " + quote(dir / "x.evemu"), dir);
  expect_clean_failure(early, {"--desktop: W and H must be from 1"});
  EXPECT_EQ(early.err.find("missing.evemu"), std::string::npos) << early.err;
  const ToolResult widest = run_tool(
      "replay --output-mode absolute --desktop -1048576,0,1048576,100 " + quote(in) + " " + quote(dir / "x.evemu"),
      dir);
  EXPECT_EQ(widest.rc, 0) << widest.err;
  EXPECT_TRUE(contains(read_text(dir / "x.evemu"), "A: 00 -2097152 -1 0 0 0")) << read_text(dir / "x.evemu");
}

// --gain is the scene file's pointer_speed: refused outside the same range (at 1e-300 the cursor never moved).
TEST(ReplayTool, GainIsRefusedWherePointerSpeedIs) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  for (const std::string gain : {"1e-300", "0", "100.5"}) {
    expect_clean_failure(run_tool("replay --gain " + gain + " " + quote(in) + " " + quote(dir / "out.evemu"), dir),
                         {"--gain: must be a finite number from 0.01 to 100, not " + gain});
  }
  EXPECT_FALSE(fs::exists(dir / "out.evemu"));
  EXPECT_EQ(run_tool("replay --gain 0.01 " + quote(in) + " " + quote(dir / "out.evemu"), dir).rc, 0);
}

TEST(ReplayTool, RelativeAndAbsoluteOutputModes) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir, "in.evemu", 400, -3, 2);
  const Recording input = testing::scripted_stroke(400, -3, 2);
  const std::string common = " --start 400.5,300.5 --desktop 0,0,800,600 " + quote(in) + " ";
  const ToolResult first = run_tool("replay" + common + quote(dir / "default.evemu"), dir);
  ASSERT_EQ(first.rc, 0) << first.err;
  // The default scene is laid out for the replay's desktop, as the daemon lays it out for its own: on 800 x 600
  // one target in the middle, nothing off the desktop.
  EXPECT_FALSE(contains(first.err, "warning")) << first.err;
  const Scene on_desktop = default_scene(Rect{0, 0, 800, 600});
  ASSERT_EQ(on_desktop.regions().size(), 1u);
  EXPECT_EQ(on_desktop.regions()[0].rect, (Rect{150, 50, 500, 500}));
  ASSERT_EQ(run_tool("replay --output-mode relative" + common + quote(dir / "relative.evemu"), dir).rc, 0);
  ASSERT_EQ(run_tool("replay --output-mode absolute" + common + quote(dir / "absolute.evemu"), dir).rc, 0);

  PipelineConfig config = start_at({400.5, 300.5});
  config.desktop = {0, 0, 800, 600};
  const std::string relative = read_text(dir / "relative.evemu");
  EXPECT_EQ(read_text(dir / "default.evemu"), relative);
  EXPECT_EQ(relative, evemu_text(replay(input, on_desktop, config)));
  EXPECT_NE(relative, evemu_text(replay(input, default_scene(), config)));  // the 1920 x 1080 layout moves it otherwise
  config.mode = OutputMode::absolute;
  const std::string absolute_text = read_text(dir / "absolute.evemu");
  EXPECT_EQ(absolute_text, evemu_text(replay(input, on_desktop, config)));

  const Recording absolute = evemu_of(absolute_text);
  EXPECT_FALSE(absolute.device.has(ev::kRel, ev::kRelX));
  EXPECT_FALSE(absolute.device.has(ev::kRel, ev::kRelY));
  EXPECT_TRUE(absolute.device.has(ev::kRel, ev::kRelWheel));
  EXPECT_TRUE(absolute.device.has(ev::kAbs, ev::kAbsX));
  EXPECT_EQ(absolute.device.absinfo.at(ev::kAbsX).maximum, 1599);  // half pixels
  EXPECT_EQ(absolute.device.absinfo.at(ev::kAbsY).maximum, 1199);
  int positions = 0;
  for (const InputEvent& e : absolute.events) {
    EXPECT_FALSE(e.type == ev::kRel && (e.code == ev::kRelX || e.code == ev::kRelY));
    if (e.type != ev::kAbs) continue;
    ++positions;
    EXPECT_GE(e.value, 0);
    EXPECT_LE(e.value, e.code == ev::kAbsX ? 1599 : 1199);
  }
  EXPECT_GT(positions, 300);
  EXPECT_EQ(evemu_of(relative).device, input.device);

  const ToolResult bad = run_tool("replay --output-mode sideways" + common + quote(dir / "x.evemu"), dir);
  EXPECT_NE(bad.rc, 0);
  EXPECT_TRUE(contains(bad.err, "--output-mode")) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "x.evemu"));
}

// --as-daemon: the pipeline as the daemon runs it with the scene file (daemon/configuration.cpp), compared with the
// library's pipeline given the same settings by hand.
TEST(ReplayTool, AsDaemonTakesTheSceneFilesDaemonTable) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir, "in.evemu", 300, 4, -2);
  const Recording input = testing::scripted_stroke(300, 4, -2);
  const std::string region = target_scene_text(all_targets()[7]);  // at 0, 0
  write_target_files(dir.path(), {all_targets()[7]});
  write_file(dir / "tuned.toml",
             "[daemon]\noutput = \"relative\"\nacceleration = \"adaptive\"\nspeed = 0.5\n"
             "mouse_dpi = 800\npointer_speed = 2.0\ndesktop = [0, 0, 640, 480]\n" +
                 region);
  write_file(dir / "plain.toml", region);
  const auto run = [&](const std::string& args, const std::string& out) {
    const ToolResult r = run_tool("replay --start 100.5,120.5 " + args + " " + quote(in) + " " + quote(dir / out), dir);
    EXPECT_EQ(r.rc, 0) << args << ": " << r.err;
    return read_text(dir / out);
  };
  const Scene scene = load_scene(parse_scene_file(dir / "plain.toml"));
  PipelineConfig config = start_at({100.5, 120.5});
  {
    SCOPED_TRACE("a [daemon] table: each of its pipeline settings");
    config.mode = OutputMode::relative;
    config.acceleration = {AccelProfile::adaptive, 0.5, 800.0};
    config.pointer_gain = 2.0;
    config.desktop = {0, 0, 640, 480};
    // The trace too: the desktop keeps the cursor model in, which relative output's counts do not show.
    const std::string tuned =
        run("--as-daemon --trace " + quote(dir / "tuned.csv") + " --scene " + quote(dir / "tuned.toml"), "tuned.evemu");
    std::vector<FrameReport> reports;
    EXPECT_EQ(tuned, evemu_text(replay(input, scene, config, &reports)));
    EXPECT_EQ(read_text(dir / "tuned.csv"), trace_of(reports));
    EXPECT_NE(tuned, run("--scene " + quote(dir / "tuned.toml"), "flags.evemu"));  // without it: the flags' defaults
  }
  {
    SCOPED_TRACE("a flag beside it wins over the table");
    config.acceleration.profile = AccelProfile::flat;
    config.pointer_gain = 1.5;
    EXPECT_EQ(run("--as-daemon --acceleration flat --gain 1.5 --scene " + quote(dir / "tuned.toml"), "over.evemu"),
              evemu_text(replay(input, scene, config)));
  }
  {
    SCOPED_TRACE("no [daemon] table: the daemon's defaults, absolute output and adaptive acceleration");
    config = start_at({100.5, 120.5});
    config.mode = OutputMode::absolute;
    config.acceleration = acceleration_of(DaemonSettings{});
    EXPECT_EQ(config.acceleration.profile, AccelProfile::adaptive);
    EXPECT_EQ(run("--as-daemon --scene " + quote(dir / "plain.toml"), "plain.evemu"),
              evemu_text(replay(input, scene, config)));
    SCOPED_TRACE("relative output asked for: the acceleration follows it, as in the daemon (flat)");
    config.mode = OutputMode::relative;
    config.acceleration = {};
    EXPECT_EQ(run("--as-daemon --output-mode relative --scene " + quote(dir / "plain.toml"), "relative.evemu"),
              evemu_text(replay(input, scene, config)));
  }
}

TEST(ReplayTool, StandardInputAndOutput) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  const ToolResult file =
      run_tool("replay --trace " + quote(dir / "t.csv") + " " + quote(in) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(file.rc, 0) << file.err;
  {
    SCOPED_TRACE("- -");
    const ToolResult r = run_tool("replay - - < " + quote(in), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(r.out, read_text(dir / "out.evemu"));
    EXPECT_FALSE(contains(r.err, "replayed")) << r.err;  // nothing but the recording on stdout, no chatter
  }
  {
    SCOPED_TRACE("the trace to stdout");
    const ToolResult r = run_tool("replay --trace - - " + quote(dir / "out2.evemu") + " < " + quote(in), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(r.out, read_text(dir / "t.csv"));
    EXPECT_EQ(read_text(dir / "out2.evemu"), read_text(dir / "out.evemu"));
  }
  {
    SCOPED_TRACE("a libinput record file on stdin");
    const ToolResult r = run_tool("replay - - < " + quote(kDataDir / "libinput_mouse.yml"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    std::ifstream yml(kDataDir / "libinput_mouse.yml", std::ios::binary);
    const Recording input = read_libinput_record(yml, "mouse");
    EXPECT_EQ(r.out, evemu_text(replay(input, default_scene(), PipelineConfig{})));
  }
  {
    SCOPED_TRACE("both to stdout");
    const ToolResult r = run_tool("replay --trace - " + quote(in) + " -", dir);
    expect_clean_failure(r, {"stdout"});
    EXPECT_TRUE(r.out.empty());
  }
}

// Replaces line `number` (from 1) of `text`.
std::string with_line(const std::string& text, int number, const std::string& replacement) {
  std::istringstream lines(text);
  std::string line, result;
  for (int i = 1; std::getline(lines, line); ++i) result += (i == number ? replacement : line) + "\n";
  return result;
}

TEST(ReplayTool, MalformedInputNamesFileAndLineAndWritesNothing) {
  ScratchDir dir;
  const std::string good = evemu_text(testing::scripted_stroke(50, 3, 1));
  // The 21st event line.
  std::istringstream lines(good);
  std::string line;
  int event_line = 0;
  for (int i = 1; event_line == 0 && std::getline(lines, line); ++i) {
    if (line.starts_with("E:")) event_line = i + 20;
  }
  ASSERT_GT(event_line, 20);
  write_file(dir / "bad.evemu", with_line(good, event_line, "E: 1.008000 0002 0000 zz"));
  write_file(dir / "old.evemu", "old output\n");
  write_file(dir / "old.csv", "old trace\n");
  const auto before = listing(dir);
  {
    SCOPED_TRACE("new output files are not created");
    const ToolResult r = run_tool(
        "replay --trace " + quote(dir / "new.csv") + " " + quote(dir / "bad.evemu") + " " + quote(dir / "new.evemu"),
        dir);
    expect_clean_failure(r, {"bad.evemu:" + std::to_string(event_line) + ":"});
    EXPECT_EQ(listing(dir), before);
  }
  {
    SCOPED_TRACE("old output files are kept as they were");
    const ToolResult r = run_tool(
        "replay --trace " + quote(dir / "old.csv") + " " + quote(dir / "bad.evemu") + " " + quote(dir / "old.evemu"),
        dir);
    expect_clean_failure(r, {"bad.evemu:" + std::to_string(event_line) + ":"});
    EXPECT_EQ(listing(dir), before);
    EXPECT_EQ(read_text(dir / "old.evemu"), "old output\n");
    EXPECT_EQ(read_text(dir / "old.csv"), "old trace\n");
  }
  {
    SCOPED_TRACE("on stdin, to stdout: nothing on stdout");
    const ToolResult r = run_tool("replay - - < " + quote(dir / "bad.evemu"), dir);
    expect_clean_failure(r, {"<stdin>:" + std::to_string(event_line) + ":"});
    EXPECT_TRUE(r.out.empty());
  }
  {
    SCOPED_TRACE("libinput record: the YAML line");
    std::ifstream yml(kDataDir / "libinput_mouse.yml", std::ios::binary);
    std::ostringstream text;
    text << yml.rdbuf();
    std::string bad = text.str();
    const std::string event = "    - [  0,      0,   2,   0,       1]";
    const std::size_t at = bad.find(event);
    ASSERT_NE(at, std::string::npos);
    bad.replace(at, event.size(), "    - [  0,      0,   2,   0,       x]");
    const int yaml_line = 1 + static_cast<int>(std::count(bad.begin(), bad.begin() + static_cast<long>(at), '\n'));
    write_file(dir / "bad.yml", bad);
    const ToolResult r = run_tool("replay " + quote(dir / "bad.yml") + " " + quote(dir / "new.evemu"), dir);
    expect_clean_failure(r, {"bad.yml:" + std::to_string(yaml_line) + ": event value must be an integer"});
    EXPECT_FALSE(fs::exists(dir / "new.evemu"));
  }
  {
    SCOPED_TRACE("libinput record, no line at fault: FILE: as evemu says it, not FILE:0:");
    write_file(dir / "empty.yml", "# libinput record\n---\n");
    const ToolResult r = run_tool("replay " + quote(dir / "empty.yml") + " " + quote(dir / "new.evemu"), dir);
    expect_clean_failure(r, {"empty.yml: empty input"});
    EXPECT_FALSE(contains(r.err, "empty.yml:0:")) << r.err;
    write_file(dir / "empty.evemu", "");
    const ToolResult e = run_tool("replay " + quote(dir / "empty.evemu") + " " + quote(dir / "new.evemu"), dir);
    expect_clean_failure(e, {"empty.evemu: empty recording"});
    EXPECT_FALSE(fs::exists(dir / "new.evemu"));
  }
  {
    SCOPED_TRACE("a missing input: the reason, as the scene file's errors give it");
    const ToolResult r = run_tool("replay " + quote(dir / "none.evemu") + " " + quote(dir / "new.evemu"), dir);
    expect_clean_failure(r, {"none.evemu: cannot open: No such file or directory"});
    EXPECT_FALSE(fs::exists(dir / "new.evemu"));
  }
  {
    SCOPED_TRACE("a folder as the input: said, not a read error");
    fs::create_directory(dir / "folder.evemu");
    const ToolResult r = run_tool("replay " + quote(dir / "folder.evemu") + " " + quote(dir / "new.evemu"), dir);
    expect_clean_failure(r, {"folder.evemu: is a folder, not a recording"});
    EXPECT_FALSE(contains(r.err, "read error")) << r.err;
    EXPECT_FALSE(fs::exists(dir / "new.evemu"));
  }
}

TEST(ReplayTool, WritesIntoAFifo) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  ASSERT_EQ(
      run_tool("replay --trace " + quote(dir / "t.csv") + " " + quote(in) + " " + quote(dir / "out.evemu"), dir).rc, 0);
  make_fifo(dir / "out.fifo");
  make_fifo(dir / "trace.fifo");
  {
    SCOPED_TRACE("the output into a FIFO, the trace into a file");
    FifoReader reader(dir / "out.fifo");
    const ToolResult r =
        run_tool("replay --trace " + quote(dir / "t2.csv") + " " + quote(in) + " " + quote(dir / "out.fifo"), dir);
    EXPECT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(reader.finish(), read_text(dir / "out.evemu"));
    EXPECT_EQ(read_text(dir / "t2.csv"), read_text(dir / "t.csv"));
  }
  {
    SCOPED_TRACE("the trace into a FIFO, the output into a file");
    FifoReader reader(dir / "trace.fifo");
    const ToolResult r = run_tool(
        "replay --trace " + quote(dir / "trace.fifo") + " " + quote(in) + " " + quote(dir / "out2.evemu"), dir);
    EXPECT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(reader.finish(), read_text(dir / "t.csv"));
    EXPECT_EQ(read_text(dir / "out2.evemu"), read_text(dir / "out.evemu"));
  }
  {
    SCOPED_TRACE("a trace that cannot be written: nothing goes into the output FIFO");
    FifoReader reader(dir / "out.fifo");
    const ToolResult r = run_tool(
        "replay --trace " + quote(dir / "no" / "t.csv") + " " + quote(in) + " " + quote(dir / "out.fifo"), dir);
    expect_clean_failure(r, {"t.csv"});
    EXPECT_EQ(reader.finish(), "");
  }
  // Still FIFOs, not replaced by files.
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(dir / "out.fifo")));
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(dir / "trace.fifo")));
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "out.evemu", "out2.evemu", "t.csv", "t2.csv", "out.fifo",
                                                 "trace.fifo"}));
}

TEST(ReplayTool, WritesThroughASymbolicLink) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  ASSERT_EQ(run_tool("replay " + quote(in) + " " + quote(dir / "out.evemu"), dir).rc, 0);
  const std::string expected = read_text(dir / "out.evemu");
  fs::create_directory(dir / "results");
  write_file(dir / "results" / "run.evemu", "old\n");
  fs::create_symlink("results/run.evemu", dir / "link.evemu");
  {
    SCOPED_TRACE("a link to a regular file: the link stays, the file it names gets the output");
    const ToolResult r = run_tool("replay " + quote(in) + " " + quote(dir / "link.evemu"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(fs::is_symlink(dir / "link.evemu"));
    EXPECT_EQ(fs::read_symlink(dir / "link.evemu"), "results/run.evemu");
    EXPECT_EQ(read_text(dir / "results" / "run.evemu"), expected);
  }
  {
    SCOPED_TRACE("a link to a file not there yet: created");
    fs::create_symlink("results/new.evemu", dir / "dangling.evemu");
    const ToolResult r = run_tool("replay " + quote(in) + " " + quote(dir / "dangling.evemu"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(fs::is_symlink(dir / "dangling.evemu"));
    EXPECT_EQ(read_text(dir / "results" / "new.evemu"), expected);
  }
  {
    SCOPED_TRACE("a link to a FIFO");
    make_fifo(dir / "results" / "pipe");
    fs::create_symlink("results/pipe", dir / "pipe.evemu");
    FifoReader reader(dir / "results" / "pipe");
    const ToolResult r = run_tool("replay " + quote(in) + " " + quote(dir / "pipe.evemu"), dir);
    EXPECT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(reader.finish(), expected);
    EXPECT_TRUE(fs::is_symlink(dir / "pipe.evemu"));
    EXPECT_TRUE(fs::is_fifo(dir / "results" / "pipe"));
  }
  {
    SCOPED_TRACE("a link to a directory: an error, the link untouched");
    fs::create_directory_symlink("results", dir / "dir.evemu");
    const ToolResult r = run_tool("replay " + quote(in) + " " + quote(dir / "dir.evemu"), dir);
    expect_clean_failure(r, {"dir.evemu"});
    EXPECT_TRUE(fs::is_symlink(dir / "dir.evemu"));
  }
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "out.evemu", "results", "link.evemu", "dangling.evemu",
                                                 "pipe.evemu", "dir.evemu"}));
  std::set<std::string> results;
  for (const auto& entry : fs::directory_iterator(dir / "results")) results.insert(entry.path().filename().string());
  EXPECT_EQ(results, (std::set<std::string>{"run.evemu", "new.evemu", "pipe"}));
}

// /dev/stdout is a link to /proc/self/fd/1; a link of our own to it (never /dev/stdout itself: a broken
// tool could replace that) with the shell appending to a file: the output is appended, the file kept.
TEST(ReplayTool, LinkToStandardOutputKeepsTheShellsAppend) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  ASSERT_EQ(run_tool("replay " + quote(in) + " " + quote(dir / "out.evemu"), dir).rc, 0);
  fs::create_symlink("/proc/self/fd/1", dir / "stdout.evemu");
  write_file(dir / "log", "earlier lines\n");
  const std::string command = quote(std::string(PH_TOOL_PATH)) + " replay " + quote(in) + " " +
                              quote(dir / "stdout.evemu") + " >>" + quote(dir / "log") + " 2>" +
                              quote(dir / "stderr.txt");
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(dir / "stderr.txt");
  EXPECT_EQ(read_text(dir / "log"), "earlier lines\n" + read_text(dir / "out.evemu"));
  EXPECT_TRUE(fs::is_symlink(dir / "stdout.evemu"));
}

TEST(ReplayTool, AFailedTraceLeavesTheOutputUncommitted) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  write_file(dir / "old.evemu", "old output\n");
  fs::create_directory(dir / "a-directory");
  const auto before = listing(dir);
  {
    SCOPED_TRACE("the trace's directory does not exist");
    for (const char* out : {"old.evemu", "new.evemu"}) {
      const ToolResult r = run_tool(
          "replay --trace " + quote(dir / "missing" / "t.csv") + " " + quote(in) + " " + quote(dir / out), dir);
      expect_clean_failure(r, {"missing/t.csv"});
    }
  }
  {
    SCOPED_TRACE("the trace is a directory: it fails when written, after the output's temporary file");
    for (const char* out : {"old.evemu", "new.evemu"}) {
      const ToolResult r =
          run_tool("replay --trace " + quote(dir / "a-directory") + " " + quote(in) + " " + quote(dir / out), dir);
      expect_clean_failure(r, {"a-directory"});
    }
  }
  {
    SCOPED_TRACE("the output is a directory: the trace is not committed either");
    const ToolResult r =
        run_tool("replay --trace " + quote(dir / "t.csv") + " " + quote(in) + " " + quote(dir / "a-directory"), dir);
    expect_clean_failure(r, {"a-directory"});
  }
  EXPECT_EQ(read_text(dir / "old.evemu"), "old output\n");
  EXPECT_EQ(listing(dir), before);
  EXPECT_TRUE(fs::is_empty(dir / "a-directory"));
}

// A reader of standard output that goes away early (`| head`) ends the replay quietly, as SIGPIPE would, but only once
// its temporary files are removed: SIGPIPE used to end it in the middle, leaving the trace's temporary file behind.
TEST(ReplayTool, AReaderThatGoesAwayLeavesNoTemporaryFiles) {
  ScratchDir dir;
  stroke_file(dir, "in.evemu", 300, 3, 1);
  int ends[2];
  ASSERT_EQ(::pipe(ends), 0);
  ::close(ends[0]);  // the reader has gone before anything is written
  const std::string err = (dir / "err.txt").string();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::dup2(ends[1], 1);
    const int to_err = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(to_err, 2);
    if (::chdir(dir.path().c_str()) != 0) ::_exit(126);
    ::signal(SIGPIPE, SIG_DFL);  // as a shell leaves it, whatever the test runner does with it
    ::execl(PH_TOOL_PATH, PH_TOOL_PATH, "replay", "--trace", "t.csv", "in.evemu", "-", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(ends[1]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGPIPE) << "status " << status << ": " << read_text(err);
  EXPECT_EQ(read_text(err), "");
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "err.txt"}));
}

// "-" and /dev/stdout are one output: the trace and the replay used to be written into it one after the other.
TEST(ReplayTool, StandardOutputByAnyNameIsOneOutput) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  for (const std::string& args :
       {"--trace /dev/stdout " + quote(in) + " -", "--trace - " + quote(in) + " /dev/stdout"}) {
    const ToolResult r = run_tool("replay " + args, dir);
    EXPECT_EQ(r.rc, 1) << args;
    EXPECT_TRUE(contains(r.err, "is OUTPUT too")) << args << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << args;
  }
}

TEST(ReplayTool, ReplacesARegularFileKeepingItsMode) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  write_file(dir / "out.evemu", "old\n");
  fs::permissions(dir / "out.evemu", fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  const ToolResult r = run_tool("replay " + quote(in) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(read_text(dir / "out.evemu"), evemu_text(replay(testing::scripted_stroke(300, 3, 1), default_scene(), {})));
  EXPECT_EQ(fs::status(dir / "out.evemu").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "out.evemu"}));
}

// A replay written over its own recording (or a trace over either) replaced the user's recording without a word.
TEST(ReplayTool, RefusesToWriteOverItsInputOrOneOutputOverTheOther) {
  ScratchDir dir;
  const fs::path in = stroke_file(dir);
  const std::string recorded = read_text(in);
  fs::create_symlink(in, dir / "link.evemu");
  for (const std::string& args :
       {quote(in) + " " + quote(in), quote(in) + " " + quote(dir / "." / "in.evemu"),
        quote(in) + " " + quote(dir / "link.evemu"), "--trace " + quote(in) + " " + quote(in) + " out.evemu"}) {
    const ToolResult r = run_tool_in_dir("replay " + args, dir);
    EXPECT_EQ(r.rc, 1) << args;
    EXPECT_NE(r.err.find("is the recording INPUT"), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(read_text(in), recorded) << args;
  }
  // Run from the scratch folder: a relative out.evemu written by mistake would be seen in its listing.
  const ToolResult both = run_tool_in_dir("replay --trace out.evemu " + quote(in) + " out.evemu", dir);
  EXPECT_EQ(both.rc, 1);
  EXPECT_NE(both.err.find("--trace out.evemu is OUTPUT too"), std::string::npos) << both.err;
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "link.evemu"}));
  // The recording read from standard input (`< FILE`) is that file too.
  for (const std::string& args : {"- " + quote(in), "--trace " + quote(dir / "link.evemu") + " - out.evemu"}) {
    const ToolResult r = run_tool_in_dir("replay " + args + " < " + quote(in), dir);
    EXPECT_EQ(r.rc, 1) << args;
    EXPECT_NE(r.err.find("is the file standard input reads"), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(read_text(in), recorded) << args;
  }
  EXPECT_EQ(listing(dir), (std::set<std::string>{"in.evemu", "link.evemu"}));
}

// A recording with nothing to rescale is replayed as it is, with a warning: it is most likely not the one meant.
TEST(ReplayTool, ARecordingWithoutMotionIsWarnedOf) {
  ScratchDir dir;
  Recording keys;
  keys.device = testing::test_mouse();
  const fs::path empty = dir / "empty.evemu";
  write_file(empty, evemu_text(keys));
  const ToolResult none = run_tool("replay " + quote(empty) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(none.rc, 0) << none.err;
  EXPECT_TRUE(contains(none.err, "warning: " + empty.string() + " holds no events: nothing was rescaled")) << none.err;
  testing::add_frame(keys, 1000, {{0, ev::kKey, 0x110, 1}});
  testing::add_frame(keys, 9000, {{0, ev::kKey, 0x110, 0}});
  const fs::path clicks = dir / "clicks.evemu";
  write_file(clicks, evemu_text(keys));
  const ToolResult still = run_tool("replay - " + quote(dir / "out.evemu") + " < " + quote(clicks), dir);
  ASSERT_EQ(still.rc, 0) << still.err;
  EXPECT_TRUE(contains(still.err, "warning: <stdin> holds no REL_X/REL_Y motion: nothing was rescaled")) << still.err;
  const ToolResult moved = run_tool("replay " + quote(stroke_file(dir)) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(moved.rc, 0) << moved.err;
  EXPECT_FALSE(contains(moved.err, "warning")) << moved.err;
  // Motion whose frames never end (no SYN_REPORT) is never applied: said, not passed through in silence.
  Recording unframed;
  unframed.device = testing::test_mouse();
  for (std::int64_t t = 0; t < 5; ++t) unframed.events.push_back({t * 1000, ev::kRel, ev::kRelX, 7});
  const fs::path motion = dir / "unframed.evemu";
  write_file(motion, evemu_text(unframed));
  const ToolResult unended = run_tool("replay " + quote(motion) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(unended.rc, 0) << unended.err;
  EXPECT_TRUE(contains(unended.err, "warning: " + motion.string() +
                                        " holds no SYN_REPORT, which ends a frame: no frame ended, nothing was "
                                        "rescaled"))
      << unended.err;
}

// A long recording takes seconds: on a terminal the replay says what it is doing, on one line it erases; into a
// file or a pipe it says nothing of it (a log would fill with progress).
TEST(ReplayTool, ProgressIsShownOnATerminalOnly) {
  if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "no script(1) for a terminal";
  ScratchDir dir;
  const fs::path in = testing::recorded_mice().front();
  ASSERT_EQ(testing::missing_file({in}), "");
  const std::string replay = quote(std::string(PH_TOOL_PATH)) + " replay " + quote(in) + " " + quote(dir / "out.evemu");
  const ToolResult on_terminal = run_program("script", "-qec " + quote(replay) + " /dev/null", dir);
  ASSERT_EQ(on_terminal.rc, 0) << on_terminal.out << on_terminal.err;
  EXPECT_TRUE(contains(on_terminal.out, "\rreplay: reading ")) << on_terminal.out;
  EXPECT_TRUE(contains(on_terminal.out, " % of ")) << on_terminal.out;
  EXPECT_TRUE(contains(on_terminal.out, "\rreplay: writing ")) << on_terminal.out;
  EXPECT_TRUE(contains(on_terminal.out, "replayed ")) << on_terminal.out;
  // The replay to standard output, the same terminal: the progress line is gone before the recording's text.
  const ToolResult to_terminal = run_program(
      "script", "-qec " + quote(quote(std::string(PH_TOOL_PATH)) + " replay " + quote(in) + " -") + " /dev/null", dir);
  ASSERT_EQ(to_terminal.rc, 0) << to_terminal.out;
  EXPECT_FALSE(contains(to_terminal.out, "replay: writing")) << to_terminal.out.substr(0, 300);
  const std::size_t text = to_terminal.out.find("# EVEMU");
  ASSERT_NE(text, std::string::npos);
  EXPECT_EQ(to_terminal.out.find("replay: ", text), std::string::npos);
  const ToolResult in_a_file = run_tool("replay " + quote(in) + " " + quote(dir / "out.evemu"), dir);
  ASSERT_EQ(in_a_file.rc, 0) << in_a_file.err;
  EXPECT_FALSE(contains(in_a_file.err, "replay: ")) << in_a_file.err;
}

TEST(ReplayTool, IsDeterministicAcrossProcesses) {
  ScratchDir dir;
  const fs::path in = testing::recorded_mice().front();
  ASSERT_EQ(testing::missing_file({in}), "");
  for (const char* run : {"a", "b"}) {
    const ToolResult r = run_tool("replay --trace " + quote(dir / (std::string(run) + ".csv")) + " " + quote(in) + " " +
                                      quote(dir / (std::string(run) + ".evemu")),
                                  dir);
    ASSERT_EQ(r.rc, 0) << r.err;
  }
  const std::string a = read_text(dir / "a.evemu");
  EXPECT_GT(a.size(), 10'000u);
  EXPECT_EQ(a, read_text(dir / "b.evemu"));
  EXPECT_EQ(read_text(dir / "a.csv"), read_text(dir / "b.csv"));
  EXPECT_NE(a, read_text(in));  // over the default scene, not a copy
}

TEST(ReplayTool, DeviceOfALibinputRecordFile) {
  ScratchDir dir;
  const fs::path two = kDataDir / "libinput_two_devices.yml";
  auto device = [&](std::size_t index) {
    std::ifstream yml(two, std::ios::binary);
    return read_libinput_record(yml, "two", index);
  };
  const std::string mouse = evemu_text(replay(device(1), default_scene(), PipelineConfig{}));
  {
    SCOPED_TRACE("default: device 0 is a keyboard, so the mouse, with a note saying so");
    const ToolResult r = run_tool("replay " + quote(two) + " -", dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(r.out, mouse);
    for (std::string_view part :
         {"device 0 has no REL_X/REL_Y", "device 1 of 2", "Razer Razer DeathAdder V2", "--device"}) {
      EXPECT_TRUE(contains(r.err, part)) << "expected '" << part << "' in: " << r.err;
    }
  }
  {
    SCOPED_TRACE("--device 1: the mouse, no note");
    const ToolResult r = run_tool("replay --device 1 " + quote(two) + " -", dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(r.out, mouse);
    EXPECT_TRUE(r.err.empty()) << r.err;
  }
  {
    SCOPED_TRACE("--device 0: the keyboard, passed through, with a note");
    const ToolResult r = run_tool("replay --device 0 " + quote(two) + " -", dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    const Recording keyboard = device(0);
    EXPECT_EQ(evemu_of(r.out).events, keyboard.events);
    EXPECT_EQ(evemu_of(r.out).device.name, "AT Translated Set 2 keyboard");
    EXPECT_TRUE(contains(r.err, "has no REL_X/REL_Y")) << r.err;
  }
  {
    SCOPED_TRACE("a device the file does not have");
    const ToolResult r = run_tool("replay --device 2 " + quote(two) + " " + quote(dir / "x.evemu"), dir);
    expect_clean_failure(r, {"libinput_two_devices.yml:", "no device 2: the file has 2 device(s)"});
    EXPECT_FALSE(fs::exists(dir / "x.evemu"));
  }
  {
    SCOPED_TRACE("a negative or overlong --device is refused, not read as a huge number");
    for (const std::string device : {"-1", "-2", "99999999999999999999"}) {
      expect_clean_failure(run_tool("replay --device " + device + " " + quote(two) + " " + quote(dir / "x.evemu"), dir),
                           {"--device: must be a whole number from 0 to 65535, not " + device});
    }
    expect_clean_failure(run_tool("replay --trace '' " + quote(two) + " " + quote(dir / "x.evemu"), dir),
                         {"--trace: is empty: give a path"});
    EXPECT_FALSE(fs::exists(dir / "x.evemu"));
  }
  {
    SCOPED_TRACE("evemu holds one device");
    const fs::path in = stroke_file(dir);
    const ToolResult r = run_tool("replay --device 1 " + quote(in) + " " + quote(dir / "x.evemu"), dir);
    expect_clean_failure(r, {"in.evemu: no device 1"});
    EXPECT_FALSE(fs::exists(dir / "x.evemu"));
    EXPECT_EQ(run_tool("replay --device 0 " + quote(in) + " " + quote(dir / "y.evemu"), dir).rc, 0);
  }
  {
    SCOPED_TRACE("a one-device file whose device is the mouse: no note");
    const ToolResult r = run_tool("replay " + quote(kDataDir / "libinput_mouse.yml") + " -", dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
  }
}

}  // namespace
}  // namespace ph
