// Run inside the VM under tests/vm/with-xorg (a real Xorg whose libinput driver reads the input devices
// named "pseudohaptic ..." and "ph-x11 untaken"), as root: is the cursor the daemon models the cursor X
// shows? Creates uinput test mice, starts the daemon (argv[1]) on one, moves it like a hand and, after
// every frame, compares where X put its pointer (XQueryPointer) with the cursor model: that of
// ph::Pipeline fed the same frames offline (the daemon's own: every frame the daemon emits is checked
// against it too, and its `cursor` over the control socket at the end), or, where something else moves
// the cursor, the daemon's `cursor` over the control socket.
//
//   x11_cursor_e2e DAEMON [--scene DIR] [--session HELPER] [--frames N] [--relative-frames N]
//                  [--cases abcedf] [-v [--trace-from FRAME]]
//   x11_cursor_e2e --write-scene DIR     (on the host, before: writes the scene's maps into DIR)
//
// Cases, one daemon each (d and g share one), all on one X server; the scene is the embedded default
// scene's three targets, loaded from files, on a 1920 x 1080 desktop (f: no region):
//   a  absolute output: X's pixel holds the model at every frame (within 0.5 px of the pixel's centre);
//      then an untaken pointer moves X's pointer on without a jump;
//   b  relative output, X's flat acceleration profile: within 1 px;
//   c  relative output, X's default adaptive profile: the drift, measured and reported only;
//   e  pseudohaptic-session (HELPER) against a stand-in control socket;
//   d  with the helper connected: an application warp, then motion: the model follows within two frames;
//   g  ... a pointer the daemon does not take moves the cursor: the model follows;
//   j  with the helper: two outputs of different sizes; where X stops the pointer at an output's edge, the model
//      stops too (X's pixel holds it at every frame);
//   f  our adaptive profile against X's libinput adaptive profile (the daemon's relative output, its own
//      acceleration flat) on the same out-and-back strokes, given the times libinput saw (those of the daemon's
//      events): the two cursors within 2 % of the path's length; the daemon's absolute output live beside it,
//      reported only (its times are the mouse's, which the daemon's latency under TCG parts from libinput's).
// The distance at a check is from the model to the centre of the pixel X reports, per axis:
// |model - (pixel + 0.5)|. One PASS, FAIL or INFO line per case; exit status 1 when any failed.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/pipeline.hpp"
#include "core/engine/targets.hpp"
#include "tests/vm/control_stub.hpp"
#include "tests/vm/e2e_support.hpp"
#include "tests/vm/hand_motion.hpp"
#include "tests/vm/x11_support.hpp"

namespace {

using namespace ph::e2e;
using ph::Frame;
using ph::Vec2;
namespace ev = ph::ev;

constexpr const char* kMouseName = "ph-x11 mouse";
constexpr const char* kVirtualName = "pseudohaptic ph-x11 mouse";
constexpr ph::Rect kDesktop{0, 0, 1920, 1080};
constexpr auto kFrameTimeout = 5s;  // a frame through the daemon, or through X (TCG is slow)

struct Options {
  std::string daemon;
  int frames = 2000;          // motion frames of the absolute case
  int relative_frames = 600;  // motion frames of each relative case
  bool verbose = false;
  std::string cases = "abcedjf";  // which run, by letter (e: the helper alone; d: d, g and h; j; f)
  long trace_from = -1;           // -v: trace 12 frames from this one
  int acceleration_strokes = 8;   // out-and-back strokes of case f
  std::filesystem::path scratch;
  std::filesystem::path scene_dir;  // the targets' maps; default: in scratch
  std::string session;              // pseudohaptic-session, for its case; none: not run
};

void trace(const Options& options, const std::string& what) {
  static const auto start = Clock::now();
  if (!options.verbose) return;
  std::fprintf(stderr, "[%9.3f] %s\n", std::chrono::duration<double>(Clock::now() - start).count(), what.c_str());
}

// ---- the scene: the default scene's three targets, from files ------------------------------------------------

struct Target {
  const char* name;
  int x, y;
};
constexpr Target kTargets[] = {
    {"bump-gaussian-h1-r200", 135, 290}, {"hole-polynomial-h1-r200", 710, 290}, {"bump-linear-h1-r100", 1285, 290}};

std::vector<ph::TargetSpec> scene_targets() {
  std::vector<ph::TargetSpec> specs;
  for (const Target& t : kTargets) {
    for (const ph::TargetSpec& spec : ph::all_targets()) {
      if (spec.name() == t.name) specs.push_back(spec);
    }
  }
  if (specs.size() != std::size(kTargets)) throw Fatal("a target of the default scene is missing");
  return specs;
}

// The regions' scene text, naming the maps in `dir` by absolute path. Writes the maps there when they
// are missing (slow under TCG: scripts/vm-test writes them on the host first, with --write-scene).
std::string scene_regions(const std::filesystem::path& dir) {
  const std::vector<ph::TargetSpec> specs = scene_targets();
  if (!ph::target_files_present(dir, specs)) ph::write_target_files(dir, specs);
  const std::string prefix = std::filesystem::absolute(dir).string() + "/";
  std::string regions;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    std::string region = ph::target_scene_text(specs[i]);
    const std::string at_origin = "x = 0\ny = 0\n";
    const auto pos = region.find(at_origin);
    if (pos == std::string::npos) throw Fatal("unexpected target scene text:\n" + region);
    region.replace(pos, at_origin.size(), fmt::format("x = {}\ny = {}\n", kTargets[i].x, kTargets[i].y));
    for (const char* key : {"normal_map = \"", "depth_map = \""}) {
      const auto at = region.find(key);
      if (at == std::string::npos) throw Fatal("unexpected target scene text:\n" + region);
      region.insert(at + std::strlen(key), prefix);
    }
    regions += "\n" + region;
  }
  return regions;
}

// A config file `name`.toml: the test mouse only, the desktop spelled out, `mode`, the daemon's own
// acceleration `acceleration` at speed 0, and `regions` (scene text).
std::filesystem::path write_config(const std::filesystem::path& dir, const std::string& name, ph::OutputMode mode,
                                   const std::string& acceleration, const std::string& regions) {
  const std::filesystem::path path = dir / (name + ".toml");
  std::ofstream out(path, std::ios::trunc);
  out << "[daemon]\n"
      << "devices = [\"name:ph-x11 mouse\"]\n"
      << "output = \"" << (mode == ph::OutputMode::absolute ? "absolute" : "relative") << "\"\n"
      << "acceleration = \"" << acceleration << "\"\n"
      << "speed = 0.0\n"
      << "desktop = [0, 0, 1920, 1080]\n"
      << "pointer_speed = 1.0\n"
      << regions;
  if (!out) throw Fatal("cannot write " + path.string());
  return path;
}

// ---- figures -------------------------------------------------------------------------------------------------

