// Run inside the project's VM (tests/vm/run-in-vm), as root: the real pseudohapticd on the embedded default
// scene, fed by a virtual mouse that replays a recording, and what came out of the daemon's virtual device:
// how many frames the texture changed, the cursor's path, and the C/D ratio met over each target.
// scripts/install runs it where this machine cannot run the service (scripts/vm-demo).
//
//   daemon_demo DAEMON RECORDING
//
// Each recorded frame is written into the virtual mouse and the frame the daemon emits for it is read
// before the next is sent. The same frames go through ph::Pipeline here with the daemon's configuration
// (the embedded default scene, the desktop resolved as the daemon resolves it), which says what the
// daemon should emit and the C/D ratio of each frame; a frame that came out otherwise is counted and
// printed. With absolute output and the adaptive acceleration (the defaults) the check is the
// end-to-end tests' (tests/vm/absolute_follower.hpp): within a pixel, for the kernel's frame times. Exit status 1 when
// the daemon did not start, a frame differed, or the texture changed none.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/engine/pipeline.hpp"
#include "daemon/configuration.hpp"
#include "recording/recording_file.hpp"
#include "tests/vm/absolute_follower.hpp"
#include "tests/vm/e2e_support.hpp"

namespace {

using namespace ph::e2e;
using ph::Frame;
namespace ev = ph::ev;

std::vector<Frame> split_frames(const std::vector<ph::InputEvent>& events) {
  std::vector<Frame> frames;
  Frame pending;
  for (const ph::InputEvent& e : events) {
    pending.events.push_back(e);
    if (e.type == ev::kSyn && e.code == ev::kSynReport) frames.push_back(std::exchange(pending, {}));
  }
  return frames;
}

// Per region of the scene (and "outside"): frames that started there and the C/D range met.
struct RegionStats {
  int frames = 0, changed = 0;
  double cd_min = INFINITY, cd_max = -INFINITY;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: daemon_demo DAEMON RECORDING\n");
    return 2;
  }
  const std::string daemon_path = argv[1], recording_path = argv[2];
  try {
    const ph::Recording recording = ph::read_recording_file(recording_path);
    const std::vector<Frame> frames = split_frames(recording.events);
    ph::ConfigChoice choice;
    choice.default_scene = true;
    const ph::Configuration config = ph::load_configuration(choice);
    ph::Pipeline model(config.scene, config.pipeline);
    // What a scene without texture emits: one pipeline along (in relative mode it carries no fraction
    // outside a texture; in absolute mode it is put at the model's cursor before each frame).
    const auto no_texture = std::make_shared<const ph::Scene>();
    ph::Pipeline flat(no_texture, config.pipeline);
    const bool absolute = config.pipeline.mode == ph::OutputMode::absolute;

    const std::filesystem::path scratch = "/run/tmp/ph-demo";
    std::filesystem::create_directories(scratch);
    const UeventMonitor uevents;
    TestMouse mouse("ph-demo mouse");
    NotifySocket notify((scratch / "notify.sock").string());
    const std::string control_path = (scratch / "control").string();
    ChildProcess daemon({daemon_path, "--default-scene", "--control", control_path},
                        {"NOTIFY_SOCKET=" + notify.path(), "PATH=/usr/sbin:/usr/bin:/sbin:/bin", "LANG=C.UTF-8"},
                        (scratch / "daemon.log").string());
    const auto started = Clock::now();
    if (!notify.expect("READY=1", 90s)) throw Fatal("the daemon sent no READY=1 within 90 s:\n" + daemon.log());
    const double ready_s = std::chrono::duration<double>(Clock::now() - started).count();
    const std::string virtual_name = "pseudohaptic " + mouse.name();
    const std::string node = wait_for_device(virtual_name, 20s, uevents);
    if (node.empty()) throw Fatal("no virtual device '" + virtual_name + "':\n" + daemon.log());
    EventReader out(node);
    // The daemon grabs the mouse just after making the virtual device: wheel notches until one comes
    // through, so that no recorded frame goes to the mouse's own node (frames without motion leave the
    // cursor alone).
    bool through = false;
    for (int i = 0; i < 100 && !through; ++i) {
      mouse.send(make_frame({rel(ev::kRelWheel, 1)}));
      through = out.next_frame(200ms).has_value();
    }
    if (!through) throw Fatal("nothing came out of " + node);
    while (out.next_frame(300ms)) {
    }

    std::map<std::string, RegionStats> stats;
    std::vector<std::string> order;
    for (const ph::Region& r : config.scene->regions()) order.push_back(r.name);
    order.emplace_back("outside the targets");
    // Absolute output: the follower checks each frame against the model within the kernel's timing and
    // moves the model to the daemon's own cursor where they part (tests/vm/absolute_follower.hpp).
    ph::control::Client control(control_path);
    AbsoluteFollower follower(model, control);
    Check check;
    ph::Vec2 cursor = model.cursor().position;  // from what came out
    std::vector<std::pair<ph::TimeUs, ph::Vec2>> path{{0, cursor}};
    int sent = 0, emitted = 0, changed = 0, mismatched = 0;
    std::string first_mismatch;
    const auto replay_start = Clock::now();
    for (const Frame& in : frames) {
      const ph::Vec2 at = model.cursor().position;
      const std::optional<std::size_t> index = config.scene->owner(
          {static_cast<std::int32_t>(std::floor(at.x)), static_cast<std::int32_t>(std::floor(at.y))});
      ph::FrameReport report;
      // The same motion with and without texture, from the same place and acceleration history: did the
      // texture change the frame?
      const ph::TimeUs now = monotonic_us();
      ph::Pipeline textured = model;
      if (absolute) flat.move_cursor_to(at);
      const bool texture =
          !same_events(untimed(textured.process(stamped(in, now))), untimed(flat.process(stamped(in, now))));
      ++sent;
      std::optional<Frame> got;
      bool agrees = true;
      if (absolute) {
        const std::size_t failures_before = check.failed();
        got = follower.through(check, mouse, out, in, fmt::format("frame {}", sent), nullptr, &report);
        agrees = check.failed() == failures_before;
        if (!got) continue;
      } else {
        const Frame expected = untimed(model.process(stamped(in, now), &report));
        mouse.send(in);
        if (!delivers_something(expected)) continue;
        got = out.next_frame(kFrameTimeout);
        if (!got) throw Fatal(fmt::format("frame {}: nothing came out within 5 s", sent));
        agrees = same_events(*got, expected);
        if (!agrees && mismatched == 0) {
          first_mismatch = fmt::format("frame {}: sent [{}], the offline pipeline says [{}], the daemon emitted [{}]",
                                       sent, describe(in), describe(expected), describe(*got));
        }
      }
      ++emitted;
      mismatched += agrees ? 0 : 1;
      for (const ph::InputEvent& e : got->events) {
        if (e.type == ev::kRel && e.code == ev::kRelX) cursor.x += e.value;
        if (e.type == ev::kRel && e.code == ev::kRelY) cursor.y += e.value;
        if (e.type == ev::kAbs && e.code == ev::kAbsX) cursor.x = (e.value - 1) / ph::kAbsUnitsPerPixel;
        if (e.type == ev::kAbs && e.code == ev::kAbsY) cursor.y = (e.value - 1) / ph::kAbsUnitsPerPixel;
      }
      // A desktop without pointer acceleration moves its cursor so, and stops it at its edges.
      const ph::Rect& desktop = config.pipeline.desktop;
      cursor.x = std::clamp(cursor.x, double(desktop.x), double(desktop.x + desktop.w - 1));
      cursor.y = std::clamp(cursor.y, double(desktop.y), double(desktop.y + desktop.h - 1));
      changed += texture ? 1 : 0;
      RegionStats& s = stats[index ? config.scene->regions()[*index].name : order.back()];
      ++s.frames;
      s.changed += texture ? 1 : 0;
      s.cd_min = std::min(s.cd_min, report.cd_min);
      s.cd_max = std::max(s.cd_max, report.cd_max);
      const ph::TimeUs t = in.events.empty() ? 0 : in.events.back().time - frames.front().events.front().time;
      if (t - path.back().first >= 500000) path.emplace_back(t, cursor);
    }
    const double replay_s = std::chrono::duration<double>(Clock::now() - replay_start).count();
    path.emplace_back(-1, cursor);

    std::printf("pseudohapticd (%s, started in %.1f s) took the virtual mouse '%s' and emitted through %s.\n",
                daemon_path.c_str(), ready_s, mouse.name().c_str(), node.c_str());
    std::printf("Replayed %s: %d frames in, %d out (%.1f s under emulation); the texture changed %d of them.\n",
                recording_path.c_str(), sent, emitted, replay_s, changed);
    std::printf("Output %s; every frame %s the offline pipeline (ph::Pipeline over the same scene%s).\n%s",
                absolute ? "absolute (ABS_X/ABS_Y)" : "relative (REL_X/REL_Y)",
                mismatched == 0 ? (absolute ? "within a pixel of" : "equal to") : "NOT as",
                absolute ? ", with the daemon's acceleration" : "",
                absolute ? ("  " + follower.summary() + ".\n").c_str() : "");
    std::string points;
    for (const auto& [t, p] : path) {
      points += fmt::format("{}({:.0f}, {:.0f})", points.empty() ? "" : " -> ", p.x, p.y);
    }
    std::printf("Cursor path, every 0.5 s of the recording: %s\n", points.c_str());
    std::printf("%-26s %7s %8s %16s\n", "region", "frames", "changed", "C/D met");
    for (const std::string& name : order) {
      const auto it = stats.find(name);
      if (it == stats.end()) {
        std::printf("%-26s %7d %8d %16s\n", name.c_str(), 0, 0, "-");
        continue;
      }
      const RegionStats& s = it->second;
      std::printf("%-26s %7d %8d %7.2f .. %5.2f\n", name.c_str(), s.frames, s.changed, s.cd_min, s.cd_max);
    }
    if (mismatched > 0) {
      std::printf("%d frames differed from the offline pipeline; the first:\n    %s\n", mismatched,
                  absolute ? check.failures().c_str() : first_mismatch.c_str());
      return 1;
    }
    if (changed == 0) {
      std::printf("the texture changed no frame: the recording missed the scene's regions\n");
      return 1;
    }
    daemon.signal(SIGTERM);
    daemon.wait_exit(10s);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "daemon_demo: %s\n", e.what());
    return 1;
  }
}