// Distances from the model to the centre of the pixel X shows, over the checks of a case.
class Distances {
 public:
  void add(long frame, Vec2 model, XServer::Pointer pixel) {
    const double dx = std::abs(model.x - (pixel.x + 0.5)), dy = std::abs(model.y - (pixel.y + 0.5));
    const double axis = std::max(dx, dy), euclid = std::hypot(dx, dy);
    if (axis > max_axis_) {
      max_axis_ = axis;
      worst_ =
          fmt::format("frame {}: model ({:.3f}, {:.3f}), X pixel ({}, {})", frame, model.x, model.y, pixel.x, pixel.y);
    }
    max_euclid_ = std::max(max_euclid_, euclid);
    sum_sq_ += euclid * euclid;
    last_ = euclid;
    ++checks_;
    axes_.push_back(axis);
    texts_.push_back(
        fmt::format("frame {}: model ({:.3f}, {:.3f}), X pixel ({}, {})", frame, model.x, model.y, pixel.x, pixel.y));
  }
  // The first check whose per-axis distance exceeds `bound`, in words.
  std::string first_over(double bound) const {
    for (std::size_t i = 0; i < axes_.size(); ++i) {
      if (axes_[i] > bound) return texts_[i];
    }
    return "none";
  }
  // Checks whose per-axis distance exceeds `bound`.
  long over(double bound) const {
    return std::count_if(axes_.begin(), axes_.end(), [&](double a) { return a > bound; });
  }

  double max_axis() const { return max_axis_; }
  double max_euclid() const { return max_euclid_; }
  double rms() const { return checks_ > 0 ? std::sqrt(sum_sq_ / static_cast<double>(checks_)) : 0.0; }
  double last() const { return last_; }
  long checks() const { return checks_; }
  const std::string& worst() const { return worst_; }

 private:
  double max_axis_ = 0, max_euclid_ = 0, sum_sq_ = 0, last_ = 0;
  long checks_ = 0;
  std::vector<double> axes_;
  std::vector<std::string> texts_;
  std::string worst_;
};

// ---- one case ------------------------------------------------------------------------------------------------

struct CaseSpec {
  std::string label;
  ph::OutputMode mode;
  std::string x_profile;  // relative output: the profile X's libinput driver gets ("flat", "adaptive")
  int frames;
  std::optional<double> bound;  // per-axis distance every check must keep; none: measured only
  bool untaken_after = false;   // then an untaken pointer moves X's pointer
};

struct CaseResult {
  Distances distances;
  long motion_frames = 0, daemon_frames = 0, daemon_mismatches = 0, lost_syncs = 0;
  double model_path = 0, seconds = 0, late_ms = 0;
  long late_frames = 0;
  std::vector<std::string> problems;
  std::vector<std::string> notes;
};

// What the kernel passes on of a frame the daemon writes: an ABS value equal to the axis' last one, a
// REL value of 0 and an empty frame are dropped. `abs` holds the last ABS_X, ABS_Y.
Frame as_delivered(const Frame& frame, std::int32_t abs[2]) {
  Frame out;
  bool any = false;
  for (const ph::InputEvent& e : frame.events) {
    if (e.type == ev::kAbs && (e.code == ev::kAbsX || e.code == ev::kAbsY)) {
      std::int32_t& last = abs[e.code == ev::kAbsX ? 0 : 1];
      if (e.value == last) continue;
      last = e.value;
    }
    if (e.type == ev::kRel && e.value == 0) continue;
    if (e.type != ev::kSyn) any = true;
    out.events.push_back(e);
  }
  if (!any) out.events.clear();
  return out;
}

std::int32_t abs_value(int fd, std::uint16_t code) {
  input_absinfo info{};
  if (::ioctl(fd, EVIOCGABS(code), &info) < 0) return 0;
  return info.value;
}

// The daemon (on `config`, with a control socket in the scratch folder) as a child, once it has taken
// the test mouse and X has added its virtual device. stop() ends it as the service manager would.
class RunningDaemon {
 public:
  RunningDaemon(const Options& options, XServer& x, TestMouse& mouse, const UeventMonitor& uevents,
                const std::filesystem::path& config)
      : notify_((options.scratch / "notify.sock").string()),
        control_((options.scratch / "daemon.control").string()),
        daemon_(arguments(options, config, control_),
                {"NOTIFY_SOCKET=" + notify_.path(), "PATH=/usr/sbin:/usr/bin:/sbin:/bin", "LANG=C.UTF-8"},
                (options.scratch / "daemon.log").string()) {
    if (!notify_.expect("READY=1", 120s)) fatal("no READY=1 within 120 s");
    const std::string node = wait_for_device(kVirtualName, 10s, uevents);
    if (node.empty()) fatal("no virtual device '" + std::string(kVirtualName) + "'");
    out_.emplace(node);
    if (!wait_taken(mouse, *out_, 10s)) fatal("the daemon did not take the test mouse");
    const std::optional<int> device = x.wait_for_pointer(kVirtualName, 30s);
    if (!device) fatal("X did not add the virtual device within 30 s");
    device_ = *device;
  }

  [[noreturn]] void fatal(const std::string& what) { throw Fatal(what + "; the daemon's output:\n" + daemon_.log()); }
  EventReader& out() { return *out_; }
  int x_device() const { return device_; }                 // the virtual device's XInput id
  const std::string& control() const { return control_; }  // its control socket

  // SIGTERM: the daemon exits 0 and X lets go of its device. Adds what went wrong to `problems`.
  void stop(XServer& x, std::vector<std::string>& problems) {
    daemon_.signal(SIGTERM);
    const std::optional<int> status = daemon_.wait_exit(10s);
    if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
      problems.push_back("the daemon did not exit 0 on SIGTERM: " +
                         (status ? describe_wait_status(*status) : std::string("still running")));
    }
    if (!x.wait_pointer_gone(kVirtualName, 30s)) problems.push_back("X kept the virtual device");
  }

 private:
  static std::vector<std::string> arguments(const Options& options, const std::filesystem::path& config,
                                            const std::string& control) {
    std::vector<std::string> argv{options.daemon, "-c", config.string(), "--control", control};
    if (options.verbose) argv.emplace_back("-v");
    return argv;
  }

  NotifySocket notify_;
  std::string control_;
  ChildProcess daemon_;
  std::optional<EventReader> out_;
  int device_ = 0;
};

CaseResult run_case(const Options& options, XServer& x, TestMouse& mouse, TestMouse* untaken,
                    const UeventMonitor& uevents, const std::filesystem::path& config, const CaseSpec& spec) {
  CaseResult result;
  const auto start = Clock::now();
  RunningDaemon daemon(options, x, mouse, uevents, config);
  auto fatal = [&](const std::string& what) { daemon.fatal(what); };
  EventReader& out = daemon.out();
  const int device = daemon.x_device();
  trace(options, fmt::format("{}: X device {}", spec.label, device));

  ph::PipelineConfig pipeline_config;
  pipeline_config.mode = spec.mode;
  pipeline_config.desktop = kDesktop;
  pipeline_config.pointer_gain = 1.0;
  const auto scene = std::make_shared<const ph::Scene>(ph::load_scene(ph::parse_scene_file(config)));
  ph::Pipeline model(scene, pipeline_config);
  if (spec.mode == ph::OutputMode::relative) {
    x.set_accel_profile(device, spec.x_profile);
    if (x.accel_profile(device) != spec.x_profile) fatal("X kept the profile " + x.accel_profile(device));
    // Relative output moves X's pointer from where it is: start it where the model starts.
    const Vec2 at = model.cursor().position;
    // A warp, then the first motion of a new relative device put X's pointer in the screen's far corner
    // when an absolute device had moved it last (X.Org 21.1.7); one relative XTEST motion first avoids it.
    x.xtest_move_by(1, 1);
    x.warp(static_cast<int>(at.x), static_cast<int>(at.y));
    trace(options, fmt::format("{}: warped X's pointer to ({}, {})", spec.label, x.pointer().x, x.pointer().y));
  }
  x.drain();
  long motions = x.motions(device);
  std::int32_t abs[2] = {abs_value(out.fd(), ev::kAbsX), abs_value(out.fd(), ev::kAbsY)};

  HandMotion hand({150, 150, 1620, 780}, 12345);
  const auto first = Clock::now();
  auto origin = first;  // frame i is due at origin + i * 8 ms; moved on when a frame is late
  long frame = 0;
  Vec2 previous = model.cursor().position;
  for (; result.motion_frames < spec.frames; ++frame) {
    const Counts counts = hand.next(model.cursor().position);
    const auto due = origin + std::chrono::microseconds(frame * kFramePeriodUs);
    const auto now = Clock::now();
    if (now < due) {
      std::this_thread::sleep_until(due);
    } else if (now - due > 1ms) {
      // Late (TCG): keep the 8 ms to the next frames rather than catching up with a burst, which
      // would look like a faster hand to the acceleration profiles.
      ++result.late_frames;
      result.late_ms += std::chrono::duration<double, std::milli>(now - due).count();
      origin += now - due;
    }
    if (!counts.any()) continue;  // a pause: time passes, nothing is sent
    ++result.motion_frames;
    std::vector<ph::InputEvent> events;
    if (counts.dx != 0) events.push_back(rel(ev::kRelX, counts.dx));
    if (counts.dy != 0) events.push_back(rel(ev::kRelY, counts.dy));
    const Frame in = make_frame(std::move(events));
    const Frame expected = as_delivered(model.process(in), abs);
    result.model_path += length(model.cursor().position - previous);
    previous = model.cursor().position;
    mouse.send(in);
    if (!expected.events.empty()) {
      ++result.daemon_frames;
      const std::optional<Frame> got = out.next_frame(kFrameTimeout);
      if (!got)
        fatal(fmt::format("frame {}: nothing came out of the daemon within {} s", frame, kFrameTimeout.count()));
      if (!same_events(*got, expected) && result.daemon_mismatches++ < 3) {
        result.problems.push_back(fmt::format("frame {}: the daemon emitted [{}], the offline pipeline [{}]", frame,
                                              describe(*got), describe(expected)));
      }
      if (!x.wait_motions(device, ++motions, kFrameTimeout)) {
        if (result.lost_syncs++ < 3) result.problems.push_back(fmt::format("frame {}: X reported no motion", frame));
        x.drain();
        motions = x.motions(device);
      }
    }
    const XServer::Pointer pointer = x.pointer();
    result.distances.add(frame, model.cursor().position, pointer);
    if (result.motion_frames <= 3 ||
        (options.trace_from >= 0 && frame >= options.trace_from && frame < options.trace_from + 12)) {
      trace(options, fmt::format("{}: frame {} [{}] -> [{}]: model ({:.3f}, {:.3f}), X ({}, {})", spec.label, frame,
                                 describe(in), describe(expected), model.cursor().position.x, model.cursor().position.y,
                                 pointer.x, pointer.y));
    }
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - first).count();
  if (spec.untaken_after && untaken != nullptr) {
    // Another pointer, which the daemon does not take, moves X's pointer on from where the daemon's
    // device left it: X switches between the two devices without a jump.
    const std::optional<int> other = x.wait_for_pointer(untaken->name(), 10s);
    if (!other) fatal("X did not add the untaken pointer");
    x.drain();
    const long seen = x.motions(*other);
    const XServer::Pointer before = x.pointer();
    untaken->send(make_frame({rel(ev::kRelX, 5), rel(ev::kRelY, 5)}));
    if (!x.wait_motions(*other, seen + 1, kFrameTimeout)) result.problems.push_back("the untaken pointer: no motion");
    const XServer::Pointer after = x.pointer();
    result.notes.push_back(fmt::format("the untaken pointer's +5,+5 counts moved X's pointer from ({}, {}) by ({}, {})",
                                       before.x, before.y, after.x - before.x, after.y - before.y));
    const auto moved = [](int d) { return d >= 1 && d <= 15; };  // X's adaptive profile: a factor, not a jump
    if (!moved(after.x - before.x) || !moved(after.y - before.y)) {
      result.problems.push_back("the untaken pointer did not move X's pointer on from where it was: " +
                                result.notes.back());
    }
  }

  // The daemon's own model, through its control socket, is the offline one.
  const Vec2 reported = ControlClient(daemon.control(), 5s).cursor();
  if (std::abs(reported.x - model.cursor().position.x) > 1e-9 ||
      std::abs(reported.y - model.cursor().position.y) > 1e-9) {
    result.problems.push_back(fmt::format("the daemon's cursor model is ({}, {}), the offline one ({:.3f}, {:.3f})",
                                          reported.x, reported.y, model.cursor().position.x,
                                          model.cursor().position.y));
  }
  daemon.stop(x, result.problems);
  trace(options,
        fmt::format("{}: {:.1f} s in all", spec.label, std::chrono::duration<double>(Clock::now() - start).count()));
  return result;
}

// One line per case: PASS / FAIL against the bound, INFO where the case only measures.
bool report(const CaseSpec& spec, const CaseResult& r) {
  const Distances& d = r.distances;
  const long over = spec.bound ? d.over(*spec.bound) : 0;
  const bool ok = over == 0 && r.problems.empty();
  const char* verdict = !ok ? "FAIL" : spec.bound ? "PASS" : "INFO";
  std::printf(
      "%s %s: %ld motion frames in %.1f s (%ld frames late, by %.0f ms in all), model path %.0f px; distance "
      "from the model to the centre of X's pixel over %ld checks: max %.3f px per axis (%.3f px), RMS %.3f px, "
      "last %.3f px%s\n",
      verdict, spec.label.c_str(), r.motion_frames, r.seconds, r.late_frames, r.late_ms, r.model_path, d.checks(),
      d.max_axis(), d.max_euclid(), d.rms(), d.last(),
      spec.bound ? fmt::format("; {} checks beyond {} px", over, *spec.bound).c_str() : "");
  if (spec.bound && over > 0) std::printf("    first beyond: %s\n", d.first_over(*spec.bound).c_str());
  std::printf("    worst: %s; daemon frames %ld, of them unlike the offline pipeline %ld; X syncs lost %ld\n",
              d.worst().c_str(), r.daemon_frames, r.daemon_mismatches, r.lost_syncs);
  for (const std::string& n : r.notes) std::printf("    %s\n", n.c_str());
  for (const std::string& p : r.problems) std::printf("    %s\n", p.c_str());
  std::fflush(stdout);
  return ok;
}

// ---- the model follows what else moves the cursor (the session helper connected) ----------------------------

// Sends the hand's next frame and, once X has taken in what the daemon made of it, returns the pixel X
// shows; nullopt for a pause frame (nothing sent). Frames the daemon turns into nothing (an absolute
// position that did not change) are waited for only briefly.
struct Player {
  XServer& x;
  TestMouse& mouse;
  RunningDaemon& daemon;
  long motions = 0;
  long frame = 0;
  Clock::time_point origin = Clock::now();
  std::optional<Frame> last_out{};  // what the daemon emitted for the last motion frame, with the kernel's times

  std::optional<XServer::Pointer> play(Counts counts) {
    const auto due = origin + std::chrono::microseconds(frame++ * kFramePeriodUs);
    if (Clock::now() < due) {
      std::this_thread::sleep_until(due);
    } else {
      origin += Clock::now() - due;  // late under TCG: keep the 8 ms rather than send a burst
    }
    if (!counts.any()) return std::nullopt;
    std::vector<ph::InputEvent> events;
    if (counts.dx != 0) events.push_back(rel(ev::kRelX, counts.dx));
    if (counts.dy != 0) events.push_back(rel(ev::kRelY, counts.dy));
    mouse.send(make_frame(std::move(events)));
    last_out = daemon.out().next_frame(300ms);
    if (last_out) {
      if (!x.wait_motions(daemon.x_device(), ++motions, kFrameTimeout)) {
        x.drain();
        motions = x.motions(daemon.x_device());
      }
    }
    return x.pointer();
  }
  // A pause: time passes, nothing is sent.
  void pause(Clock::duration d) {
    std::this_thread::sleep_for(d);
    origin = Clock::now() - std::chrono::microseconds(frame * kFramePeriodUs);
  }
  void start() {
    x.drain();
    motions = x.motions(daemon.x_device());
    origin = Clock::now() - std::chrono::microseconds(frame * kFramePeriodUs);
  }
};

std::string distances_text(const Distances& d) {
  return fmt::format("{} checks, max {:.3f} px per axis ({:.3f} px), RMS {:.3f} px", d.checks(), d.max_axis(),
                     d.max_euclid(), d.rms());
}

void print_verdict(const std::string& label, const std::vector<std::string>& problems,
                   const std::vector<std::string>& notes, double seconds) {
  std::printf("%s %s (%.1f s)%s\n", problems.empty() ? "PASS" : "FAIL", label.c_str(), seconds,
              problems.empty() ? "" : ":");
  for (const std::string& n : notes) std::printf("    %s\n", n.c_str());
  for (const std::string& p : problems) std::printf("    %s\n", p.c_str());
  std::fflush(stdout);
}

// [d] an application warp (xdotool mousemove) and [g] a pointer the daemon does not take move X's pointer;
// with pseudohaptic-session connected, the daemon's model (its `cursor` over the control socket) follows,
// and X's pixel holds the model at every later check. Returns how many of the two failed.
int follow_cases(const Options& options, XServer& x, TestMouse& mouse, TestMouse& untaken, const UeventMonitor& uevents,
                 const std::filesystem::path& config) {
  const auto start = Clock::now();
  RunningDaemon daemon(options, x, mouse, uevents, config);
  const char* display = std::getenv("DISPLAY");
  ChildProcess helper({options.session, "--control", daemon.control(), "--passthrough", "PH-GAME", "-v"},
                      {std::string("DISPLAY=") + (display != nullptr ? display : ""), "PATH=/usr/bin:/bin"},
                      (options.scratch / "session-follow.log").string());
  ControlClient control(daemon.control(), 10s);
  if (!wait_until([&] { return control.request("status").find("helper=yes") != std::string::npos; }, 20s, nullptr,
                  200ms)) {
    daemon.fatal("the session helper did not connect within 20 s; its log:\n" + helper.log());
  }
  Player player{x, mouse, daemon};
  HandMotion hand({150, 150, 1620, 780}, 777);
  // Hand frames; from `from` on, X's pixel must hold the model (read over the socket) at every check.
  auto move = [&](int frames, int from, Distances& held, std::vector<XServer::Pointer>* seen) {
    for (int k = 0; k < frames;) {
      const Vec2 model = control.cursor();
      const std::optional<XServer::Pointer> at = player.play(hand.next(model));
      if (!at) continue;
      ++k;
      if (seen != nullptr) seen->push_back(*at);
      if (k >= from) held.add(player.frame, control.cursor(), *at);
    }
  };
  player.start();
  Distances before;
  move(100, 1, before, nullptr);

  int failed = 0;
  {  // [d] an application warp, then motion: the model follows within two frames
    const auto case_start = Clock::now();
    std::vector<std::string> problems, notes;
    player.pause(400ms);
    const int status = std::system("xdotool mousemove 400 300");
    if (status != 0) problems.push_back(fmt::format("xdotool mousemove: status {}", status));
    const XServer::Pointer warped = x.pointer();
    player.pause(400ms);
    Distances after;
    std::vector<XServer::Pointer> seen;
    move(60, 2, after, &seen);
    if (seen.size() >= 2) {
      const XServer::Pointer p = seen[1];
      notes.push_back(
          fmt::format("X's pointer warped to ({}, {}), after two frames at ({}, {})", warped.x, warped.y, p.x, p.y));
      // Two frames move the cursor by some 10s of px; going back to the old place is hundreds away.
      if (std::hypot(p.x - 400, p.y - 300) > 120) problems.push_back("the warp was undone: " + notes.back());
    }
    notes.push_back("from the second frame after the warp: " + distances_text(after));
    if (after.over(0.5) > 0) problems.push_back("first beyond 0.5 px: " + after.first_over(0.5));
    notes.push_back("before the warp: " + distances_text(before));
    if (before.over(0.5) > 0) problems.push_back("before the warp, first beyond 0.5 px: " + before.first_over(0.5));
    print_verdict("[d] an application warp (xdotool mousemove), then motion: the model follows", problems, notes,
                  std::chrono::duration<double>(Clock::now() - case_start).count());
    failed += !problems.empty();
  }
  {  // [g] an untaken pointer moves X's pointer: the model follows, then the mouse moves on from there
    const auto case_start = Clock::now();
    std::vector<std::string> problems, notes;
    const std::optional<int> other = x.wait_for_pointer(untaken.name(), 10s);
    if (!other) daemon.fatal("X did not add the untaken pointer");
    x.drain();
    long seen = x.motions(*other);
    const XServer::Pointer from = x.pointer();
    for (int i = 0; i < 3; ++i) {
      untaken.send(make_frame({rel(ev::kRelX, 10), rel(ev::kRelY, 10)}));
      if (!x.wait_motions(*other, ++seen, kFrameTimeout)) problems.push_back("the untaken pointer: no motion");
      std::this_thread::sleep_for(8ms);
    }
    const XServer::Pointer to = x.pointer();
    const auto moved = Clock::now();
    const auto inside = [&] {
      const Vec2 m = control.cursor();
      return std::abs(m.x - (to.x + 0.5)) <= 0.5 && std::abs(m.y - (to.y + 0.5)) <= 0.5;
    };
    const bool followed = wait_until(inside, 3s, nullptr, 20ms);
    const Vec2 m = control.cursor();
    notes.push_back(
        fmt::format("the untaken pointer moved X's pointer from ({}, {}) to ({}, {}); the model {} "
                    "({:.2f}, {:.2f}) after {:.0f} ms",
                    from.x, from.y, to.x, to.y, followed ? "followed to" : "stayed at", m.x, m.y,
                    std::chrono::duration<double, std::milli>(Clock::now() - moved).count()));
    if (!followed) problems.push_back("the model did not follow within 3 s");
    Distances after;
    player.start();
    move(60, 1, after, nullptr);
    notes.push_back("the mouse then: " + distances_text(after));
    if (after.over(0.5) > 0) problems.push_back("first beyond 0.5 px: " + after.first_over(0.5));
    print_verdict("[g] an untaken pointer moves the cursor: the model follows", problems, notes,
                  std::chrono::duration<double>(Clock::now() - case_start).count());
    failed += !problems.empty();
  }
  // A window of the application the helper was given with --passthrough, made the active one.
  const auto focus_game = [&] {
    const Window game = XCreateSimpleWindow(x.get(), x.root(), 0, 0, 64, 64, 0, 0, 0);
    XClassHint hint{const_cast<char*>("ph-game"), const_cast<char*>("Ph-game")};
    XSetClassHint(x.get(), game, &hint);
    x.set_active_window(game);
    XSync(x.get(), False);
    return game;
  };
  const auto passing = [&] { return control.request("status").find("passthrough=on") != std::string::npos; };
  {  // [h] a listed application has the focus: the mouse's motion reaches X unchanged through the
     // pass-through device, not through the absolute one, and the textures come back when it loses it
    const auto case_start = Clock::now();
    std::vector<std::string> problems, notes;
    const Window game = focus_game();
    if (!wait_until(passing, 10s, nullptr, 50ms)) daemon.fatal("the daemon did not switch to pass-through");
    const std::optional<int> relative = x.wait_for_pointer(std::string(kVirtualName) + " (pass-through)", 30s);
    if (!relative) daemon.fatal("X did not add the pass-through device");
    // What the daemon emits, read beside X from both of its devices.
    EventReader through(find_input_node(std::string(kVirtualName) + " (pass-through)"));
    EventReader positions(find_input_node(kVirtualName));
    x.drain();
    const XServer::Pointer from = x.pointer();
    int unchanged = 0;
    for (int i = 0; i < 5; ++i) {
      const Frame in = make_frame({rel(ev::kRelX, -7), rel(ev::kRelY, 3)});
      mouse.send(in);
      const std::optional<Frame> got = through.next_frame(kFrameTimeout);
      if (!got) {
        problems.push_back(fmt::format("frame {}: nothing came out of the pass-through device", i));
      } else if (!same_events(*got, in)) {
        problems.push_back(
            fmt::format("frame {}: sent [{}], the pass-through device emitted [{}]", i, describe(in), describe(*got)));
      } else {
        ++unchanged;
      }
      std::this_thread::sleep_for(8ms);
    }
    std::this_thread::sleep_for(200ms);
    x.drain();
    const XServer::Pointer to = x.pointer();
    const std::size_t from_absolute = positions.read_now().size();
    if (from_absolute != 0)
      problems.push_back(
          fmt::format("the absolute device emitted {} events while the application had the focus", from_absolute));
    if (to.x >= from.x || to.y <= from.y) problems.push_back("X's pointer did not move with the relative motion");
    notes.push_back(
        fmt::format("{} of 5 frames of (-7, +3) counts came out of the pass-through device (XInput id {}) "
                    "unchanged, nothing out of the absolute one; X's pointer went from ({}, {}) to ({}, {})",
                    unchanged, *relative, from.x, from.y, to.x, to.y));
    // The focus leaves while the mouse goes on moving: the frames after the switch start where the application left
    // X's pointer, not from the model of before (the daemon holds them for the helper's answer, as after a pause):
    // X's pointer never jumps back. The application first takes the pointer 200 px or so away from the model, and
    // the frames come a millisecond apart, so that some reach the daemon before the helper's answer.
    for (int i = 0; i < 10; ++i) {
      mouse.send(make_frame({rel(ev::kRelX, -20)}));
      std::this_thread::sleep_for(8ms);
    }
    std::this_thread::sleep_for(100ms);
    x.drain();
    x.set_active_window(None);
    XSync(x.get(), False);
    XServer::Pointer last = x.pointer();
    double largest_step = 0.0;
    std::string largest_at;
    for (int i = 0; i < 200; ++i) {
      mouse.send(make_frame({rel(ev::kRelX, 1)}));
      std::this_thread::sleep_for(1ms);
      if (i % 5 != 4) continue;
      const XServer::Pointer now = x.pointer();
      const double step = std::hypot(now.x - last.x, now.y - last.y);
      if (step > largest_step) {
        largest_step = step;
        largest_at = fmt::format("frames {}-{}: ({}, {}) -> ({}, {})", i - 4, i, last.x, last.y, now.x, now.y);
      }
      last = now;
    }
    if (!wait_until([&] { return !passing(); }, 10s, nullptr, 50ms)) problems.push_back("pass-through did not end");
    notes.push_back(fmt::format(
        "200 frames of +1 count 1 ms apart across the switch: X's pointer's largest step in 5 frames {:.1f} px ({})",
        largest_step, largest_at));
    if (largest_step > 60.0) problems.push_back("X's pointer jumped at the switch: " + largest_at);
    XDestroyWindow(x.get(), game);
    XSync(x.get(), False);
    // Back to the textures: after the helper's answer, the mouse's frames come from the absolute device
    // again and X's pixel holds the model.
    std::this_thread::sleep_for(400ms);
    Distances after;
    player.start();
    move(30, 2, after, nullptr);
    notes.push_back("after the focus left: " + distances_text(after));
    if (after.over(0.5) > 0) problems.push_back("after pass-through, first beyond 0.5 px: " + after.first_over(0.5));
    print_verdict("[h] an application that holds the pointer gets the mouse's motion unchanged (pass-through)",
                  problems, notes, std::chrono::duration<double>(Clock::now() - case_start).count());
    failed += !problems.empty();
  }
  {  // [i] the session ends (the helper stops) while a listed application has the focus: pass-through ends with
     // the helper's connection, and the mouse's frames come out of the absolute device again
    const auto case_start = Clock::now();
    std::vector<std::string> problems, notes;
    const Window game = focus_game();
    if (!wait_until(passing, 10s, nullptr, 50ms)) daemon.fatal("the daemon did not switch to pass-through again");
    EventReader through(find_input_node(std::string(kVirtualName) + " (pass-through)"));
    EventReader positions(find_input_node(kVirtualName));
    helper.signal(SIGTERM);
    helper.wait_exit(5s);
    const auto stopped = Clock::now();
    if (!wait_until([&] { return !passing(); }, 5s, nullptr, 10ms))
      problems.push_back("pass-through stayed on after the helper that asked for it had gone");
    const double ended_ms = std::chrono::duration<double, std::milli>(Clock::now() - stopped).count();
    through.read_now();
    positions.read_now();
    const Frame in = make_frame({rel(ev::kRelX, 6), rel(ev::kRelY, -2)});
    mouse.send(in);
    const std::optional<Frame> got = positions.next_frame(kFrameTimeout);
    if (!got) problems.push_back("nothing came out of the absolute device after pass-through ended");
    std::this_thread::sleep_for(100ms);
    const std::size_t from_through = through.read_now().size();
    if (from_through != 0)
      problems.push_back(fmt::format("the pass-through device emitted {} events after it ended", from_through));
    notes.push_back(
        fmt::format("the helper stopped with the application in focus; status said passthrough=off "
                    "{:.0f} ms later; the next frame came out of the absolute device{}",
                    ended_ms, got ? " (" + describe(*got) + ")" : std::string(" (none)")));
    x.set_active_window(None);
    XDestroyWindow(x.get(), game);
    XSync(x.get(), False);
    print_verdict("[i] the session ends with that application in focus: pass-through ends with the helper", problems,
                  notes, std::chrono::duration<double>(Clock::now() - case_start).count());
    failed += !problems.empty();
  }
  std::vector<std::string> problems;
  daemon.stop(x, problems);
  for (const std::string& p : problems) std::printf("FAIL [d, g] %s\n", p.c_str());
  trace(options, fmt::format("[d, g]: {:.1f} s in all", std::chrono::duration<double>(Clock::now() - start).count()));
  if (failed > 0) std::printf("---- the daemon's log is in %s, the helper's:\n%s", "daemon.log", helper.log().c_str());
  return failed + (problems.empty() ? 0 : 1);
}

// ---- [j] outputs of different sizes ---------------------------------------------------------------------------

// Two outputs side by side, 1920 x 1080 and 1280 x 720 to its right: below the smaller one lies a 1280 x 360 px part
// of the root window that no output shows, and X stops the pointer at the edge of the output it comes from
// (RandR's RRConstrainCursorHarder). With pseudohaptic-session telling the daemon where the outputs are, the model
// stops there too: X's pixel holds the model at every frame, down against the smaller output's bottom edge, back up
// (the first frame moves the cursor), and right against the larger one's edge below the smaller one.
bool outputs_case(const Options& options, XServer& x, TestMouse& mouse, const UeventMonitor& uevents) {
  const auto case_start = Clock::now();
  const std::string label = "[j] outputs of different sizes: the model stops where X stops the pointer";
  std::vector<std::string> problems, notes;
  std::system("xrandr --addmode DUMMY1 1280x720 2>/dev/null");  // (already there after [e])
  if (const int status = std::system("xrandr --output DUMMY1 --mode 1280x720 --right-of DUMMY0"); status != 0)
    problems.push_back(fmt::format("xrandr: status {}", status));
  // The desktop left to the helper (no `desktop` key): the daemon's desktop and its outputs are the helper's.
  const std::filesystem::path config = options.scratch / "j.toml";
  std::ofstream(config, std::ios::trunc) << "[daemon]\ndevices = [\"name:ph-x11 mouse\"]\noutput = \"absolute\"\n"
                                            "acceleration = \"flat\"\nspeed = 0.0\npointer_speed = 1.0\n";
  try {
    RunningDaemon daemon(options, x, mouse, uevents, config);
    const int first_device = daemon.x_device();
    const char* display = std::getenv("DISPLAY");
    ChildProcess helper({options.session, "--control", daemon.control(), "-v"},
                        {std::string("DISPLAY=") + (display != nullptr ? display : ""), "PATH=/usr/bin:/bin"},
                        (options.scratch / "session-outputs.log").string());
    ControlClient control(daemon.control(), 10s);
    const auto laid_out = [&] {
      const std::string status = control.request("status");
      return status.find("helper=yes") != std::string::npos &&
             status.find("desktop=0,0,3200,1080") != std::string::npos;
    };
    if (!wait_until(laid_out, 20s, nullptr, 200ms))
      daemon.fatal("the daemon did not take the helper's 3200 x 1080 layout within 20 s; its log:\n" + helper.log());
    // A new desktop remakes the absolute device (new axis ranges): X's id for it changes.
    std::optional<int> device;
    wait_until([&] { return (device = x.pointer_device(kVirtualName)) && *device != first_device; }, 10s, nullptr,
               100ms);
    if (!device) daemon.fatal("X has no virtual device after the new layout");
    Distances held;
    long frame = 0;
    // Each frame's check once X's pointer is on the model's pixel, or after 2 s where it never comes there (a frame
    // held against an edge moves neither; under TCG X may take a while to take in what the daemon emitted).
    const auto on_the_model = [&] {
      const Vec2 m = control.cursor();
      const XServer::Pointer p = x.pointer();
      return std::floor(m.x) == p.x && std::floor(m.y) == p.y;
    };
    const auto play = [&](int dx, int dy, int frames) {
      for (int i = 0; i < frames; ++i, ++frame) {
        mouse.send(make_frame({rel(ev::kRelX, dx), rel(ev::kRelY, dy)}));
        std::this_thread::sleep_for(8ms);
        wait_until(on_the_model, 2s, nullptr, 10ms);
        held.add(frame, control.cursor(), x.pointer());
      }
    };
    // X's pointer and the model on the smaller output (the helper's answer after a pause would bring the model to
    // wherever X's pointer is).
    x.warp(2500, 500);
    control.request("position 2500.5 500.5");
    std::this_thread::sleep_for(500ms);
    play(0, 1, 1);
    play(0, 40, 12);  // down into the space below the smaller output: both stop at its bottom row
    const XServer::Pointer bottom = x.pointer();
    const Vec2 model_bottom = control.cursor();
    play(0, -40, 1);  // back up: the cursor moves at once
    const XServer::Pointer first_up = x.pointer();
    play(0, -40, 3);
    play(-40, 0, 20);  // left onto the larger output
    play(0, 40, 12);   // down below the smaller output's bottom row, on the larger one
    play(40, 0, 12);   // right, below the smaller one: both stop at the larger one's right column
    const XServer::Pointer right = x.pointer();
    notes.push_back(
        fmt::format("down against the smaller output: X ({}, {}), the model ({:.2f}, {:.2f}); one frame of "
                    "-40 counts up: X at y {}; right below it: X ({}, {})",
                    bottom.x, bottom.y, model_bottom.x, model_bottom.y, first_up.y, right.x, right.y));
    notes.push_back("every frame: " + distances_text(held));
    if (bottom.y != 719) problems.push_back("X did not hold the pointer at the smaller output's bottom row (719)");
    if (first_up.y >= bottom.y) problems.push_back("the first frame up did not move the cursor");
    if (right.x != 1919) problems.push_back("X did not hold the pointer at the larger output's right column (1919)");
    if (held.over(0.5) > 0) problems.push_back("first beyond 0.5 px: " + held.first_over(0.5));
    helper.signal(SIGTERM);
    helper.wait_exit(5s);
    daemon.stop(x, problems);
  } catch (const Fatal& e) {
    problems.push_back(e.what());
  }
  if (const int status = std::system("xrandr --output DUMMY1 --off"); status != 0)
    problems.push_back(fmt::format("xrandr --off: status {}", status));
  print_verdict(label, problems, notes, std::chrono::duration<double>(Clock::now() - case_start).count());
  return problems.empty();
}

// ---- [f] the daemon's adaptive profile against libinput's own ------------------------------------------------

// The pixels X shows after each motion frame of `frames`, with the daemon on `config` (X's libinput
// profile `x_profile` for relative output; X's pointer starts where the model does). `emitted_at`: the
// kernel's time on what the daemon emitted for each of them (0 where nothing came out).
std::vector<Vec2> cursor_path(const Options& options, XServer& x, TestMouse& mouse, const UeventMonitor& uevents,
                              const std::filesystem::path& config, const std::string& x_profile,
                              const std::vector<Counts>& frames, std::vector<std::string>& problems,
                              std::vector<ph::TimeUs>& emitted_at) {
  RunningDaemon daemon(options, x, mouse, uevents, config);
  if (!x_profile.empty()) {
    x.set_accel_profile(daemon.x_device(), x_profile);
    x.xtest_move_by(1, 1);  // see run_case: a warp after an absolute device needs a relative motion first
    x.warp(960, 540);
  }
  Player player{x, mouse, daemon};
  player.start();
  std::vector<Vec2> path;
  for (const Counts& c : frames) {
    if (const std::optional<XServer::Pointer> at = player.play(c)) {
      path.push_back({at->x + 0.5, at->y + 0.5});
      emitted_at.push_back(player.last_out ? player.last_out->events.back().time : 0);
    }
  }
  daemon.stop(x, problems);
  return path;
}

// The pixels our adaptive profile (absolute output, flat scene) puts the cursor on for the motion frames of
// `frames` stamped with `times`, offline, from where cursor_path starts X's pointer.
std::vector<Vec2> offline_path(const std::vector<Counts>& frames, const std::vector<ph::TimeUs>& times) {
  ph::PipelineConfig config;
  config.mode = ph::OutputMode::absolute;
  config.desktop = kDesktop;
  config.acceleration.profile = ph::AccelProfile::adaptive;
  config.start = Vec2{960.0, 540.0};
  ph::Pipeline model(std::make_shared<const ph::Scene>(), config);
  std::vector<Vec2> path;
  std::size_t i = 0;
  for (const Counts& c : frames) {
    if (!c.any() || i >= times.size()) continue;
    model.process(stamped(make_frame({rel(ev::kRelX, c.dx), rel(ev::kRelY, c.dy)}), times[i++]));
    const Vec2 at = model.cursor().position;
    path.push_back({std::floor(at.x) + 0.5, std::floor(at.y) + 0.5});
  }
  return path;
}

// How far apart two paths of pixels are, against the length of `reference`.
struct PathGap {
  double length = 0, other_length = 0, max_distance = 0, rms = 0, end = 0;
  std::size_t worst = 0;

  PathGap(const std::vector<Vec2>& other, const std::vector<Vec2>& reference) {
    double sum_sq = 0;
    for (std::size_t i = 0; i < other.size(); ++i) {
      if (i > 0) length += ph::length(reference[i] - reference[i - 1]);
      if (i > 0) other_length += ph::length(other[i] - other[i - 1]);
      const double d = ph::length(other[i] - reference[i]);
      sum_sq += d * d;
      if (d > max_distance) {
        max_distance = d;
        worst = i;
      }
    }
    rms = std::sqrt(sum_sq / static_cast<double>(std::max<std::size_t>(other.size(), 1)));
    end = other.empty() ? 0.0 : ph::length(other.back() - reference.back());
  }
  double percent() const { return 100.0 * max_distance / length; }
};

bool acceleration_case(const Options& options, XServer& x, TestMouse& mouse, const UeventMonitor& uevents) {
  const auto start = Clock::now();
  const std::string label =
      "[f] our adaptive profile against X's libinput adaptive profile, on the times libinput saw (flat scene)";
  std::vector<std::string> problems, notes;
  const std::vector<Counts> frames = out_and_back(options.acceleration_strokes, 4242);
  std::vector<ph::TimeUs> absolute_times, relative_times;
  const std::vector<Vec2> ours = cursor_path(
      options, x, mouse, uevents, write_config(options.scratch, "f-absolute", ph::OutputMode::absolute, "adaptive", ""),
      "", frames, problems, absolute_times);
  const std::vector<Vec2> theirs = cursor_path(
      options, x, mouse, uevents, write_config(options.scratch, "f-relative", ph::OutputMode::relative, "flat", ""),
      "adaptive", frames, problems, relative_times);
  // libinput measures the hand's speed on the times of the virtual device's events, which the daemon's
  // latency under TCG spreads; our profile measures it on the mouse's. The bound is on our profile given the
  // same times as libinput (the daemon's own acceleration equals the offline one: cases a and [3] of
  // daemon_e2e); the live comparison is reported beside it.
  const bool all_emitted = std::find(relative_times.begin(), relative_times.end(), 0) == relative_times.end();
  const std::vector<Vec2> same_times = offline_path(frames, relative_times);
  if (ours.size() != theirs.size() || ours.empty() || same_times.size() != theirs.size() || !all_emitted) {
    problems.push_back(fmt::format("paths of {}, {} and {} checks{}", ours.size(), theirs.size(), same_times.size(),
                                   all_emitted ? "" : "; a relative frame without output"));
  } else {
    auto describe_gap = [&](const PathGap& g, const std::vector<Vec2>& path) {
      return fmt::format(
          "libinput's path {:.0f} px, ours {:.0f} px; apart by max {:.1f} px ({:.2f} % of the path; worst at check {}: "
          "ours ({:.1f}, {:.1f}), libinput's ({:.1f}, {:.1f})), RMS {:.1f} px, at the end {:.1f} px",
          g.length, g.other_length, g.max_distance, g.percent(), g.worst, path[g.worst].x, path[g.worst].y,
          theirs[g.worst].x, theirs[g.worst].y, g.rms, g.end);
    };
    const PathGap offline(same_times, theirs), live(ours, theirs);
    notes.push_back(fmt::format("{} motion frames. Our profile on the times libinput saw: {}", ours.size(),
                                describe_gap(offline, same_times)));
    notes.push_back("the daemon's absolute output live (its times, measured only): " + describe_gap(live, ours));
    if (offline.max_distance > 0.02 * offline.length) problems.push_back("apart by more than 2 % of the path");
    // Given the same times the two profiles are one computation: only a pixel's rounding may part them.
    if (offline.max_distance > 2.0) problems.push_back("given the same times, apart by more than 2 px");
  }
  print_verdict(label, problems, notes, std::chrono::duration<double>(Clock::now() - start).count());
  return problems.empty();
}

// ---- the session helper ------------------------------------------------------------------------------------

// pseudohaptic-session on this X server, talking to a stand-in for the daemon's control socket: what it
// says at start, its answer to a query, its layout after RandR changes, its reconnection, its exit.
bool session_case(const Options& options, XServer& x) {
  HelperCase c;
  c.label = "pseudohaptic-session (x11 backend) against a stand-in control socket";
  ControlStub stub((options.scratch / "control").string());
  x.warp(700, 300);
  const char* display = std::getenv("DISPLAY");
  ChildProcess helper({options.session, "--control", stub.path(), "--passthrough", "PH-GAME", "-v"},
                      {std::string("DISPLAY=") + (display != nullptr ? display : ""), "PATH=/usr/bin:/bin"},
                      (options.scratch / "session.log").string());
  // Lines before the one wanted are not a problem here: the pointer's reports may come between.
  auto expect = [&](const std::string& want, const std::string& when) { c.expect(stub, want, when, false); };
  auto xrandr = [&](const std::string& args) {
    const int status = std::system(("xrandr " + args).c_str());
    if (status != 0) c.problems.push_back(fmt::format("xrandr {}: status {}", args, status));
  };
  try {
    if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
    expect("helper x11", "at start");
    expect("layout 0 0 1920 1080", "at start");
    expect("position 700.5 300.5", "at start");
    x.warp(123, 456);
    stub.send("query");
    expect("position 123.5 456.5", "after a query");
    xrandr("--output DUMMY0 --mode 1280x720");
    expect("layout 0 0 1280 720", "after a smaller mode");
    xrandr("--output DUMMY0 --mode 1920x1080");
    expect("layout 0 0 1920 1080", "after the mode back");
    xrandr("--addmode DUMMY1 1280x720");  // the dummy driver's other outputs are disconnected, without modes
    xrandr("--output DUMMY1 --mode 1280x720 --right-of DUMMY0");
    // Below the smaller one lies space no output shows: the outputs follow the desktop.
    expect("layout 0 0 3200 1080 0 0 1920 1080 1920 0 1280 720", "after a second, smaller output to the right");
    xrandr("--output DUMMY1 --off");
    expect("layout 0 0 1920 1080", "after the second output is off");
    // A listed application gets the focus (as a window manager says: _NET_ACTIVE_WINDOW), then none has it.
    const Window game = XCreateSimpleWindow(x.get(), x.root(), 0, 0, 64, 64, 0, 0, 0);
    XClassHint hint{const_cast<char*>("ph-game"), const_cast<char*>("Ph-game")};
    XSetClassHint(x.get(), game, &hint);
    x.set_active_window(game);
    expect("passthrough on", "when a listed application has the focus");
    x.set_active_window(None);
    expect("passthrough off", "when it has lost the focus");
    XDestroyWindow(x.get(), game);
    XSync(x.get(), False);
    stub.stop();       // as a daemon restart: the socket goes away and comes back
    x.warp(300, 200);  // before the helper can reconnect: it says where the pointer is as it connects
    std::this_thread::sleep_for(700ms);
    stub.restart();
    if (!stub.accept(20s)) throw Fatal("the helper did not reconnect within 20 s");
    expect("helper x11", "after reconnecting");
    expect("layout 0 0 1920 1080", "after reconnecting");
    expect("position 300.5 200.5", "after reconnecting");
    helper.signal(SIGTERM);
    const std::optional<int> status = helper.wait_exit(10s);
    if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
      c.problems.push_back("SIGTERM: " + (status ? describe_wait_status(*status) : std::string("still running")));
    }
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

int usage(const char* why) {
  std::fprintf(stderr,
               "x11_cursor_e2e: %s\nusage: x11_cursor_e2e DAEMON [--scene DIR] [--session HELPER] [--frames N] "
               "[--relative-frames N] [--cases abcedf] [-v [--trace-from FRAME]]\n"
               "       x11_cursor_e2e --write-scene DIR\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--frames" && i + 1 < argc) {
      options.frames = std::atoi(argv[++i]);
    } else if (arg == "--relative-frames" && i + 1 < argc) {
      options.relative_frames = std::atoi(argv[++i]);
    } else if (arg == "--scene" && i + 1 < argc) {
      options.scene_dir = argv[++i];
    } else if (arg == "--write-scene" && i + 1 < argc) {
      ph::write_target_files(argv[i + 1], scene_targets());
      return 0;
    } else if (arg == "--trace-from" && i + 1 < argc) {
      options.trace_from = std::atol(argv[++i]);
    } else if (arg == "--session" && i + 1 < argc) {
      options.session = std::filesystem::absolute(argv[++i]).string();
    } else if (arg == "--cases" && i + 1 < argc) {
      options.cases = argv[++i];
    } else if (arg == "-v") {
      options.verbose = true;
    } else if (options.daemon.empty() && !arg.empty() && arg[0] != '-') {
      options.daemon = std::filesystem::absolute(arg).string();
    } else {
      return usage(("unexpected argument " + arg).c_str());
    }
  }
  if (options.daemon.empty()) return usage("no daemon given");
  options.scratch = own_scratch("ph-x11");
  std::printf("x11_cursor_e2e: scratch folder %s\n", options.scratch.c_str());

  int failed = 0;
  try {
    XServer x;
    const UeventMonitor uevents;
    trace(options, "writing the scene");
    const std::string regions = scene_regions(options.scene_dir.empty() ? options.scratch : options.scene_dir);
    trace(options, "scene written");
    TestMouse mouse(kMouseName);
    TestMouse untaken("ph-x11 untaken");
    const std::vector<CaseSpec> cases{
        {"absolute output", ph::OutputMode::absolute, "", options.frames, 0.5, true},
        {"relative output, X's flat profile", ph::OutputMode::relative, "flat", options.relative_frames, 1.0},
        {"relative output, X's adaptive profile (drift, measured only)", ph::OutputMode::relative, "adaptive",
         options.relative_frames, std::nullopt},
    };
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const CaseSpec& spec = cases[i];
      if (options.cases.find(static_cast<char>('a' + i)) == std::string::npos) continue;
      // The daemon's acceleration flat at speed 0 (the identity): the offline model is the plain pipeline.
      const std::filesystem::path config =
          write_config(options.scratch, std::string(1, static_cast<char>('a' + i)), spec.mode, "flat", regions);
      try {
        if (!report(spec, run_case(options, x, mouse, &untaken, uevents, config, spec))) ++failed;
      } catch (const Fatal& e) {
        std::printf("FAIL %s: %s\n", spec.label.c_str(), e.what());
        std::fflush(stdout);
        ++failed;
      }
    }
    if (!options.session.empty() && options.cases.find('e') != std::string::npos && !session_case(options, x)) {
      ++failed;
    }
    if (!options.session.empty() && options.cases.find('d') != std::string::npos) {
      const std::filesystem::path config =
          write_config(options.scratch, "d", ph::OutputMode::absolute, "adaptive", regions);
      try {
        failed += follow_cases(options, x, mouse, untaken, uevents, config);
      } catch (const Fatal& e) {
        std::printf("FAIL [d, g]: %s\n", e.what());
        ++failed;
      }
    }
    if (!options.session.empty() && options.cases.find('j') != std::string::npos) {
      failed += !outputs_case(options, x, mouse, uevents);
    }
    if (options.cases.find('f') != std::string::npos) {
      try {
        failed += !acceleration_case(options, x, mouse, uevents);
      } catch (const Fatal& e) {
        std::printf("FAIL [f]: %s\n", e.what());
        ++failed;
      }
    }
  } catch (const std::exception& e) {
    std::printf("FAIL x11_cursor_e2e: %s\n", e.what());
    return 1;
  }
  std::printf("x11_cursor_e2e: %d failed\n", failed);
  return failed > 0 ? 1 : 0;
}
