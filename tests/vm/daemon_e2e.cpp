// Run inside the VM (tests/vm/run-in-vm), as root: end-to-end checks of the real pseudohapticd. It creates
// uinput test mice, starts the daemon (argv[1]) as a child with NOTIFY_SOCKET pointing at a socket of its
// own, drives it and reads what comes out of its virtual devices. Where the daemon rescales motion, the
// expected output is what ph::Pipeline computes here for the same frames: exactly with relative output
// and no acceleration; with the default absolute output and adaptive acceleration (which depends on the
// kernel's timestamps) within 1 px (AbsoluteFollower says why). One PASS or FAIL line per case; the exit
// status is 1 when any failed.
//
//   daemon_e2e DAEMON [--tool PSEUDOHAPTIC] [--cycles N] [--latency-frames N] [--rounds N]
//              [--baseline BARE_REEMITTER] [--baseline-polls] [--profile-side daemon|bare] [--parts pfdr]
//              [--scene-dir DIR] [-v]
//
// --tool: the pseudohaptic tool for `pseudohaptic status` (default: ../tools/pseudohaptic next to the
// daemon's folder, as in the build tree); --cycles: hotplug create/destroy cycles (100); --latency-frames:
// frames per latency figure (500); --rounds: interleaved rounds of the daemon against the bare re-emitter,
// half as many frames each per round (10); --baseline: the bare re-emitter (bare_reemitter beside this
// program); --baseline-polls: the re-emitter waits in poll() before each read(), as an event loop does;
// --profile-side: [10d] times only that side's frames, between the lines "profile: begin" (then a pause of
// 3 s, for a profiler on the host to attach to the emulator) and "profile: end, N frames", and first prints
// that side's program's mappings ("profile: map ...") (for tests/vm/count-tcg-work);
// --parts: the parts to run, by letter (below; all four by default); --scene-dir: where the default scene's
// target maps are (x11_cursor_e2e --write-scene writes them on the host, faster than here; missing ones are
// written in the scratch folder); -v passes -v to
// the daemon (its debug lines are printed when a case fails) and traces the hotplug cycles.
//
// Four parts, each with a fresh daemon (or none): (p) latency of the test mouse's own node; (f) the daemon with a
// flat config file (held button at start, identity, latency, the control socket, resync through a fake
// session helper and an untaken touchpad, SIGHUP reloads, SIGTERM with a held button); (d) the daemon with the
// embedded default scene (grab exclusivity, absolute output with adaptive acceleration over a texture
// against the offline model, latency, hotplug, two mice, SYN_DROPPED, SIGTERM); (r) latency while the daemon
// reloads a full-HD region with materials and wells, against without a reload. Numbers in brackets number
// the cases; tests/vm/README.md lists them.
#include <fmt/format.h>

#include <grp.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/pipeline.hpp"
#include "core/engine/targets.hpp"
#include "tests/vm/absolute_follower.hpp"
#include "tests/vm/e2e_support.hpp"

namespace {

using namespace ph::e2e;
using ph::Frame;
namespace ev = ph::ev;

struct Options {
  std::string daemon;
  std::string tool;  // the pseudohaptic tool, for `pseudohaptic status` ("" when there is none)
  int cycles = 100;
  int latency_frames = 500;
  int rounds = 10;              // interleaved rounds of the daemon against the bare re-emitter
  std::string baseline;         // the bare re-emitter (bare_reemitter beside this program)
  bool baseline_polls = false;  // --baseline-polls: the re-emitter waits in poll() before each read()
  std::string profile_side;     // --profile-side: "daemon" or "bare": [10d] times that side alone
  std::string parts = "pfdr";   // which parts run: passthrough, flat config, default scene, reload
  bool verbose = false;         // pass -v to the daemon
  std::filesystem::path scratch;
  std::filesystem::path scene_dir;  // the default scene's target maps, if written on the host (faster)
};

// The daemon with the flat config file: relative output, gain 1, no acceleration (relative output's
// default), the 1920 x 1080 desktop the config names.
ph::PipelineConfig pipeline_config() {
  ph::PipelineConfig config;
  config.pointer_gain = 1.0;
  config.mode = ph::OutputMode::relative;
  config.desktop = {0, 0, 1920, 1080};
  return config;
}

// The daemon with --default-scene: every [daemon] setting at its default (absolute output, libinput's
// adaptive acceleration at speed 0) on the 1920 x 1080 desktop it falls back to without DRM connectors.
ph::PipelineConfig default_pipeline_config() {
  const ph::DaemonSettings defaults;
  ph::PipelineConfig config;
  config.pointer_gain = defaults.pointer_speed;
  config.mode = defaults.output;
  config.acceleration = ph::acceleration_of(defaults);
  config.desktop = {0, 0, 1920, 1080};
  return config;
}

// ---- verdicts -------------------------------------------------------------------------------------------

class Report {
 public:
  void record(const std::string& name, const Check& check, double seconds) {
    if (check.ok()) {
      ++passed_;
      std::printf("PASS %s (%.1f s): %s\n", name.c_str(), seconds, check.notes().c_str());
    } else {
      ++failed_;
      std::printf("FAIL %s (%.1f s):\n    %s\n", name.c_str(), seconds, check.failures().c_str());
      if (!check.notes().empty()) std::printf("    (%s)\n", check.notes().c_str());
    }
    std::fflush(stdout);
  }
  void not_run(const std::string& name, const std::string& why) {
    ++failed_;
    std::printf("FAIL %s: not run (%s)\n", name.c_str(), why.c_str());
    std::fflush(stdout);
  }
  int passed() const { return passed_; }
  int failed() const { return failed_; }

 private:
  int passed_ = 0, failed_ = 0;
};

// The cases run against one daemon, which the session owns. A Fatal (or any other exception) in a case
// fails it and stops the session: its later cases are reported as not run. When anything failed, the
// daemon's stderr and its sd_notify lines are printed at the end.
class Session {
 public:
  Session(Report& report, std::string title) : report_(report), title_(std::move(title)) {
    std::printf("== %s\n", title_.c_str());
    std::fflush(stdout);
  }
  ~Session() {
    if (!any_failed_ || daemon == nullptr) return;
    if (daemon->running()) {  // where it is, in case it hangs
      const std::string proc = "/proc/" + std::to_string(daemon->pid());
      std::fprintf(stderr, "---- %s: daemon still running, wchan %s, kernel stack:\n%s", title_.c_str(),
                   read_text_file(proc + "/wchan").c_str(), read_text_file(proc + "/stack").c_str());
    }
    std::fprintf(stderr, "---- %s: daemon output (%s) ----\n%s", title_.c_str(), daemon->log_path().c_str(),
                 daemon->log().c_str());
    if (notify != nullptr) {
      std::string lines;
      for (const std::string& line : notify->history()) lines += (lines.empty() ? "" : " | ") + line;
      std::fprintf(stderr, "---- %s: sd_notify lines: %s\n", title_.c_str(), lines.c_str());
    }
    std::fprintf(stderr, "---- end of %s ----\n", title_.c_str());
  }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  template <class Body>
  void run(const std::string& name, Body body) {
    if (!stopped_.empty()) {
      report_.not_run(name, stopped_);
      any_failed_ = true;
      return;
    }
    Check check;
    const auto start = Clock::now();
    try {
      body(check);
    } catch (const std::exception& e) {
      check.expect(false, e.what());
      stopped_ = "an earlier case of this daemon stopped: " + std::string(e.what());
    }
    any_failed_ = any_failed_ || !check.ok();
    report_.record(name, check, std::chrono::duration<double>(Clock::now() - start).count());
  }

 private:
  Report& report_;
  std::string title_;
  std::string stopped_;
  bool any_failed_ = false;

 public:
  // The daemon's sd_notify socket and the daemon (killed, if still running, after the output is printed).
  std::unique_ptr<NotifySocket> notify;
  std::unique_ptr<ChildProcess> daemon;
};

// With -v: a time-stamped line on stderr, for finding where time goes.
void trace(const Options& options, const std::string& what) {
  static const auto start = Clock::now();
  if (!options.verbose) return;
  std::fprintf(stderr, "[%9.3f] %s\n", std::chrono::duration<double>(Clock::now() - start).count(), what.c_str());
}

// ---- driving the daemon ------------------------------------------------------------------------------------

constexpr auto kDeviceTimeout = 10s;  // a virtual device appearing or going away

std::unique_ptr<ChildProcess> start_daemon(const Options& options, const std::vector<std::string>& args,
                                           const NotifySocket& notify, const std::string& log_name) {
  std::vector<std::string> argv{options.daemon};
  if (options.verbose) argv.emplace_back("-v");
  argv.insert(argv.end(), args.begin(), args.end());
  return std::make_unique<ChildProcess>(
      argv,
      std::vector<std::string>{"NOTIFY_SOCKET=" + notify.path(), "PATH=/usr/sbin:/usr/bin:/sbin:/bin", "LANG=C.UTF-8"},
      (options.scratch / log_name).string());
}

// Waits for READY=1 while the daemon runs: false on timeout, Fatal when it exited.
bool wait_ready(NotifySocket& notify, ChildProcess& daemon, Clock::duration timeout) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (notify.expect("READY=1", 250ms)) return true;
    if (const std::optional<int> status = daemon.wait_exit(0s)) {
      throw Fatal("the daemon exited before READY=1: " + describe_wait_status(*status));
    }
  }
  return false;
}

// Sends `in` through the test mouse and checks that what comes out of `out` is what the offline pipeline
// makes of it. Returns what came out (nullopt when nothing did, or nothing was expected).
// A test mouse that can be pulled out with a button down. TestMouse's device (a UinputSink, as the daemon's) writes
// the release of what it holds before it goes; this one writes none of its own (the kernel releases what a device
// held as it removes it, which a reader may read before the node hangs up, or not).
class UnpluggableMouse {
 public:
  explicit UnpluggableMouse(const std::string& name) {
    const ph::LibevdevPtr description = ph::describe(test_mouse_description(name));
    libevdev_uinput* raw = nullptr;
    const int rc = libevdev_uinput_create_from_device(description.get(), LIBEVDEV_UINPUT_OPEN_MANAGED, &raw);
    if (rc < 0) throw Fatal("cannot create test mouse '" + name + "': " + errno_text(-rc));
    device_.reset(raw);
    const char* node = libevdev_uinput_get_devnode(raw);
    if (node == nullptr) throw Fatal("the kernel gave no device node for test mouse '" + name + "'");
    node_ = node;
  }

  const std::string& node() const { return node_; }
  void send(const Frame& frame) {
    for (const ph::InputEvent& e : frame.events) libevdev_uinput_write_event(device_.get(), e.type, e.code, e.value);
  }
  void unplug() { device_.reset(); }

 private:
  ph::LibevdevUinputPtr device_;
  std::string node_;
};

// The last STATUS= line the daemon sent (what `systemctl status` shows), "" when none.
std::string last_status(const NotifySocket& notify) {
  const std::vector<std::string> lines = notify.history();
  const auto it =
      std::find_if(lines.rbegin(), lines.rend(), [](const std::string& l) { return l.starts_with("STATUS="); });
  return it == lines.rend() ? std::string() : *it;
}

template <class Mouse>  // TestMouse, or UnpluggableMouse
std::optional<Frame> expect_through(Check& check, Mouse& mouse, EventReader& out, ph::Pipeline& model, const Frame& in,
                                    const std::string& label) {
  const Frame expected = untimed(model.process(in));
  mouse.send(in);
  if (!delivers_something(expected)) return std::nullopt;
  std::optional<Frame> got = out.next_frame(kFrameTimeout);
  if (!got) {
    check.expect(false, fmt::format("{}: sent [{}], expected [{}], got nothing within {} s{}", label, describe(in),
                                    describe(expected), kFrameTimeout.count(), out.gone() ? " (device gone)" : ""));
    return std::nullopt;
  }
  check.expect(same_events(*got, expected), fmt::format("{}: sent [{}], expected [{}] (offline pipeline), got [{}]",
                                                        label, describe(in), describe(expected), describe(*got)));
  return got;
}

std::string keys_text(const std::vector<std::uint16_t>& keys) {
  std::string text;
  for (std::uint16_t code : keys) text += (text.empty() ? "" : ", ") + event_name({0, ev::kKey, code, 0});
  return text.empty() ? "none" : text;
}

std::string grab_text(int err) { return err == 0 ? "success" : errno_text(err); }

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path next = path.string() + ".new";
  {
    std::ofstream out(next, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out) throw Fatal("cannot write " + next.string());
  }
  std::filesystem::rename(next, path);
}

// The [daemon] table of every config here: only the test mice, the default desktop spelled out.
std::string daemon_table() {
  return "[daemon]\n"
         "devices = [\"name:ph-e2e*\"]\n"
         "output = \"relative\"\n"
         "desktop = [0, 0, 1920, 1080]\n"
         "pointer_speed = 1.0\n";
}

ph::TargetSpec target_named(const std::string& name) {
  for (const ph::TargetSpec& spec : ph::all_targets()) {
    if (spec.name() == name) return spec;
  }
  throw Fatal("no target " + name);
}

ph::TargetSpec hole_target() { return target_named("hole-polynomial-h1-r200"); }

// The daemon table and one region: the hole target's files (in the config's folder) where the default
// scene has it, at (710, 290).
std::string region_config(const ph::TargetSpec& spec) {
  std::string region = ph::target_scene_text(spec);
  const std::string at_origin = "x = 0\ny = 0\n";
  const auto pos = region.find(at_origin);
  if (pos == std::string::npos) throw Fatal("unexpected target scene text:\n" + region);
  region.replace(pos, at_origin.size(), "x = 710\ny = 290\n");
  return daemon_table() + "\n" + region;
}

// A stroke: `count` frames moving `dx` per frame (and 1 px down every fourth), with buttons, wheel and
// hi-res wheel events in some frames, and two frames without motion.
std::vector<Frame> stroke(int count, std::int32_t dx) {
  std::vector<Frame> frames;
  for (int i = 0; i < count; ++i) {
    std::vector<ph::InputEvent> events;
    if (i == 8) events.push_back(key(ev::kBtnLeft, 1));  // a button before the motion
    events.push_back(rel(ev::kRelX, dx));
    if (i % 4 == 3) events.push_back(rel(ev::kRelY, 1));
    if (i == 3) events.push_back(key(ev::kBtnLeft, 1));
    if (i == 6) events.push_back(key(ev::kBtnLeft, 0));
    if (i == 10) events.insert(events.end(), {rel(ev::kRelWheel, 1), rel(ev::kRelWheelHiRes, 120)});
    if (i == 14) events.push_back(key(ev::kBtnLeft, 0));
    if (i == 17) events.insert(events.end(), {rel(ev::kRelHWheel, -1), rel(ev::kRelHWheelHiRes, -120)});
    if (i == 21) events.push_back(rel(ev::kRelWheelHiRes, -40));
    if (i == 24) events.insert(events.end(), {key(ev::kBtnRight, 1), key(ev::kBtnMiddle, 1)});
    if (i == 25) events.push_back(key(ev::kBtnRight, 0));
    frames.push_back(make_frame(std::move(events)));
    if (i == 26) {
      frames.push_back(make_frame({key(ev::kBtnMiddle, 0)}));
      frames.push_back(make_frame({rel(ev::kRelWheel, -1), rel(ev::kRelWheelHiRes, -120)}));
    }
  }
  return frames;
}

struct StrokeResult {
  std::vector<std::pair<Frame, Frame>> frames;  // sent, came out
  int differing = 0;                            // frames that came out changed
};

StrokeResult run_stroke(Check& check, TestMouse& mouse, EventReader& out, ph::Pipeline& model,
                        const std::vector<Frame>& frames, const std::string& label) {
  StrokeResult result;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::optional<Frame> got =
        expect_through(check, mouse, out, model, frames[i], fmt::format("{} frame {}", label, i));
    if (!got) continue;
    result.frames.emplace_back(frames[i], *got);
    if (!same_events(*got, frames[i])) ++result.differing;
  }
  return result;
}

// Connects to the control socket from a child process running as uid and gid 65534 (nobody) and returns
// the child's pid and the first line the daemon sent it (or what went wrong).
std::pair<pid_t, std::string> first_line_as_nobody(const std::string& socket_path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (socket_path.size() >= sizeof address.sun_path) throw Fatal("socket path too long: " + socket_path);
  std::memcpy(address.sun_path, socket_path.c_str(), socket_path.size() + 1);
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) throw Fatal("pipe: " + errno_text(errno));
  const Fd read_end(ends[0]);
  Fd write_end(ends[1]);
  const pid_t pid = ::fork();
  if (pid < 0) throw Fatal("fork: " + errno_text(errno));
  if (pid == 0) {  // only async-signal-safe calls from here
    const auto say = [&](const char* text, std::size_t size) {
      [[maybe_unused]] const ssize_t n = ::write(write_end.get(), text, size);
    };
    if (::setgroups(0, nullptr) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0) {
      say("(setuid failed)", 15);
      ::_exit(1);
    }
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0 || ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      say("(connect failed)", 16);
      ::_exit(1);
    }
    char buffer[512];
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 10000) <= 0) {
      say("(nothing within 10 s)", 21);
      ::_exit(1);
    }
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n > 0) say(buffer, static_cast<std::size_t>(n));
    ::_exit(0);
  }
  write_end.reset();  // the child's end: the read below ends when the child does
  std::string got;
  char buffer[512];
  pollfd p{read_end.get(), POLLIN, 0};
  while (::poll(&p, 1, 15000) > 0) {
    const ssize_t n = ::read(read_end.get(), buffer, sizeof buffer);
    if (n <= 0) break;
    got.append(buffer, static_cast<std::size_t>(n));
  }
  ::waitpid(pid, nullptr, 0);
  if (const std::size_t end = got.find('\n'); end != std::string::npos) got.resize(end);
  return {pid, got};
}

// ---- absolute output with the daemon's acceleration ---------------------------------------------------------

struct AbsoluteStroke {
  std::vector<std::pair<Frame, Frame>> frames;  // sent, came out
  int apart = 0;                                // frames whose pixel is 2 px or more from the empty scene's
  double max_apart_px = 0.0;
};

// The stroke at a mouse's 125 Hz (a frame every 8 ms, so that the adaptive acceleration sees a hand's
// speed), each frame through `follower`; `shadow` is an offline pipeline over an empty scene fed the same
// frames: where the emitted pixel is 2 px or more from its pixel, the texture moved the cursor, not the
// timing (the emitted pixel is within 1 px of the model).
AbsoluteStroke run_absolute_stroke(Check& check, AbsoluteFollower& follower, TestMouse& mouse, EventReader& out,
                                   ph::Pipeline& shadow, const std::vector<Frame>& frames, const std::string& label) {
  AbsoluteStroke result;
  auto next = Clock::now();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    std::this_thread::sleep_until(next);
    next = std::max(next + 8ms, Clock::now());
    const std::optional<Frame> got =
        follower.through(check, mouse, out, frames[i], fmt::format("{} frame {}", label, i), &shadow);
    if (!got) continue;
    result.frames.emplace_back(frames[i], *got);
    const std::optional<std::int32_t> x = value_in(*got, ev::kAbs, ev::kAbsX), y = value_in(*got, ev::kAbs, ev::kAbsY);
    const ph::Texel flat = ph::texel_at(shadow.cursor().position);
    const double dx = x ? std::abs((*x - 1) / ph::kAbsUnitsPerPixel - flat.x) : 0.0;
    const double dy = y ? std::abs((*y - 1) / ph::kAbsUnitsPerPixel - flat.y) : 0.0;
    result.max_apart_px = std::max({result.max_apart_px, dx, dy});
    if (dx >= 2 || dy >= 2) ++result.apart;
  }
  return result;
}

// ---- latency ----------------------------------------------------------------------------------------------

struct Latency {
  std::string label;
  std::vector<double> us;  // write into the test mouse -> read from the output node
  int skipped = 0;         // frames the pipeline turned into nothing (no output to wait for)
};

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::clamp<std::size_t>(rank, 1, values.size()) - 1];
}

std::string latency_text(const Latency& l) {
  return fmt::format("median {:.0f} us, p99 {:.0f} us, max {:.0f} us over {} frames{}", percentile(l.us, 0.5),
                     percentile(l.us, 0.99), l.us.empty() ? 0.0 : *std::max_element(l.us.begin(), l.us.end()),
                     l.us.size(), l.skipped > 0 ? fmt::format(" ({} without output skipped)", l.skipped) : "");
}

// One motion frame at a time (REL_X +4 and -4 in turn, so the cursor stays put): from just before
// writing it into the test mouse to just after reading it from `out`. With a model, the output must be
// what the model computes.
void time_frames(Check& check, TestMouse& mouse, EventReader& out, ph::Pipeline* model, int frames, Latency& result) {
  for (int i = 0; i < frames; ++i) {
    const Frame in = make_frame({rel(ev::kRelX, i % 2 == 0 ? 4 : -4)});
    const Frame expected = model != nullptr ? untimed(model->process(in)) : in;
    const auto start = Clock::now();
    mouse.send(in);
    if (!delivers_something(expected)) {
      ++result.skipped;
      continue;
    }
    const std::optional<Frame> got = out.next_frame(kFrameTimeout);
    const auto end = Clock::now();
    if (!got) throw Fatal(fmt::format("latency frame {}: nothing came out within {} s", i, kFrameTimeout.count()));
    if (!check.expect(same_events(*got, expected), fmt::format("latency frame {}: expected [{}], got [{}]", i,
                                                               describe(expected), describe(*got)))) {
      continue;
    }
    result.us.push_back(std::chrono::duration<double, std::micro>(end - start).count());
  }
}

void measure_latency(Check& check, TestMouse& mouse, EventReader& out, ph::Pipeline* model, int frames,
                     Latency& result) {
  time_frames(check, mouse, out, model, frames, result);
  check.note(latency_text(result));
}

// The daemon's latency as ratios to the bare re-emitter's (tests/vm/bare_reemitter.cpp), both running
// in this boot, in rounds that alternate which goes first, so that the host's load falls on both alike.
struct LatencyRatio {
  Latency daemon{"daemon, flat scene (interleaved rounds)", {}, 0};
  Latency bare{"bare re-emitter (interleaved rounds)", {}, 0};
  std::vector<double> round_ratios;  // median over median, per round

  double median_ratio() const { return percentile(daemon.us, 0.5) / percentile(bare.us, 0.5); }
  double p99_ratio() const { return percentile(daemon.us, 0.99) / percentile(bare.us, 0.99); }
  std::string text() const {
    if (daemon.us.empty() || bare.us.empty()) return "not measured";
    const auto [lo, hi] = std::minmax_element(round_ratios.begin(), round_ratios.end());
    return fmt::format(
        "median ratio {:.3f}, p99 ratio {:.3f} (daemon: {}; bare: {}); per-round median ratios "
        "{:.2f}..{:.2f} over {} rounds",
        median_ratio(), p99_ratio(), latency_text(daemon), latency_text(bare), *lo, *hi, round_ratios.size());
  }
};

void measure_against_bare(Check& check, TestMouse& mouse, EventReader& out, ph::Pipeline& model, TestMouse& bare_mouse,
                          EventReader& bare_out, const Options& options, pid_t profiled, LatencyRatio& result) {
  const int frames = std::max(2, options.latency_frames / 2);
  const bool profiling = !options.profile_side.empty();
  if (profiling) {  // the profiled program's mappings first, to tell its pages from everyone else's
    std::ifstream maps(fmt::format("/proc/{}/maps", profiled));
    for (std::string line; std::getline(maps, line);) std::printf("profile: map %s\n", line.c_str());
    std::printf("profile: begin\n");
    std::this_thread::sleep_for(3s);
  }
  for (int round = 0; round < options.rounds; ++round) {
    Latency daemon, bare;
    for (int side = 0; side < 2; ++side) {
      const bool daemon_side = (side + round) % 2 == 0;
      if (profiling && options.profile_side != (daemon_side ? "daemon" : "bare")) continue;
      if (daemon_side) {
        time_frames(check, mouse, out, &model, frames, daemon);
      } else {
        time_frames(check, bare_mouse, bare_out, nullptr, frames, bare);
      }
    }
    result.round_ratios.push_back(percentile(daemon.us, 0.5) / percentile(bare.us, 0.5));
    result.daemon.us.insert(result.daemon.us.end(), daemon.us.begin(), daemon.us.end());
    result.bare.us.insert(result.bare.us.end(), bare.us.begin(), bare.us.end());
  }
  if (profiling) std::printf("profile: end, %zu frames\n", result.daemon.us.size() + result.bare.us.size());
  check.note(result.text());
}

// The same through a daemon with absolute output: frames whose output was not waited for at once (the
// follower asked the daemon's model first) count as skipped.
void measure_latency_absolute(Check& check, TestMouse& mouse, EventReader& out, AbsoluteFollower& follower, int frames,
                              Latency& result) {
  for (int i = 0; i < frames; ++i) {
    const Frame in = make_frame({rel(ev::kRelX, i % 2 == 0 ? 4 : -4)});
    const std::optional<Frame> got = follower.through(check, mouse, out, in, fmt::format("latency frame {}", i));
    if (!follower.timed()) {
      ++result.skipped;
      continue;
    }
    if (got) result.us.push_back(follower.last_us());
  }
  check.note(latency_text(result));
}

// ---- part 1: no daemon -------------------------------------------------------------------------------------

void passthrough_part(Report& report, const Options& options, Latency& latency) {
  Session session(report, "no daemon: the test mouse's own node");
  session.run("[10a] latency, passthrough (no daemon)", [&](Check& check) {
    TestMouse mouse("ph-e2e passthrough");
    EventReader own(mouse.node());
    measure_latency(check, mouse, own, nullptr, options.latency_frames, latency);
  });
}

// ---- part 2: a config file with a flat scene ---------------------------------------------------------------

void flat_part(Report& report, const Options& options, Latency& latency, LatencyRatio& ratio) {
  Session session(report, "daemon with a flat config file (-c)");
  const UeventMonitor uevents;
  const std::filesystem::path config = options.scratch / "daemon.toml";
  const std::string virtual_name = "pseudohaptic ph-e2e mouse";
  std::optional<TestMouse> mouse;
  std::optional<EventReader> own, out;  // the test mouse's own node; the virtual device
  std::unique_ptr<NotifySocket>& notify = session.notify;
  std::unique_ptr<ChildProcess>& daemon = session.daemon;
  ph::Pipeline model(std::make_shared<const ph::Scene>(), pipeline_config());
  const ph::TargetSpec hole = hole_target();
  const std::string control_path = (options.scratch / "control-flat").string();
  std::optional<ph::control::Client> control;
  std::optional<FakeHelper> helper;
  std::optional<TestTouchpad> touchpad;

  session.run("[5] button held at start: no grab until it is released", [&](Check& check) {
    ph::write_target_files(options.scratch, {hole});  // for the reload below
    write_file_atomically(config, daemon_table());
    mouse.emplace("ph-e2e mouse");
    own.emplace(mouse->node());
    const Frame press = make_frame({key(ev::kBtnLeft, 1)}), release = make_frame({key(ev::kBtnLeft, 0)});
    mouse->send(press);
    const std::optional<Frame> pressed = own->next_frame(kFrameTimeout);
    if (!pressed || !same_events(*pressed, press)) throw Fatal("the press did not come out of the test mouse's node");
    notify = std::make_unique<NotifySocket>((options.scratch / "notify-flat.sock").string());
    daemon = start_daemon(options, {"-c", config.string(), "--control", control_path}, *notify, "daemon-flat.log");
    // READY=1 may come before the grab (the mouse is waited for) or only after it.
    bool ready = wait_ready(*notify, *daemon, 5s);
    const bool ready_while_held = ready;
    if (!daemon->running()) throw Fatal("the daemon exited: " + describe_wait_status(*daemon->wait_exit(0s)));
    const std::string early = wait_for_device(virtual_name, ready ? 1500ms : 0ms, uevents);
    check.expect(early.empty(), "expected no virtual device while BTN_LEFT is held, got " + early);
    const std::vector<ph::InputEvent> meanwhile = own->read_now();
    check.expect(meanwhile.empty(), fmt::format("expected nothing more on the test mouse's node before the release, "
                                                "got {} events",
                                                meanwhile.size()));
    mouse->send(release);
    const std::optional<Frame> released = own->next_frame(kFrameTimeout);
    check.expect(released && same_events(*released, release),
                 "expected the release on the test mouse's own node (not grabbed yet), got [" +
                     (released ? describe(*released) : std::string("nothing")) + "]");
    const std::string node = wait_for_device(virtual_name, kDeviceTimeout, uevents);
    if (node.empty()) throw Fatal("no virtual device '" + virtual_name + "' within 10 s of the release");
    out.emplace(node);
    if (!wait_taken(*mouse, *out, kDeviceTimeout)) throw Fatal("nothing came out of " + node + " within 10 s");
    own->read_now();  // wheel notches sent before the grab went to the other readers only
    if (!ready) ready = notify->expect("READY=1", kDeviceTimeout);
    check.expect(ready, "expected READY=1 from the daemon, got none");
    expect_through(check, *mouse, *out, model, make_frame({rel(ev::kRelX, 4), rel(ev::kRelY, 2)}), "after the grab");
    const std::vector<ph::InputEvent> leaked = own->read_now();
    check.expect(
        leaked.empty(),
        fmt::format("expected nothing on the test mouse's own node after the grab, got {} events", leaked.size()));
    check.note(
        fmt::format("READY=1 {}; no virtual device while held; press and release seen by another reader of the "
                    "mouse; then taken, motion came out of {} and not of the mouse's node",
                    ready_while_held ? "while the button was held" : "after the release", node));
  });

  session.run("[2] flat scene: frames come out unchanged", [&](Check& check) {
    const std::vector<Frame> frames = {
        make_frame({rel(ev::kRelX, 3), rel(ev::kRelY, -2)}),
        make_frame({key(ev::kBtnLeft, 1)}),
        make_frame({rel(ev::kRelX, -7), rel(ev::kRelY, 11), key(ev::kBtnLeft, 0)}),
        make_frame({rel(ev::kRelWheel, 1), rel(ev::kRelWheelHiRes, 120)}),
        make_frame({rel(ev::kRelHWheel, -1), rel(ev::kRelHWheelHiRes, -120)}),
        make_frame({rel(ev::kRelX, 1), key(ev::kBtnRight, 1), rel(ev::kRelWheel, -1), rel(ev::kRelWheelHiRes, -120)}),
        make_frame({key(ev::kBtnRight, 0), key(ev::kBtnMiddle, 1)}),
        make_frame({key(ev::kBtnMiddle, 0), rel(ev::kRelY, 5)}),
        make_frame({rel(ev::kRelWheelHiRes, 30)}),
        make_frame({rel(ev::kRelHWheelHiRes, 45)}),
        make_frame({rel(ev::kRelX, 100), rel(ev::kRelY, -100)}),
        make_frame({rel(ev::kRelX, -100), rel(ev::kRelY, 100), key(ev::kBtnLeft, 1), key(ev::kBtnRight, 1)}),
        make_frame({key(ev::kBtnLeft, 0), key(ev::kBtnRight, 0), rel(ev::kRelY, -1)}),
    };
    int same = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ph::Pipeline probe = model;  // the offline pipeline agrees that a flat scene changes nothing
      check.expect(same_events(probe.process(frames[i]), frames[i]),
                   fmt::format("frame {}: offline pipeline not identity", i));
      const std::optional<Frame> got =
          expect_through(check, *mouse, *out, model, frames[i], fmt::format("frame {}", i));
      if (got && same_events(*got, frames[i])) ++same;
    }
    check.expect(own->read_now().empty(), "expected nothing on the grabbed test mouse's own node");
    check.note(fmt::format("{} of {} frames (motion, buttons, wheel, hi-res wheel) came out unchanged, in order", same,
                           frames.size()));
  });

  // A mouse pulled out mid-drag: its virtual device releases the button and stays 50 ms for the desktop to read the
  // release. The daemon must not wait that long under the lock the other mice's readers take, or their frames wait
  // too (at 8 kHz a mouse's kernel buffer overflows in that time). The bar, 40 ms, is the wait's less what the
  // emulator may add to a frame now and then (frames here take 0.1 ms, the worst a few ms).
  session.run(
      "[6] a mouse unplugged with a button held: the release comes out, the other mouse's frames do not wait",
      [&](Check& check) {
        const std::string name = "ph-e2e mouse unplugged mid-drag", virtual_name = "pseudohaptic " + name;
        UnpluggableMouse dragging(name);
        const std::string node = wait_for_device(virtual_name, kDeviceTimeout, uevents);
        if (node.empty()) throw Fatal("no virtual device '" + virtual_name + "'");
        EventReader dragged(node);
        if (!wait_taken(dragging, dragged, kDeviceTimeout)) throw Fatal("nothing came out of " + node + " within 10 s");
        expect_through(check, dragging, dragged, model, make_frame({key(ev::kBtnLeft, 1)}), "the press");
        // The desktop's side: reads the virtual device until it goes, as a compositor does.
        std::vector<ph::InputEvent> after_unplug;
        std::jthread desktop([&] {
          const auto deadline = Clock::now() + kDeviceTimeout;
          while (!dragged.gone() && Clock::now() < deadline) {
            if (std::optional<Frame> frame = dragged.next_frame(100ms))
              after_unplug.insert(after_unplug.end(), frame->events.begin(), frame->events.end());
          }
        });
        dragging.unplug();
        std::vector<double> round_trip_ms;
        const auto until = Clock::now() + 300ms;
        for (int i = 0; Clock::now() < until; ++i) {
          const auto sent = Clock::now();
          const Frame frame = make_frame({rel(ev::kRelX, i % 2 == 0 ? 1 : -1)});
          if (!expect_through(check, *mouse, *out, model, frame, fmt::format("other mouse, frame {}", i))) break;
          round_trip_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
        }
        desktop.join();
        const bool released = std::any_of(after_unplug.begin(), after_unplug.end(), [](const ph::InputEvent& e) {
          return e.type == ev::kKey && e.code == ev::kBtnLeft && e.value == 0;
        });
        check.expect(released, "expected BTN_LEFT 0 from the unplugged mouse's virtual device before it went, got [" +
                                   describe(Frame{after_unplug}) + "]");
        check.expect(dragged.gone(), "the unplugged mouse's virtual device stayed 10 s");
        check.expect(!round_trip_ms.empty(), "no frame of the other mouse came through after the unplug");
        if (round_trip_ms.empty()) return;
        std::vector<double> sorted = round_trip_ms;
        std::sort(sorted.begin(), sorted.end());
        const double worst = sorted.back(), median = sorted[sorted.size() / 2];
        check.expect(worst < 40.0,
                     fmt::format("a frame of the other mouse took {:.1f} ms while the daemon let go of the "
                                 "unplugged one (bar: under 40 ms; the virtual device's 50 ms for its readers "
                                 "must not hold up the other mice)",
                                 worst));
        check.note(
            fmt::format("BTN_LEFT 0 came out of {} before it went; the other mouse's {} frames in the "
                        "300 ms after the unplug took {:.2f} ms (median), {:.2f} ms at worst",
                        node, round_trip_ms.size(), median, worst));
      });

  session.run("[10b] latency, daemon over a flat scene",
              [&](Check& check) { measure_latency(check, *mouse, *out, &model, options.latency_frames, latency); });

  session.run("[10d] latency, daemon over a flat scene against a bare re-emitter", [&](Check& check) {
    // Its mouse is not one the daemon takes, and the daemon passes over its own name prefix: the daemon
    // only watches that mouse, and the grab keeps the mouse's events from it.
    TestMouse bare_mouse("ph-bare mouse");
    const std::string bare_name = "pseudohaptic bare re-emitter";
    std::vector<std::string> bare_argv{options.baseline, bare_mouse.node(), bare_name};
    if (options.baseline_polls) bare_argv.emplace_back("poll");
    ChildProcess bare(bare_argv, {}, (options.scratch / "bare.log").string());
    const std::string node = wait_for_device(bare_name, kDeviceTimeout, uevents);
    if (node.empty()) throw Fatal("no '" + bare_name + "' device within 10 s: " + bare.log());
    EventReader bare_out(node);
    if (!wait_taken(bare_mouse, bare_out, kDeviceTimeout)) throw Fatal("nothing came out of the bare re-emitter");
    measure_against_bare(check, *mouse, *out, model, bare_mouse, bare_out, options,
                         options.profile_side == "bare" ? bare.pid() : daemon->pid(), ratio);
  });

  session.run("[11] control socket: `pseudohaptic status` reports the mouse taken and the output", [&](Check& check) {
    control.emplace(control_path);
    const ph::control::Reply reply = control->request("status", 10s);
    const std::optional<ph::control::Status> status =
        reply.ok ? ph::control::parse_status(reply.text) : std::optional<ph::control::Status>{};
    check.expect(status && !status->absolute && status->mice == 1 && status->regions == 0 && !status->helper &&
                     status->desktop == ph::Rect{0, 0, 1920, 1080} && status->cursor == model.cursor().position,
                 fmt::format("expected relative output, 1 mouse, 0 regions, no helper, desktop 1920x1080, cursor "
                             "({}, {}); got: {}",
                             model.cursor().position.x, model.cursor().position.y, reply.text));
    if (options.tool.empty()) {
      check.note("no pseudohaptic tool found (--tool); 'status' over the socket: " + reply.text);
      return;
    }
    ChildProcess tool({options.tool, "status", "--socket", control_path}, {"PATH=/usr/bin:/bin", "LANG=C.UTF-8"},
                      (options.scratch / "tool-status.log").string());
    const std::optional<int> exit = tool.wait_exit(30s);
    const std::string said = tool.log();
    check.expect(exit && WIFEXITED(*exit) && WEXITSTATUS(*exit) == 0,
                 "pseudohaptic status: " + (exit ? describe_wait_status(*exit) : "still running after 30 s") +
                     ", said: " + said);
    const std::string cursor_line =
        fmt::format("cursor:  {:.2f},{:.2f}", model.cursor().position.x, model.cursor().position.y);
    for (const std::string& line : {std::string("output:  relative"), std::string("mice:    1 taken"), cursor_line,
                                    std::string("helper:  none")}) {
      check.expect(said.find(line) != std::string::npos,
                   "expected '" + line + "' in what pseudohaptic status printed:\n" + said);
    }
    std::string one_line = said;
    std::replace(one_line.begin(), one_line.end(), '\n', ';');
    check.note("pseudohaptic status printed: " + one_line);
  });

  session.run("[11] control socket: `cursor` equals the offline model after a stroke", [&](Check& check) {
    const StrokeResult result =
        run_stroke(check, *mouse, *out, model, stroke(16, -9), "stroke");  // 16: BTN_LEFT pressed and released again
    const ph::Vec2 at = daemon_cursor(*control);
    check.expect(at == model.cursor().position,
                 fmt::format("expected 'cursor' to answer ({}, {}) (the offline model), got ({}, {})",
                             model.cursor().position.x, model.cursor().position.y, at.x, at.y));
    check.note(fmt::format("after {} frames the daemon's model is at ({}, {}), the offline model's exactly",
                           result.frames.size(), at.x, at.y));
  });

  session.run("[11] control socket: `position X Y` from a client moves the model", [&](Check& check) {
    const ph::Vec2 to{1915.25, 300.75};  // 4.75 px from the right edge: the next frames show where the model is
    const ph::control::Reply reply =
        control->request(ph::control::format_request(ph::control::PositionRequest{to}), 10s);
    check.expect(reply.ok, "expected ok to 'position', got: " + reply.text);
    model.move_cursor_to(to);
    const ph::Vec2 at = daemon_cursor(*control);
    check.expect(at == to, fmt::format("expected 'cursor' to answer ({}, {}), got ({}, {})", to.x, to.y, at.x, at.y));
    const Frame push = make_frame({rel(ev::kRelX, 10), rel(ev::kRelY, 2)});
    // Relative output passes the push on unchanged (the desktop stops its own cursor at the edge), but
    // the model stops at the edge: coming back 30 px leaves it left of 1890, not at 1895.25.
    expect_through(check, *mouse, *out, model, push, "push against the edge");
    expect_through(check, *mouse, *out, model, make_frame({rel(ev::kRelX, -30)}), "back from the edge");
    const ph::Vec2 after = daemon_cursor(*control);
    check.expect(after == model.cursor().position && after.x < 1890,
                 fmt::format("after two frames: expected ({}, {}) (stopped at the right edge), got ({}, {})",
                             model.cursor().position.x, model.cursor().position.y, after.x, after.y));
    check.note(
        fmt::format("moved to ({}, {}); after [REL_X 10, REL_Y 2] into the right edge and [REL_X -30] at "
                    "({}, {}), as the offline model moved there",
                    to.x, to.y, after.x, after.y));
  });

  session.run("[11] control socket: a client that is not root is refused and logged", [&](Check& check) {
    const std::size_t log_before = daemon->log().size();
    const auto [pid, line] = first_line_as_nobody(control_path);
    const std::string expected = "error permission denied: uid 65534";
    check.expect(line.rfind(expected, 0) == 0, "expected '" + expected + " ...' as uid 65534, got: " + line);
    std::string said;
    const std::string logged = fmt::format("refused pid {}", pid);
    check.expect(wait_until(
                     [&] {
                       said = daemon->log().substr(std::min(log_before, daemon->log().size()));
                       return said.find(logged) != std::string::npos;
                     },
                     5s),
                 "expected '" + logged + "' in the daemon's log, got: " + said);
    check.expect(daemon_cursor(*control) == model.cursor().position, "root's connection stopped answering");
    while (!said.empty() && said.back() == '\n') said.pop_back();
    check.note("uid 65534 got \"" + line + "\"; the daemon logged \"" + said + "\"");
  });

  session.run("[11] control socket: a second pseudohapticd on it exits 1 and leaves it to the running one",
              [&](Check& check) {
                const std::filesystem::path flat = options.scratch / "second.toml";
                write_file_atomically(flat, "");
                ChildProcess second({options.daemon, "-c", flat.string(), "--control", control_path},
                                    {"PATH=/usr/sbin:/usr/bin:/sbin:/bin", "LANG=C.UTF-8"},
                                    (options.scratch / "daemon-second.log").string());
                const std::optional<int> exit = second.wait_exit(30s);
                const std::string said = second.log();
                check.expect(exit && WIFEXITED(*exit) && WEXITSTATUS(*exit) == 1,
                             "the second daemon: expected exit 1, got " +
                                 (exit ? describe_wait_status(*exit) : std::string("still running after 30 s")) +
                                 "; it said: " + said);
                check.expect(said.find("another pseudohapticd answers there") != std::string::npos,
                             "expected the second daemon to say another one answers on the socket; it said: " + said);
                check.expect(std::filesystem::is_socket(control_path), "the control socket is gone");
                ph::control::Client fresh(control_path);
                const ph::control::Reply reply = fresh.request("status", 10s);
                check.expect(reply.ok && daemon_cursor(*control) == model.cursor().position,
                             "the running daemon stopped answering on its socket: " + reply.text);
                const std::size_t at = said.rfind('\n', said.find("another pseudohapticd"));
                const std::string line = said.substr(at == std::string::npos ? 0 : at + 1);
                check.note("the second daemon exited 1 saying \"" + line.substr(0, line.find('\n')) +
                           "\"; the running one answers a new connection");
              });

  session.run(
      "[12] resync: an untaken touchpad's motion queries the helper within 200 ms; the model goes to "
      "its point",
      [&](Check& check) {
        helper.emplace(control_path);
        touchpad.emplace("ph-e2e touchpad");
        if (!wait_until([&] { return process_has_open(daemon->pid(), touchpad->node()); }, kDeviceTimeout, &uevents)) {
          throw Fatal("the daemon did not open the touchpad " + touchpad->node() + " within 10 s");
        }
        check.expect(try_grab(touchpad->node()) == 0, "the daemon grabbed the touchpad");
        const ph::Vec2 point{40.5, 1060.5};  // a pixel the daemon never emitted, near the bottom-left corner
        helper->answer_with(point);
        std::vector<double> delays_ms;
        for (int k = 0; k < 5; ++k) {
          // Other phases of the 1 s timer; the settle query of the frame before has come by then. The daemon
          // asks at most every 50 ms: right after a query, a frame would wait for the settle query.
          std::this_thread::sleep_for(std::chrono::milliseconds(300 + 70 * k));
          wait_until(
              [&] {
                const std::optional<Clock::time_point> last = helper->last_query();
                return !last || Clock::now() - *last >= 60ms;
              },
              1s);
          std::vector<ph::InputEvent> events{abs_event(ev::kAbsX, 100 + 10 * k), abs_event(ev::kAbsY, 200 + k)};
          if (k == 0) events.insert(events.end(), {key(BTN_TOUCH, 1), key(BTN_TOOL_FINGER, 1)});
          const auto sent = Clock::now();
          touchpad->send(make_frame(events));
          const std::optional<Clock::time_point> query = helper->query_after(sent, 2s);
          if (!check.expect(query.has_value(), fmt::format("touchpad frame {}: no query within 2 s", k))) break;
          delays_ms.push_back(std::chrono::duration<double, std::milli>(*query - sent).count());
          check.expect(delays_ms.back() <= 200,
                       fmt::format("touchpad frame {}: the query came {:.0f} ms later", k, delays_ms.back()));
        }
        // Moving steadily: a query at most every 50 ms, and one more 100 ms after the motion stops.
        const auto start = Clock::now();
        auto stopped = start;  // when the last frame was sent: the daemon cannot have read it before
        for (int k = 0; k < 30; ++k) {
          stopped = Clock::now();
          touchpad->send(make_frame({abs_event(ev::kAbsX, 300 + 5 * k)}));
          std::this_thread::sleep_for(10ms);
        }
        const int during = helper->queries_between(start, stopped);
        // The settle query comes at least 100 ms after the daemon read the last frame, so after stopped + 90 ms,
        // where the queries of the motion (at most one per 50 ms, each right after a frame) have all come. Measured
        // from the end of the last sleep instead, a sleep that overran under the VM's emulation could put the
        // settle query before the window, and the test took the 1 s query after it for the settle query.
        const std::optional<Clock::time_point> settle = helper->query_after(stopped + 90ms, 2s);
        const double settle_ms = settle ? std::chrono::duration<double, std::milli>(*settle - stopped).count() : -1.0;
        const double moving_ms = std::chrono::duration<double, std::milli>(stopped - start).count();
        check.expect(during >= 1 && during <= static_cast<int>(moving_ms / 50) + 2,
                     fmt::format("{} queries while the touchpad moved for {:.0f} ms (at most one per 50 ms)", during,
                                 moving_ms));
        check.expect(settle && settle_ms <= 400,
                     fmt::format("expected a query 100-400 ms after the touchpad stopped, got {:.0f} ms", settle_ms));
        touchpad->send(make_frame({key(BTN_TOUCH, 0), key(BTN_TOOL_FINGER, 0)}));
        const bool moved = wait_until([&] { return daemon_cursor(*control) == point; }, 2s);
        helper->answer_with(std::nullopt);
        const ph::Vec2 at = daemon_cursor(*control);
        check.expect(moved, fmt::format("expected the model at the helper's ({}, {}), got ({}, {})", point.x, point.y,
                                        at.x, at.y));
        model.move_cursor_to(point);
        // The mouse's next frames start there: the corner shortens them.
        const std::optional<Frame> got = expect_through(
            check, *mouse, *out, model, make_frame({rel(ev::kRelX, -60), rel(ev::kRelY, 30)}), "into the corner");
        std::string delays;
        for (double d : delays_ms) delays += fmt::format("{}{:.0f}", delays.empty() ? "" : ", ", d);
        check.note(
            fmt::format("queries {} ms after the touchpad's frames; {} queries in {:.0f} ms of steady "
                        "motion, one {:.0f} ms after it stopped; the model moved to ({}, {}); the "
                        "mouse's [REL_X -60, REL_Y 30] then came out as [{}], as from there",
                        delays, during, moving_ms, settle_ms, point.x, point.y, got ? describe(*got) : "nothing"));
      });

  session.run("[12] resync: a report of a pixel the daemon just emitted leaves the model alone", [&](Check& check) {
    // The pixels the cursor was on: where an absolute device puts it, floor(x), floor(y). From the corner
    // the model stops on whole x coordinates, a pixel's left edge, where the traversal's texel is still
    // the pixel to the left: the report names the pixel, not that texel.
    std::vector<ph::Texel> emitted;
    for (int i = 0; i < 6; ++i) {
      expect_through(check, *mouse, *out, model, make_frame({rel(ev::kRelX, 7), rel(ev::kRelY, -5)}),
                     fmt::format("frame {}", i));
      emitted.push_back(ph::texel_at(model.cursor().position));
    }
    const ph::Vec2 before = model.cursor().position;
    const auto report = [&](ph::Vec2 point, int frame) {
      const int answered = helper->answers();
      helper->answer_with(point);
      const auto sent = Clock::now();
      touchpad->send(make_frame({abs_event(ev::kAbsX, 500 + frame), abs_event(ev::kAbsY, 600 + frame)}));
      const bool asked =
          helper->query_after(sent, 2s).has_value() && wait_until([&] { return helper->answers() > answered; }, 2s);
      check.expect(asked, "no query answered after the touchpad moved");
      std::this_thread::sleep_for(100ms);  // the answer is read before a later request anyway; be sure
    };
    std::string kept_text;
    for (const auto& [pixel, when] : {std::pair{emitted[5], "the pixel the cursor is on"},
                                      std::pair{emitted[1], "a pixel it was on 4 frames before"}}) {
      const ph::Vec2 centre{pixel.x + 0.5, pixel.y + 0.5};
      report(centre, static_cast<int>(kept_text.size()));
      const ph::Vec2 kept = daemon_cursor(*control);
      check.expect(kept == before,
                   fmt::format("reported ({}, {}), {}: expected the model to stay at ({}, {}), got ({}, {})", centre.x,
                               centre.y, when, before.x, before.y, kept.x, kept.y));
      kept_text += fmt::format("{}({}, {}), {}", kept_text.empty() ? "" : "; ", centre.x, centre.y, when);
    }
    const ph::Vec2 elsewhere{1500.5, 200.5};
    report(elsewhere, 100);
    const bool moved = wait_until([&] { return daemon_cursor(*control) == elsewhere; }, 2s);
    helper->answer_with(std::nullopt);
    check.expect(moved, fmt::format("a pixel the daemon did not emit, ({}, {}), did not move the model", elsewhere.x,
                                    elsewhere.y));
    model.move_cursor_to(elsewhere);
    check.note(fmt::format("{}: the model stayed at ({}, {}); ({}, {}) moved it there", kept_text, before.x, before.y,
                           elsewhere.x, elsewhere.y));
  });

  session.run("[12] resync: motion after a pause of more than 300 ms queries the helper", [&](Check& check) {
    std::vector<double> delays_ms, held_ms;
    int during_burst = 0;
    for (int k = 0; k < 3; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(400 + 150 * k));
      const auto sent = Clock::now();
      expect_through(check, *mouse, *out, model, make_frame({rel(ev::kRelX, k % 2 == 0 ? 5 : -5)}), "after a pause");
      // The helper does not answer: the frame waited the daemon's 30 ms for it.
      held_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
      check.expect(held_ms.back() >= 29,
                   fmt::format("pause {}: the frame came out after {:.1f} ms, not held for the helper's answer", k,
                               held_ms.back()));
      const std::optional<Clock::time_point> query = helper->query_after(sent, 2s);
      if (!check.expect(query.has_value(), fmt::format("pause {}: no query within 2 s of the motion", k))) continue;
      delays_ms.push_back(std::chrono::duration<double, std::milli>(*query - sent).count());
      check.expect(delays_ms.back() <= 150,
                   fmt::format("pause {}: the query came {:.0f} ms after the motion", k, delays_ms.back()));
      // Motion without a pause asks nothing more (the 1 s timer aside).
      const auto burst = Clock::now();
      for (int i = 0; i < 5; ++i) {
        std::this_thread::sleep_for(30ms);
        expect_through(check, *mouse, *out, model, make_frame({rel(ev::kRelY, i % 2 == 0 ? 3 : -3)}), "burst");
      }
      during_burst = std::max(during_burst, helper->queries_between(burst + 1ms, Clock::now()));
    }
    check.expect(during_burst <= 1,
                 fmt::format("{} queries during 150 ms of motion without a pause (the timer allows 1)", during_burst));
    check.expect(daemon_cursor(*control) == model.cursor().position, "the model moved without an answer");
    const std::vector<std::string> odd = helper->unexpected();
    check.expect(odd.empty(), "the helper's connection got: " + (odd.empty() ? "" : odd.front()));
    std::string delays, held;
    for (double d : delays_ms) delays += fmt::format("{}{:.0f}", delays.empty() ? "" : ", ", d);
    for (double d : held_ms) held += fmt::format("{}{:.1f}", held.empty() ? "" : ", ", d);
    check.note(
        fmt::format("queries {} ms after the first frame after pauses of 400, 550, 700 ms; unanswered, that "
                    "frame came out {} ms after it was sent; at most {} queries during the bursts that followed",
                    delays, held, during_burst));
  });

  session.run("[12] resync: after a pause the first frame waits for the helper's answer and starts from there",
              [&](Check& check) {
                // An application warped the cursor during the pause: the helper reports it, and the frame
                // moves the cursor from there rather than from where the model was.
                const ph::Vec2 warped{700.5, 400.5};
                helper->answer_with(warped);
                std::this_thread::sleep_for(400ms);
                const ph::Vec2 was = model.cursor().position;
                model.move_cursor_to(warped);
                const auto sent = Clock::now();
                expect_through(check, *mouse, *out, model, make_frame({rel(ev::kRelX, 5), rel(ev::kRelY, 3)}),
                               "after the warp");
                const double latency_ms = std::chrono::duration<double, std::milli>(Clock::now() - sent).count();
                helper->answer_with(std::nullopt);
                const ph::Vec2 at = daemon_cursor(*control);
                check.expect(
                    at == model.cursor().position,
                    fmt::format("expected the model at ({}, {}) (the helper's point and the frame), got ({}, "
                                "{}) (the model was at ({}, {}))",
                                model.cursor().position.x, model.cursor().position.y, at.x, at.y, was.x, was.y));
                check.note(
                    fmt::format("the model was at ({}, {}), the helper said ({}, {}); after [REL_X 5, REL_Y 3] "
                                "({:.1f} ms through the daemon) it is at ({}, {})",
                                was.x, was.y, warped.x, warped.y, latency_ms, at.x, at.y));
                helper.reset();
                touchpad.reset();
              });

  session.run("[7] SIGHUP with a valid changed config: reloads, the region takes effect", [&](Check& check) {
    // Put the cursor at (900, 540), left of the hole's centre, while the scene is still flat.
    const ph::Vec2 at = model.cursor().position;
    const auto dx = static_cast<std::int32_t>(std::lround(900 - at.x));
    const auto dy = static_cast<std::int32_t>(std::lround(540 - at.y));
    std::vector<ph::InputEvent> move;
    if (dx != 0) move.push_back(rel(ev::kRelX, dx));
    if (dy != 0) move.push_back(rel(ev::kRelY, dy));
    if (!move.empty()) expect_through(check, *mouse, *out, model, make_frame(move), "positioning");
    write_file_atomically(config, region_config(hole));
    notify->clear();
    const auto start = Clock::now();
    daemon->signal(SIGHUP);
    check.expect(notify->expect("RELOADING=1", 10s), "expected RELOADING=1 after SIGHUP, got none within 10 s");
    check.expect(notify->expect("READY=1", 60s), "expected READY=1 after RELOADING=1, got none within 60 s");
    const double reload_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (!check.ok()) throw Fatal("no reload");
    model.set_scene(std::make_shared<const ph::Scene>(ph::load_scene(ph::parse_scene_file(config))));
    const StrokeResult result = run_stroke(check, *mouse, *out, model, stroke(30, 5), "stroke");
    check.expect(result.differing > 0, "expected the region to change the output, got every frame unchanged");
    check.note(
        fmt::format("RELOADING=1 then READY=1 {:.2f} s after SIGHUP; {} frames from x=900, {} changed by the "
                    "region, all equal to the offline pipeline; cursor now at x={:.1f}",
                    reload_s, result.frames.size(), result.differing, model.cursor().position.x));
  });

  session.run("[7] SIGHUP with an invalid config: keeps the previous scene", [&](Check& check) {
    write_file_atomically(config, region_config(hole) + "bogus_key = 1\n");
    notify->clear();
    const std::size_t log_before = daemon->log().size();
    daemon->signal(SIGHUP);
    check.expect(notify->expect("RELOADING=1", 10s), "expected RELOADING=1 after SIGHUP, got none within 10 s");
    check.expect(notify->expect("READY=1", 30s), "expected READY=1 after the failed reload, got none within 30 s");
    if (!daemon->running()) throw Fatal("the daemon exited: " + describe_wait_status(*daemon->wait_exit(0s)));
    // systemctl status says it, not only the log.
    const std::string status = last_status(*notify);
    check.expect(status.find("the last reload failed") != std::string::npos,
                 "expected the STATUS= line to say that the last reload failed, got: " + status);
    std::string said;
    const bool logged = wait_until(
        [&] {
          said = daemon->log().substr(std::min(log_before, daemon->log().size()));
          return said.find("keeping the previous scene") != std::string::npos;
        },
        5s);
    check.expect(logged, "expected a log line with 'keeping the previous scene', got: " + said);
    const StrokeResult result = run_stroke(check, *mouse, *out, model, stroke(30, -5), "stroke back");
    check.expect(result.differing > 0, "expected the previous region to still change the output, got none changed");
    // The line that says it, for the note.
    const std::size_t at = said.find("keeping the previous scene");
    if (at != std::string::npos) {
      const std::size_t begin = said.rfind('\n', at), end = said.find('\n', at);
      said = said.substr(begin == std::string::npos ? 0 : begin + 1, end == std::string::npos ? end : end - begin - 1);
    }
    check.note(fmt::format("still running; said \"{}\"; {} frames back, {} changed, all as the previous scene", said,
                           result.frames.size(), result.differing));
  });

  session.run(
      "[7] SIGHUP to a hybrid region: the daemon finds its steps from the depth map, as the offline pipeline",
      [&](Check& check) {
        // The Gaussian bump of radius 100 px at the hole's place: its truncated rim steps down by about 1 px, which the
        // hybrid method finds from the depth map (docs/METHODS.md, "Hybrid"). The daemon reads images in a child
        // process, the offline pipeline in this one; until 2026-11-26 the depth map of a hybrid region did not reach
        // the daemon.
        const ph::TargetSpec bump = target_named("bump-gaussian-h1-r100");
        ph::write_target_files(options.scratch, {bump});
        std::string text = region_config(bump);
        const std::string curvature = "method = \"curvature\"", hybrid = "method = \"hybrid\"";
        text.replace(text.find(curvature), curvature.size(), hybrid);
        write_file_atomically(config, text);
        notify->clear();
        daemon->signal(SIGHUP);
        check.expect(notify->expect("RELOADING=1", 10s), "expected RELOADING=1 after SIGHUP, got none within 10 s");
        check.expect(notify->expect("READY=1", 60s), "expected READY=1 after RELOADING=1, got none within 60 s");
        check.expect(last_status(*notify).find("reload failed") == std::string::npos,
                     "the STATUS= line still says a reload failed after one that did not: " + last_status(*notify));
        if (!check.ok()) throw Fatal("no reload");
        const auto scene = std::make_shared<const ph::Scene>(ph::load_scene(ph::parse_scene_file(config)));
        std::size_t marked = 0;
        for (std::uint8_t mark : scene->regions().at(0).fields.discontinuity->values) marked += mark != 0 ? 1 : 0;
        check.expect(marked > 0, "expected the offline hybrid region to mark the bump's rim, got no mark");
        model.set_scene(scene);
        // Left of the bump's rim (at x = 860 on this row), then across the bump and its far rim (x = 1060).
        const ph::Vec2 at = model.cursor().position;
        std::vector<ph::InputEvent> move;
        if (const auto dx = static_cast<std::int32_t>(std::lround(840 - at.x)); dx != 0)
          move.push_back(rel(ev::kRelX, dx));
        if (const auto dy = static_cast<std::int32_t>(std::lround(540 - at.y)); dy != 0)
          move.push_back(rel(ev::kRelY, dy));
        if (!move.empty()) expect_through(check, *mouse, *out, model, make_frame(move), "positioning");
        // The same pipeline with the region as the curvature method: what the daemon did with no depth map.
        ph::Pipeline with_steps = model, no_steps = model;
        std::string as_curvature = text;
        as_curvature.replace(as_curvature.find(hybrid), hybrid.size(), curvature);
        no_steps.set_scene(std::make_shared<const ph::Scene>(
            ph::load_scene(ph::parse_scene_text(as_curvature, config, ph::builtin_methods()))));
        const std::vector<Frame> frames = stroke(50, 5);
        const StrokeResult result = run_stroke(check, *mouse, *out, model, frames, "stroke");
        int apart = 0;
        for (const Frame& f : frames) apart += same_events(with_steps.process(f), no_steps.process(f)) ? 0 : 1;
        check.expect(apart > 0, "expected the rim's steps to change some frame from the curvature method's, got none");
        check.note(
            fmt::format("{} texels marked; {} frames across the bump, {} changed by the region, all equal to the "
                        "offline pipeline; {} of the stroke's {} frames apart from the curvature method's (what the "
                        "daemon did with no depth map)",
                        marked, result.frames.size(), result.differing, apart, frames.size()));
      });

  session.run(
      "[3b] SIGHUP to absolute output: a tablet-like device replaces the relative one, cursor kept", [&](Check& check) {
        std::string text = region_config(hole);
        const std::string relative = "output = \"relative\"";
        // Flat acceleration keeps this case exact; the default adaptive one is checked with the default scene.
        text.replace(text.find(relative), relative.size(), "output = \"absolute\"\nacceleration = \"flat\"");
        write_file_atomically(config, text);
        notify->clear();
        daemon->signal(SIGHUP);
        check.expect(notify->expect("READY=1", 60s), "expected READY=1 after the reload, got none");
        // READY=1 comes once the mice are taken again: the old device is gone by now.
        const std::string node = wait_for_device(virtual_name, kDeviceTimeout, uevents);
        if (node.empty()) throw Fatal("no virtual device after switching to absolute output");
        out.emplace(node);
        unsigned long abs_bits = 0, rel_bits = 0;
        ::ioctl(out->fd(), EVIOCGBIT(EV_ABS, sizeof abs_bits), &abs_bits);
        ::ioctl(out->fd(), EVIOCGBIT(EV_REL, sizeof rel_bits), &rel_bits);
        input_absinfo x{}, y{};
        ::ioctl(out->fd(), EVIOCGABS(ABS_X), &x);
        ::ioctl(out->fd(), EVIOCGABS(ABS_Y), &y);
        check.expect((abs_bits & 3UL) == 3UL, "expected ABS_X and ABS_Y on the absolute device");
        check.expect((rel_bits & 3UL) == 0UL, "expected no REL_X/REL_Y next to ABS_X/ABS_Y");
        check.expect(x.minimum == 0 && x.maximum == 3839 && y.minimum == 0 && y.maximum == 2159,
                     fmt::format("expected ABS ranges 0..3839 x 0..2159 (half pixels), got {}..{} x {}..{}", x.minimum,
                                 x.maximum, y.minimum, y.maximum));
        ph::PipelineConfig absolute = pipeline_config();
        absolute.mode = ph::OutputMode::absolute;
        absolute.start = model.cursor().position;  // the daemon keeps its cursor across the switch
        model = ph::Pipeline(std::make_shared<const ph::Scene>(ph::load_scene(ph::parse_scene_file(config))), absolute);
        if (!wait_taken(*mouse, *out, kDeviceTimeout)) throw Fatal("nothing came out of " + node);
        // The kernel drops an absolute value equal to the axis' current one (a stroke along x leaves
        // ABS_Y out); the offline pipeline writes both axes. Compare with what the kernel passes on.
        std::map<std::uint16_t, std::int32_t> axis = {{ev::kAbsX, 0}, {ev::kAbsY, 0}};
        int frames = 0, moved = 0;
        for (const Frame& in : stroke(20, 6)) {
          const Frame computed = untimed(model.process(in));
          Frame expected;
          for (const ph::InputEvent& e : computed.events) {
            if (e.type == ev::kAbs && axis.count(e.code) != 0) {
              if (axis[e.code] == e.value) continue;
              axis[e.code] = e.value;
              ++moved;
            }
            expected.events.push_back(e);
          }
          mouse->send(in);
          if (!delivers_something(expected)) continue;
          const std::optional<Frame> got = out->next_frame(kFrameTimeout);
          check.expect(got && same_events(*got, expected),
                       fmt::format("absolute frame {}: sent [{}], expected [{}], got [{}]", frames, describe(in),
                                   describe(expected), got ? describe(*got) : std::string("nothing")));
          ++frames;
        }
        check.expect(moved > 0, "expected ABS_X/ABS_Y events in place of the REL motion, got none");
        check.note(
            fmt::format("{} has ABS_X 0..3839, ABS_Y 0..2159 (half pixels), no REL_X/Y; {} frames equal to the offline "
                        "absolute pipeline started at the kept cursor",
                        node, frames));
      });

  session.run("[8] SIGTERM: exit 0, held button released first, device gone, mouse ungrabbed", [&](Check& check) {
    expect_through(check, *mouse, *out, model, make_frame({key(ev::kBtnLeft, 1)}), "press before SIGTERM");
    notify->clear();
    daemon->signal(SIGTERM);
    bool released = false;
    std::string seen;
    while (std::optional<Frame> frame = out->next_frame(kDeviceTimeout)) {
      seen += (seen.empty() ? "" : " | ") + describe(*frame);
      for (const ph::InputEvent& e : frame->events) {
        released = released || (e.type == ev::kKey && e.code == ev::kBtnLeft && e.value == 0);
      }
    }
    check.expect(released, "expected BTN_LEFT 0 from the virtual device before it went away, got [" + seen + "]");
    check.expect(out->gone(), "expected the virtual device to go away within 10 s of SIGTERM");
    const std::optional<int> status = daemon->wait_exit(15s);
    check.expect(
        status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0,
        "expected exit status 0, got " + (status ? describe_wait_status(*status) : "still running after 15 s"));
    check.expect(notify->expect("STOPPING=1", 1s), "expected STOPPING=1, got none");
    check.expect(wait_for_device_gone(virtual_name, kDeviceTimeout, uevents), "the virtual device is still there");
    const int grab = try_grab(mouse->node());
    check.expect(grab == 0, "EVIOCGRAB on the test mouse after the exit: expected success, got " + grab_text(grab));
    own->read_now();
    mouse->send(make_frame({rel(ev::kRelX, 1)}));
    check.expect(own->next_frame(kFrameTimeout).has_value(),
                 "the test mouse's own node delivers nothing after the exit");
    check.note(fmt::format("released before removal: [{}]; {}; EVIOCGRAB on the test mouse succeeds", seen,
                           status ? describe_wait_status(*status) : "?"));
  });
}

// ---- part 3: the embedded default scene --------------------------------------------------------------------

// A new test mouse named `name`, grabbed by the test before the daemon takes it (the daemon waits for udev's
// event, the test only for the node), and the grab's descriptor. Should the daemon be first all the same, a fresh
// mouse is tried.
struct HeldMouse {
  std::unique_ptr<TestMouse> mouse;
  Fd holder;
};
HeldMouse hold_new_mouse(const std::string& name, const UeventMonitor& uevents) {
  HeldMouse held;
  for (int attempt = 1; attempt <= 3 && !held.holder; ++attempt) {
    held.mouse.reset();
    if (attempt > 1 && !wait_for_device_gone("pseudohaptic " + name, kDeviceTimeout, uevents)) break;
    held.mouse = std::make_unique<TestMouse>(name);
    Fd fd(::open(held.mouse->node().c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
    if (fd && ::ioctl(fd.get(), EVIOCGRAB, 1) == 0) held.holder = std::move(fd);
  }
  if (!held.holder) throw Fatal("the daemon grabbed a new test mouse before the test could, three times");
  return held;
}

// Whether the daemon logs, after `log_before` bytes of its log, that another program holds `node`; `said`: what it
// logged meanwhile.
bool daemon_says_held_elsewhere(const ChildProcess& daemon, std::size_t log_before, const std::string& node,
                                std::string& said) {
  const std::string expected = node + ": another program has grabbed it; taking it once that program lets go";
  return wait_until(
      [&] {
        said = daemon.log().substr(std::min(log_before, daemon.log().size()));
        return said.find(expected) != std::string::npos;
      },
      kDeviceTimeout);
}

void default_scene_part(Report& report, const Options& options, Latency& latency) {
  Session session(report, "daemon with the embedded default scene (--default-scene)");
  const UeventMonitor uevents;
  const std::string name_a = "ph-e2e mouse A", virtual_a = "pseudohaptic ph-e2e mouse A";
  std::optional<TestMouse> mouse;
  std::optional<EventReader> before, out;  // opened on the test mouse before the daemon; the virtual device
  std::unique_ptr<NotifySocket>& notify = session.notify;
  std::unique_ptr<ChildProcess>& daemon = session.daemon;
  std::shared_ptr<const ph::Scene> scene;
  std::optional<ph::Pipeline> model;
  std::optional<ph::control::Client> control;
  std::optional<AbsoluteFollower> follower;
  AbsoluteStroke over_texture;
  const std::string control_path = (options.scratch / "control-default").string();

  session.run("default scene: the daemon starts and takes the mouse", [&](Check& check) {
    auto start = Clock::now();
    scene = std::make_shared<const ph::Scene>(ph::default_scene());
    model.emplace(scene, default_pipeline_config());
    const double model_s = std::chrono::duration<double>(Clock::now() - start).count();
    mouse.emplace(name_a);
    before.emplace(mouse->node());
    notify = std::make_unique<NotifySocket>((options.scratch / "notify-default.sock").string());
    start = Clock::now();
    daemon = start_daemon(options, {"--default-scene", "--control", control_path}, *notify, "daemon-default.log");
    if (!wait_ready(*notify, *daemon, 90s)) throw Fatal("no READY=1 within 90 s");
    const double ready_s = std::chrono::duration<double>(Clock::now() - start).count();
    const std::string node = wait_for_device(virtual_a, kDeviceTimeout, uevents);
    if (node.empty()) throw Fatal("no virtual device '" + virtual_a + "'");
    out.emplace(node);
    control.emplace(control_path);
    follower.emplace(*model, *control);
    const ph::control::Reply reply = control->request("status", 10s);
    const std::optional<ph::control::Status> status =
        reply.ok ? ph::control::parse_status(reply.text) : std::optional<ph::control::Status>{};
    check.expect(status && status->absolute && status->mice == 1 && status->regions == 3,
                 "expected 'status' to say absolute output, 1 mouse, 3 regions; got: " + reply.text);
    check.note(
        fmt::format("READY=1 {:.2f} s after the start, virtual device {}, daemon VmRSS {} KiB (the offline "
                    "default scene took {:.2f} s here); status: {}",
                    ready_s, node, rss_kib(daemon->pid()), model_s, reply.text));
  });

  session.run("[1] grab exclusivity", [&](Check& check) {
    const int grab = try_grab(mouse->node());
    check.expect(grab == EBUSY, "EVIOCGRAB on the test mouse: expected EBUSY, got " + grab_text(grab));
    EventReader late(mouse->node());
    before->read_now();
    follower->through(check, *mouse, *out, make_frame({rel(ev::kRelX, 2)}), "frame");
    // Once the frame came out of the virtual device the kernel had handed it to every reader of the mouse.
    const std::size_t early = before->read_now().size(), later = late.read_now().size();
    check.expect(early == 0 && later == 0,
                 fmt::format("expected nothing for the other readers of the test mouse, got {} (opened before the "
                             "daemon) and {} (opened after)",
                             early, later));
    check.note("EVIOCGRAB fails with EBUSY; two other readers got nothing while the frame came out");
  });

  session.run("[3] texture: absolute output with adaptive acceleration follows the offline model", [&](Check& check) {
    const ph::Vec2 from = model->cursor().position;
    ph::Pipeline empty = *model;  // the same cursor and acceleration history, no texture
    empty.set_scene(std::make_shared<const ph::Scene>());
    over_texture = run_absolute_stroke(check, *follower, *mouse, *out, empty, stroke(40, 6), "stroke");
    check.expect(over_texture.apart > 0,
                 "expected the hole to move the cursor 2 px or more from where an empty scene puts it, got no frame");
    const ph::Vec2 daemon_at = daemon_cursor(*control);
    check.expect(ph::length(daemon_at - model->cursor().position) < 1.5,
                 fmt::format("the daemon's model ended at ({:.2f}, {:.2f}), the offline model at ({:.2f}, {:.2f})",
                             daemon_at.x, daemon_at.y, model->cursor().position.x, model->cursor().position.y));
    check.note(
        fmt::format("{} frames at 8 ms from ({:.0f}, {:.0f}) to ({:.1f}, {:.1f}) (the daemon's model: "
                    "({:.2f}, {:.2f})); an empty scene ends at ({:.1f}, {:.1f}); {} frames 2 px or more from "
                    "the empty scene's pixel (up to {:.0f} px); so far {}",
                    over_texture.frames.size(), from.x, from.y, model->cursor().position.x, model->cursor().position.y,
                    daemon_at.x, daemon_at.y, empty.cursor().position.x, empty.cursor().position.y, over_texture.apart,
                    over_texture.max_apart_px, follower->summary()));
  });

  session.run("[4] texture: buttons, wheel and hi-res wheel pass unchanged in their frames", [&](Check& check) {
    int with_others = 0;
    for (const auto& [in, got] : over_texture.frames) {
      const Frame others_in = without_motion(in), others_out = without_motion(got);
      check.expect(same_events(others_in, others_out),
                   fmt::format("sent [{}], got [{}]: the other events changed", describe(in), describe(got)));
      if (others_in.events.size() > 1) ++with_others;
    }
    check.expect(with_others >= 10,
                 fmt::format("expected at least 10 frames with buttons or wheels, got {}", with_others));
    check.note(fmt::format("{} frames with buttons or wheels: the same events, in the same order", with_others));
  });

  session.run(
      "[11] control socket, absolute output: the frames after `position X Y` come out from there", [&](Check& check) {
        const ph::Vec2 to{1000.25, 540.75};  // on the hole's wall, for the latency below
        const ph::control::Reply reply =
            control->request(ph::control::format_request(ph::control::PositionRequest{to}), 10s);
        check.expect(reply.ok, "expected ok to 'position', got: " + reply.text);
        model->move_cursor_to(to);
        const std::optional<Frame> got =
            follower->through(check, *mouse, *out, make_frame({rel(ev::kRelX, 1)}), "after position");
        const std::optional<std::int32_t> x = got ? value_in(*got, ev::kAbs, ev::kAbsX) : std::nullopt;
        const std::optional<std::int32_t> y = got ? value_in(*got, ev::kAbs, ev::kAbsY) : std::nullopt;
        check.expect(x && y && std::abs(*x - ph::abs_value_of_pixel(1000)) <= 2 && *y == ph::abs_value_of_pixel(540),
                     "expected ABS_X 2001 (+-2) and ABS_Y 1081, got [" + (got ? describe(*got) : "nothing") + "]");
        check.note(
            fmt::format("moved to ({}, {}); [REL_X 1] came out as [{}]", to.x, to.y, got ? describe(*got) : "nothing"));
      });

  session.run("[10c] latency, daemon over the default scene's texture", [&](Check& check) {
    const ph::Vec2 at = model->cursor().position;
    const std::optional<std::size_t> region = scene->owner(model->cursor().texel);
    if (!region) throw Fatal(fmt::format("the cursor ({:.1f}, {:.1f}) is not over a region", at.x, at.y));
    measure_latency_absolute(check, *mouse, *out, *follower, options.latency_frames, latency);
    check.note(fmt::format("at ({:.1f}, {:.1f}) in region {}", at.x, at.y, scene->regions()[*region].name));
  });

  session.run(
      fmt::format("[6] hotplug: {} create/destroy cycles, no fd or memory leak", options.cycles), [&](Check& check) {
        const std::string name = "ph-e2e hotplug", virtual_name = "pseudohaptic ph-e2e hotplug";
        const pid_t pid = daemon->pid();
        const int fds_before = open_fd_count(pid);
        int fds_first = -1, fds_last = -1;
        long rss_first = -1, rss_last = -1;
        std::vector<std::string> grown;  // mappings whose resident KiB grew by 64 or more since cycle 1
        // VmRSS at the end of each third of the cycles: a leak grows in every third. It may also rise once, by 0.2-1.6
        // MB some 10-20 s after the daemon's start: the guest kernel's transparent huge pages are "always", and
        // khugepaged (every 10 s, collapsing a 2 MB range with even one page present) makes the scene's fields huge
        // pages, with the untouched top of the stack of the mouse's reader thread that lies next to them in one
        // mapping (the mapping's AnonHugePages 0 -> 6144 KiB as its Rss rose; none of it with THP set to "never").
        // That is no leak; the mappings that grew are named in the note.
        const int third = std::max(1, options.cycles / 3);
        std::vector<long> rss_thirds;
        std::map<std::string, MappingKib> maps_first;  // after cycle 1: what grew is named in the note
        int done = 0;
        const auto start = Clock::now();
        for (int cycle = 1; cycle <= options.cycles; ++cycle) {
          trace(options, fmt::format("cycle {}: creating the mouse", cycle));
          {
            TestMouse hot(name);
            trace(options, "created " + hot.node());
            const std::string node = wait_for_device(virtual_name, kDeviceTimeout, uevents);
            trace(options, "virtual device " + node);
            if (!check.expect(!node.empty(), fmt::format("cycle {}: no virtual device within 10 s", cycle))) break;
            if (cycle == 1) {
              EventReader hot_out(node);
              check.expect(wait_taken(hot, hot_out, kDeviceTimeout), "nothing came out of " + node);
              follower->through(check, hot, hot_out, make_frame({rel(ev::kRelY, 3)}), "hotplugged mouse");
              const int grab = try_grab(hot.node());
              check.expect(grab == EBUSY, "EVIOCGRAB on the hotplugged mouse: expected EBUSY, got " + grab_text(grab));
            }
          }
          trace(options, "destroyed the mouse");
          if (!check.expect(wait_for_device_gone(virtual_name, kDeviceTimeout, uevents),
                            fmt::format("cycle {}: the virtual device stayed after its mouse went away", cycle))) {
            break;
          }
          ++done;
          if (cycle == 1) {
            wait_until([&] { return open_fd_count(pid) <= fds_before; }, 2s);
            fds_first = open_fd_count(pid);
            rss_first = rss_kib(pid);
            maps_first = mappings_kib(pid);
          }
          if (cycle % third == 0 && cycle / third <= 2) rss_thirds.push_back(rss_kib(pid));
        }
        const double per_cycle = std::chrono::duration<double>(Clock::now() - start).count() / std::max(done, 1);
        if (done == options.cycles) {
          wait_until([&] { return open_fd_count(pid) <= fds_first; }, 5s);
          fds_last = open_fd_count(pid);
          rss_last = rss_kib(pid);
          grown = grown_mappings(maps_first, mappings_kib(pid), 64);
          check.expect(fds_last == fds_first,
                       fmt::format("open fds: {} after cycle 1, {} after cycle {}", fds_first, fds_last, done));
          // A leak of 2.6 KiB a cycle or more grows both later thirds by a third of the slack; a one-time rise stays
          // within the bound on the whole run.
          constexpr long kRssSlackKib = 256, kRssOnceKib = 4096;
          if (rss_thirds.size() == 2) {
            const long second = rss_thirds[1] - rss_thirds[0], last = rss_last - rss_thirds[1];
            check.expect(
                std::min(second, last) <= kRssSlackKib / 3,
                fmt::format("VmRSS grew in each of the last two thirds of the cycles: by {} KiB (cycles {}-{}) "
                            "and {} KiB (cycles {}-{}); allowed in one of them: {} KiB",
                            second, third, 2 * third, last, 2 * third, done, kRssSlackKib / 3));
          }
          check.expect(rss_last - rss_first <= kRssOnceKib,
                       fmt::format("VmRSS grew from {} KiB after cycle 1 to {} KiB after cycle {} (allowed: "
                                   "{} KiB)",
                                   rss_first, rss_last, done, kRssOnceKib));
        }
        check.expect(daemon->running(), "the daemon exited during the cycles");
        // One mouse is left, so one reader thread, named for ps -L and top -H.
        const std::vector<std::string> threads = thread_names(pid);
        check.expect(std::count(threads.begin(), threads.end(), "ph-mouse-reader") == 1,
                     fmt::format("expected one thread named ph-mouse-reader after the cycles, got threads: {}",
                                 fmt::join(threads, ", ")));
        const std::string thirds = rss_thirds.size() == 2 ? fmt::format(", {} and {} KiB after cycles {} and {}",
                                                                        rss_thirds[0], rss_thirds[1], third, 2 * third)
                                                          : std::string();
        check.note(fmt::format(
            "{} cycles, {:.0f} ms each; open fds {} before, {} after cycle 1, {} after the "
            "last; VmRSS {} KiB after cycle 1{}, {} KiB after the last; mappings grown by 64 KiB or more: {}",
            done, per_cycle * 1000, fds_before, fds_first, fds_last, rss_first, thirds, rss_last,
            grown.empty() ? std::string("none") : fmt::format("{}", fmt::join(grown, "; "))));
      });

  session.run("[6] two mice at once: both taken, one shared cursor model", [&](Check& check) {
    const std::string virtual_b = "pseudohaptic ph-e2e mouse B";
    {
      TestMouse mouse_b("ph-e2e mouse B");
      const std::string node = wait_for_device(virtual_b, kDeviceTimeout, uevents);
      if (node.empty()) throw Fatal("no virtual device '" + virtual_b + "' for the second mouse");
      EventReader out_b(node);
      if (!wait_taken(mouse_b, out_b, kDeviceTimeout)) throw Fatal("nothing came out of " + node + " within 10 s");
      check.expect(!find_input_node(virtual_a).empty(), "the first mouse's virtual device went away");
      int differing = 0;
      for (int i = 0; i < 24; ++i) {
        const bool on_b = i % 2 == 1;
        const Frame in = on_b ? make_frame({rel(ev::kRelX, -3), rel(ev::kRelY, -2)})
                              : make_frame({rel(ev::kRelX, -5), rel(ev::kRelY, 2)});
        EventReader& from = on_b ? out_b : *out;
        EventReader& other = on_b ? *out : out_b;
        const std::optional<Frame> got = follower->through(check, on_b ? mouse_b : *mouse, from, in,
                                                           fmt::format("frame {} on mouse {}", i, on_b ? "B" : "A"));
        if (got && value_in(*got, ev::kAbs, ev::kAbsX)) ++differing;
        const std::size_t stray = other.read_now().size();
        check.expect(stray == 0,
                     fmt::format("frame {}: {} events came out of the other mouse's virtual device", i, stray));
      }
      const int grab = try_grab(mouse_b.node());
      check.expect(grab == EBUSY, "EVIOCGRAB on the second mouse: expected EBUSY, got " + grab_text(grab));
      check.expect(differing > 0, "expected ABS_X out of the virtual devices, got none");
      check.note(
          fmt::format("24 frames alternating A and B, {} with ABS_X, each device's position within 1 px of one "
                      "offline model fed the interleaved frames",
                      differing));
    }
    check.expect(wait_for_device_gone(virtual_b, kDeviceTimeout, uevents),
                 "the second mouse's virtual device stayed after the mouse went away");
  });

  session.run("[6] a mouse another program holds: left to it, taken once it lets go", [&](Check& check) {
    const std::string name = "ph-e2e held elsewhere", virtual_name = "pseudohaptic " + name;
    const std::size_t log_before = daemon->log().size();
    auto [held, holder] = hold_new_mouse(name, uevents);
    std::string said;
    const bool logged = daemon_says_held_elsewhere(*daemon, log_before, held->node(), said);
    check.expect(logged, "expected the daemon to log that another program holds " + held->node() + ", got: " + said);
    check.expect(find_input_node(virtual_name).empty(), "a virtual device stayed for the mouse held elsewhere");
    const auto status_now = [&] {
      const ph::control::Reply reply = control->request("status", 10s);
      return reply.ok ? ph::control::parse_status(reply.text) : std::optional<ph::control::Status>{};
    };
    const std::optional<ph::control::Status> while_held = status_now();
    check.expect(while_held && while_held->mice == 1 && while_held->held_elsewhere == 1,
                 "while held elsewhere, expected 'status' to say 1 mouse taken and 1 held elsewhere");
    // What systemctl status shows (sd_notify's STATUS=), sent before the log line; read by the socket's thread.
    const bool told_systemd = wait_until(
        [&] {
          const std::vector<std::string> lines = notify->history();
          return std::any_of(lines.begin(), lines.end(), [](const std::string& line) {
            return line.starts_with("STATUS=") && line.find("; 1 held by another program; ") != std::string::npos;
          });
        },
        2s);
    check.expect(told_systemd, "expected a STATUS= line saying '1 held by another program'");
    std::string tool_said = "(no pseudohaptic tool found: --tool)";
    if (!options.tool.empty()) {
      ChildProcess tool({options.tool, "status", "--socket", control_path}, {"PATH=/usr/bin:/bin", "LANG=C.UTF-8"},
                        (options.scratch / "tool-status-held.log").string());
      tool.wait_exit(30s);
      const std::string line = "mice:    1 taken; 1 held by another program (taken once it lets go)";
      tool_said = tool.log();
      check.expect(tool_said.find(line) != std::string::npos,
                   "expected '" + line + "' in what pseudohaptic status printed:\n" + tool_said);
      tool_said = tool_said.substr(0, tool_said.find('\n', tool_said.find("mice:")));
      tool_said = tool_said.substr(tool_said.find("mice:"));
    }
    // The holder gets the mouse's frames, the daemon nothing.
    held->send(make_frame({rel(ev::kRelX, 4)}));
    std::vector<input_event> to_holder;
    wait_until(
        [&] {
          input_event e{};
          while (::read(holder.get(), &e, sizeof e) == static_cast<ssize_t>(sizeof e)) to_holder.push_back(e);
          return !to_holder.empty();
        },
        2s);
    check.expect(!to_holder.empty(), "the program holding the mouse got none of its events");
    check.expect(find_input_node(virtual_name).empty() && out->read_now().empty(),
                 "the daemon emitted while another program held the mouse");
    // Let go; the mouse's next frames reach every reader again, the daemon's too.
    ::ioctl(holder.get(), EVIOCGRAB, 0);
    const auto released = Clock::now();
    held->send(make_frame({rel(ev::kRelWheel, 1)}));  // to the desktop; the daemon reads it and takes the mouse
    const std::string node = wait_for_device(virtual_name, kDeviceTimeout, uevents);
    if (node.empty()) throw Fatal("no virtual device for the mouse within 10 s of the other program letting go");
    EventReader held_out(node);
    if (!wait_taken(*held, held_out, kDeviceTimeout)) throw Fatal("nothing came out of " + node);
    const double taken_s = std::chrono::duration<double>(Clock::now() - released).count();
    follower->through(check, *held, held_out, make_frame({rel(ev::kRelX, 3), rel(ev::kRelY, -2)}),
                      "frame after the other program let go");
    const int grab = try_grab(held->node());
    check.expect(grab == EBUSY, "EVIOCGRAB on the mouse once taken: expected EBUSY, got " + grab_text(grab));
    const std::optional<ph::control::Status> after = status_now();
    check.expect(after && after->mice == 2 && after->held_elsewhere == 0,
                 "once taken, expected 'status' to say 2 mice taken and none held elsewhere");
    check.note(
        fmt::format("the holder got {} events and the daemon emitted none; pseudohaptic status said \"{}\"; "
                    "taken {:.2f} s after the release",
                    to_holder.size(), tool_said, taken_s));
    holder = Fd();
    held.reset();
    check.expect(wait_for_device_gone(virtual_name, kDeviceTimeout, uevents),
                 "the virtual device stayed after the mouse went away");
  });

  session.run(
      "[6] a mouse another program holds, unplugged while held: not taken for a release, no virtual device made",
      [&](Check& check) {
        const std::string name = "ph-e2e unplugged while held", virtual_name = "pseudohaptic " + name;
        const std::size_t log_before = daemon->log().size();
        auto [held, holder] = hold_new_mouse(name, uevents);
        std::string said;
        if (!daemon_says_held_elsewhere(*daemon, log_before, held->node(), said))
          throw Fatal("the daemon did not log that another program holds " + held->node() + ": " + said);
        const std::string node = held->node();
        // What the daemon says from here on is of this mouse: hold_new_mouse may have made one before it that the
        // daemon took first, on the same node.
        const std::size_t log_held = std::max(log_before, daemon->log().find(node + ": another program", log_before));
        held.reset();  // unplugged, the other program's grab still on
        const std::string unplugged = node + " \"" + name + "\": unplugged while another program held it";
        const std::string removed = node + " removed";  // udev's remove event came first: let go without a word
        const bool gone = wait_until(
            [&] {
              said = daemon->log().substr(std::min(log_before, daemon->log().size()));
              const std::optional<ph::control::Status> status =
                  ph::control::parse_status(control->request("status").text);
              return status && status->held_elsewhere == 0;
            },
            kDeviceTimeout);
        check.expect(gone, "the daemon still counted a mouse held elsewhere after it was unplugged");
        std::this_thread::sleep_for(300ms);
        said = daemon->log().substr(std::min(log_held, daemon->log().size()));
        check.expect(said.find("the other program let go of it") == std::string::npos,
                     "the unplug was taken for a release: " + said);
        check.expect(said.find("took " + node) == std::string::npos && find_input_node(virtual_name).empty(),
                     "a virtual device was made for the unplugged mouse: " + said);
        check.note(said.find(unplugged) != std::string::npos
                       ? "the node hung up first: the daemon logged \"" + unplugged + "\""
                       : "udev's remove event came first (\"" + removed + "\" at debug level): let go of it");
      });

  session.run("[9] SYN_DROPPED: the daemon survives an overflow, no button stays stuck", [&](Check& check) {
    follower->through(check, *mouse, *out, make_frame({key(ev::kBtnLeft, 1)}), "press before the flood");
    daemon->signal(SIGSTOP);
    if (!daemon->wait_stopped()) throw Fatal("the daemon exited instead of stopping");
    constexpr int kFlood = 4000;
    for (int i = 0; i < kFlood; ++i) {
      std::vector<ph::InputEvent> events{rel(ev::kRelX, 1)};
      if (i == 1000) events.push_back(key(ev::kBtnLeft, 0));  // the release of the press above
      if (i == 2000) events.push_back(key(ev::kBtnRight, 1));
      if (i == 2500) events.push_back(key(ev::kBtnRight, 0));
      mouse->send(make_frame(std::move(events)));
    }
    daemon->signal(SIGCONT);
    // What comes out first is the resync (libevdev discards what was queued behind the SYN_DROPPED and
    // reports the state differences): BTN_LEFT's release.
    int frames = 0;
    bool left_released = false;
    std::string seen;
    while (!left_released) {
      const std::optional<Frame> frame = out->next_frame(20s);
      if (!frame) break;
      if (++frames <= 4) seen += (seen.empty() ? "" : " | ") + describe(*frame);
      for (const ph::InputEvent& e : frame->events) {
        left_released = left_released || (e.type == ev::kKey && e.code == ev::kBtnLeft && e.value == 0);
      }
    }
    check.expect(daemon->running(), "the daemon did not survive the overflow");
    check.expect(left_released,
                 "expected BTN_LEFT 0 from the resync (it was released in the lost part), got [" + seen + "]");
    check.expect(frames < kFlood, fmt::format("expected the daemon's reader to overflow (fewer than {} frames out), "
                                              "got {}",
                                              kFlood, frames));
    const std::vector<std::uint16_t> held = out->keys_down();
    check.expect(held.empty(),
                 "EVIOCGKEY on the virtual device after the flood: expected nothing held, got " + keys_text(held));
    // A dropped frame does not move the cursor model, so the daemon's model is still the offline one.
    int moved = 0;
    for (int i = 0; i < 6; ++i) {
      std::vector<ph::InputEvent> events{rel(ev::kRelX, -10)};
      if (i == 0) events.push_back(rel(ev::kRelWheel, 1));
      const std::optional<Frame> got = follower->through(check, *mouse, *out, make_frame(std::move(events)),
                                                         fmt::format("frame {} after the flood", i));
      if (got && value_in(*got, ev::kAbs, ev::kAbsX)) ++moved;
    }
    check.expect(moved > 0, "expected motion out of the virtual device after the flood, got none");
    check.note(
        fmt::format("{} frame(s) of {} came out: [{}]; held on the virtual device: {}; {} of 6 later frames "
                    "moved, within 1 px of the offline model; all frames of this daemon: {}",
                    frames, kFlood, seen, keys_text(held), moved, follower->summary()));
  });

  session.run(
      "[8] SIGTERM: a click written as it comes still comes out; exit 0, devices gone, mouse ungrabbed",
      [&](Check& check) {
        // The click is written while the daemon is stopped (SIGSTOP), with SIGTERM pending: once it goes on, its event
        // loop and the mouse's reader race for the state lock. Whichever wins, the grab kept the click from the
        // desktop, and the virtual device must emit it before it goes.
        out->read_now();
        const pid_t pid = daemon->pid();
        ::kill(pid, SIGSTOP);
        const bool stopped = wait_until(
            [pid] {
              const std::string stat = read_text_file("/proc/" + std::to_string(pid) + "/stat");
              const std::size_t end = stat.rfind(')');
              return end != std::string::npos && stat.size() > end + 2 && stat[end + 2] == 'T';
            },
            kDeviceTimeout);
        check.expect(stopped, "the daemon did not stop on SIGSTOP");
        mouse->send(make_frame({key(ev::kBtnLeft, 1)}));
        mouse->send(make_frame({key(ev::kBtnLeft, 0)}));
        daemon->signal(SIGTERM);
        ::kill(pid, SIGCONT);
        std::vector<int> left;  // BTN_LEFT's values, in order
        std::string seen;
        while (std::optional<Frame> frame = out->next_frame(kDeviceTimeout)) {
          seen += (seen.empty() ? "" : " | ") + describe(*frame);
          for (const ph::InputEvent& e : frame->events) {
            if (e.type == ev::kKey && e.code == ev::kBtnLeft) left.push_back(e.value);
          }
        }
        check.expect(left == std::vector<int>{1, 0},
                     "expected BTN_LEFT 1, then 0 from the virtual device before it went away, got [" + seen + "]");
        const std::optional<int> status = daemon->wait_exit(15s);
        check.expect(
            status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0,
            "expected exit status 0, got " + (status ? describe_wait_status(*status) : "still running after 15 s"));
        check.expect(notify->expect("STOPPING=1", 1s), "expected STOPPING=1, got none");
        const bool gone =
            wait_until([] { return input_devices_named("pseudohaptic ").empty(); }, kDeviceTimeout, &uevents);
        check.expect(gone, "expected no 'pseudohaptic ...' device after the exit");
        const int grab = try_grab(mouse->node());
        check.expect(grab == 0, "EVIOCGRAB on the test mouse after the exit: expected success, got " + grab_text(grab));
        // (Which of the two won the race, said in the daemon's debug log: with -v.)
        const bool kept = daemon->log().find("events its grab kept emitted") != std::string::npos;
        check.note("the click came out: [" + seen + "]" +
                   (options.verbose && left == std::vector<int>{1, 0}
                        ? kept ? ", emitted as the mouse was let go of" : ", handed on by its reader"
                        : "") +
                   "; " + (status ? describe_wait_status(*status) : "?") +
                   ", no virtual device left, the mouse can be grabbed");
      });
}

// ---- part 4: images read by the daemon's child; a reload of a full-HD region while the mouse moves ---------

// A line "NAME:   N kB" of /proc/PID/status, in KiB; -1 when absent.
long status_kib(pid_t pid, const std::string& name) {
  std::istringstream status(read_text_file("/proc/" + std::to_string(pid) + "/status"));
  for (std::string line; std::getline(status, line);) {
    if (line.rfind(name + ":", 0) == 0) return std::stol(line.substr(name.size() + 1));
  }
  return -1;
}

// The maps of `spec`: those in `maps` when present there (written on the host), else written into `dir`.
ph::TargetFilePaths target_maps(const ph::TargetSpec& spec, const std::filesystem::path& maps,
                                const std::filesystem::path& dir) {
  if (ph::target_files_present(maps, {spec})) return ph::target_file_paths(maps, spec);
  if (!ph::target_files_present(dir, {spec})) ph::write_target_files(dir, {spec});
  return ph::target_file_paths(dir, spec);
}

// A region of `spec` at (x, y) from its maps, named by absolute path.
std::string target_region(const ph::TargetSpec& spec, const ph::TargetFilePaths& maps, int x, int y) {
  std::string region = ph::target_scene_text(spec);
  for (const auto& [key, path] :
       {std::pair{"normal_map = \"", maps.normal_map}, std::pair{"depth_map = \"", maps.depth_map}}) {
    const auto from = region.find(key) + std::strlen(key);
    region.replace(from, region.find('"', from) - from, std::filesystem::absolute(path).string());
  }
  const std::string at_origin = "x = 0\ny = 0\n";
  region.replace(region.find(at_origin), at_origin.size(), fmt::format("x = {}\ny = {}\n", x, y));
  return region;
}

// The default scene's three targets at their places, from map files.
std::string three_target_config(const Options& options) {
  struct At {
    const char* name;
    int x, y;
  };
  constexpr At kAt[] = {
      {"bump-gaussian-h1-r200", 135, 290}, {"hole-polynomial-h1-r200", 710, 290}, {"bump-linear-h1-r100", 1285, 290}};
  std::string text = daemon_table();
  for (const At& at : kAt) {
    for (const ph::TargetSpec& spec : ph::all_targets()) {
      if (spec.name() == at.name)
        text += "\n" + target_region(spec, target_maps(spec, options.scene_dir, options.scratch), at.x, at.y);
    }
  }
  return text;
}

// A [daemon] table on a desktop twice full HD wide, and one region over its left half (1920 x 1080) from
// the hole target's maps, with materials and gravity wells: what makes a load take seconds (the class
// map, the wells' pattern field). `variant` changes the filter and the wells' levels, so that a reload
// has a new scene to compute.
std::string full_hd_config(const ph::TargetSpec& spec, const ph::TargetFilePaths& maps, int variant) {
  return fmt::format(
      "[daemon]\n"
      "devices = [\"name:ph-e2e*\"]\n"
      "output = \"relative\"\n"
      "desktop = [0, 0, 3840, 1080]\n"
      "pointer_speed = 1.0\n\n"
      "[[region]]\n"
      "name = \"full-hd\"\n"
      "x = 0\ny = 0\nwidth = 1920\nheight = 1080\n"
      "method = \"curvature\"\n"
      "normal_map = \"{normal}\"\n"
      "depth_map = \"{depth}\"\n"
      "depth_zero = 0.5\n"
      "relief_px = {relief}\n\n"
      "[region.materials]\n"
      "source = \"depth\"\n"
      "filter_radius = {radius}\n"
      "parabolic = \"damping\"\n"
      "elliptic = \"friction\"\n"
      "hyperbolic = \"stick_slip\"\n\n"
      "[region.wells]\n"
      "pattern = \"contours\"\n"
      "levels = [{level}, 20.0]\n"
      "radius_px = 16.0\n",
      fmt::arg("normal", std::filesystem::absolute(maps.normal_map).string()),
      fmt::arg("depth", std::filesystem::absolute(maps.depth_map).string()), fmt::arg("relief", 2.0 * spec.relief_px),
      fmt::arg("radius", 2 + variant), fmt::arg("level", 10.0 + variant));
}

// One motion frame every 8 ms (a 125 Hz mouse; REL_X +4 and -4 in turn over the flat part, so the
// output is the input) until `done`: the latency of each, from just before the write into the test mouse
// to just after the read from `out`. Paced alike with and without a reload, so that both medians see a
// daemon that waited 8 ms between frames.
template <typename Done>
void paced_latency(Check& check, TestMouse& mouse, EventReader& out, ph::Pipeline& model, Latency& result, Done done) {
  for (int i = 0; !done(); ++i) {
    const auto next = Clock::now() + 8ms;
    const Frame in = make_frame({rel(ev::kRelX, i % 2 == 0 ? 4 : -4)});
    const Frame expected = untimed(model.process(in));
    const auto before = Clock::now();
    mouse.send(in);
    const std::optional<Frame> got = out.next_frame(kFrameTimeout);
    const auto after = Clock::now();
    if (!got) throw Fatal(fmt::format("frame {}: nothing came out within {} s", i, kFrameTimeout.count()));
    if (check.expect(same_events(*got, expected),
                     fmt::format("frame {}: expected [{}], got [{}]", i, describe(expected), describe(*got))))
      result.us.push_back(std::chrono::duration<double, std::micro>(after - before).count());
    std::this_thread::sleep_until(next);
  }
}

void reload_part(Report& report, const Options& options, Latency& steady, Latency& reloading) {
  Session session(report, "daemon reloading a full-HD region with materials and wells (-c)");
  const UeventMonitor uevents;
  const std::filesystem::path config = options.scratch / "reload.toml";
  const std::string virtual_name = "pseudohaptic ph-e2e reload mouse";
  const std::string control_path = (options.scratch / "control-reload").string();
  const ph::TargetSpec hole = hole_target();
  std::optional<TestMouse> mouse;
  std::optional<EventReader> out;
  std::unique_ptr<NotifySocket>& notify = session.notify;
  std::unique_ptr<ChildProcess>& daemon = session.daemon;
  // The frames go over the flat right half, where relative output is the input unchanged: every frame's
  // output is known exactly, whichever scene the daemon holds at that moment.
  ph::PipelineConfig flat_right = pipeline_config();
  flat_right.desktop = {0, 0, 3840, 1080};
  flat_right.start = {2880.5, 540.5};
  ph::Pipeline model(std::make_shared<const ph::Scene>(), flat_right);
  ph::TargetFilePaths hole_maps;

  session.run("[14] the default scene's three targets from image files: the daemon's memory", [&](Check& check) {
    const std::filesystem::path three = options.scratch / "three.toml";
    write_file_atomically(three, three_target_config(options));
    const auto scene = ph::load_scene(ph::parse_scene_file(three));  // here, for the size of its fields
    std::size_t field_bytes = 0;
    for (const ph::Region& region : scene.regions()) field_bytes += region.fields.bytes();
    NotifySocket three_notify((options.scratch / "notify-three.sock").string());
    ChildProcess three_daemon(std::vector<std::string>{options.daemon, "-c", three.string(), "--control", ""},
                              std::vector<std::string>{"NOTIFY_SOCKET=" + three_notify.path(), "LANG=C.UTF-8"},
                              (options.scratch / "daemon-three.log").string());
    if (!wait_ready(three_notify, three_daemon, 120s)) throw Fatal("no READY=1 within 120 s");
    const std::string maps = read_text_file("/proc/" + std::to_string(three_daemon.pid()) + "/maps");
    const long rss = status_kib(three_daemon.pid(), "VmRSS"), peak = status_kib(three_daemon.pid(), "VmHWM");
    three_daemon.signal(SIGTERM);
    three_daemon.wait_exit(30s);
    check.expect(maps.find("OpenImageIO") == std::string::npos && maps.find("ph_image_oiio") == std::string::npos,
                 "expected the daemon not to map OpenImageIO nor the image module; it does");
    const long fields_kib = static_cast<long>(field_bytes / 1024);
    check.expect(rss > 0 && rss <= 16 * 1024 + fields_kib,
                 fmt::format("expected VmRSS at most 16 MiB + the fields ({} KiB), got {} KiB", fields_kib, rss));
    check.note(fmt::format("daemon VmRSS {} KiB, of which fields {} KiB; peak (VmHWM) {} KiB; no OpenImageIO mapped",
                           rss, fields_kib, peak));
  });

  session.run("[13] start on a full-HD region with materials and wells; latency without a reload", [&](Check& check) {
    hole_maps = target_maps(hole, options.scene_dir, options.scratch);
    write_file_atomically(config, full_hd_config(hole, hole_maps, 0));
    mouse.emplace("ph-e2e reload mouse");
    notify = std::make_unique<NotifySocket>((options.scratch / "notify-reload.sock").string());
    const auto start = Clock::now();
    daemon = start_daemon(options, {"-c", config.string(), "--control", control_path}, *notify, "daemon-reload.log");
    if (!wait_ready(*notify, *daemon, 180s)) throw Fatal("no READY=1 within 180 s");
    const double start_s = std::chrono::duration<double>(Clock::now() - start).count();
    const std::string node = wait_for_device(virtual_name, kDeviceTimeout, uevents);
    if (node.empty()) throw Fatal("no virtual device '" + virtual_name + "'");
    out.emplace(node);
    if (!wait_taken(*mouse, *out, kDeviceTimeout)) throw Fatal("nothing came out of " + node);
    ph::control::Client control(control_path);
    const ph::control::Reply reply =
        control.request(ph::control::format_request(ph::control::PositionRequest{*flat_right.start}), 10s);
    if (!reply.ok) throw Fatal("'position' refused: " + reply.text);
    const std::size_t frames = static_cast<std::size_t>(options.latency_frames) / 2;
    paced_latency(check, *mouse, *out, model, steady, [&] { return steady.us.size() >= frames; });
    check.note(fmt::format("READY=1 {:.1f} s after the start (the scene loaded before it); {}", start_s,
                           latency_text(steady)));
  });

  session.run("[13] SIGHUP: frames keep coming out while the new scene loads, within 2x the median", [&](Check& check) {
    write_file_atomically(config, full_hd_config(hole, hole_maps, 1));
    notify->clear();
    const std::size_t log_before = daemon->log().size();
    const double median = percentile(steady.us, 0.5);
    const auto sent_hup = Clock::now();
    daemon->signal(SIGHUP);
    if (!notify->expect("RELOADING=1", 10s)) throw Fatal("no RELOADING=1 within 10 s of SIGHUP");
    // The frames go on until the daemon says READY=1: the load runs meanwhile.
    bool ready = false;
    const auto deadline = Clock::now() + 180s;
    paced_latency(check, *mouse, *out, model, reloading, [&] {
      ready = ready || notify->expect("READY=1", 0ms);
      return ready || Clock::now() > deadline;
    });
    const double reload_s = std::chrono::duration<double>(Clock::now() - sent_hup).count();
    if (!ready) throw Fatal("no READY=1 within 180 s of SIGHUP");
    const std::string said = daemon->log().substr(std::min(log_before, daemon->log().size()));
    check.expect(said.find("reloaded: " + config.string()) != std::string::npos,
                 "expected 'reloaded: " + config.string() + "' in the daemon's log, got: " + said);
    check.expect(reloading.us.size() >= 10,
                 fmt::format("expected at least 10 frames during the reload, got {}", reloading.us.size()));
    const double during = percentile(reloading.us, 0.5);
    check.expect(during <= 2 * median,
                 fmt::format("expected the median latency during the reload within 2x the steady median ({:.0f} us), "
                             "got {:.0f} us",
                             median, during));
    check.note(
        fmt::format("READY=1 {:.1f} s after SIGHUP; {} frames meanwhile, all unchanged as expected; during "
                    "the reload {}; without a reload median {:.0f} us",
                    reload_s, reloading.us.size(), latency_text(reloading), median));
  });

  session.run("[15] SIGHUP with a truncated PNG: the reload fails naming it, the daemon keeps its scene",
              [&](Check& check) {
                // A copy of the depth map cut to a third (the maps may be on the host, read-only).
                ph::TargetFilePaths maps = hole_maps;
                const std::string bytes = read_text_file(maps.depth_map);
                maps.depth_map = options.scratch / "truncated.depth.png";
                write_file_atomically(maps.depth_map, bytes.substr(0, bytes.size() / 3));
                write_file_atomically(config, full_hd_config(hole, maps, 2));
                notify->clear();
                const std::size_t log_before = daemon->log().size();
                daemon->signal(SIGHUP);
                check.expect(notify->expect("READY=1", 120s), "expected READY=1 after the failed reload, got none");
                if (!daemon->running())
                  throw Fatal("the daemon exited: " + describe_wait_status(*daemon->wait_exit(0s)));
                std::string said;
                wait_until(
                    [&] {
                      said = daemon->log().substr(std::min(log_before, daemon->log().size()));
                      return said.find("keeping the previous scene") != std::string::npos;
                    },
                    5s);
                const std::string png = maps.depth_map.string();
                check.expect(said.find("reload failed: ") != std::string::npos && said.find(png) != std::string::npos &&
                                 said.find("keeping the previous scene") != std::string::npos,
                             "expected 'reload failed: ... " + png + " ... keeping the previous scene', got: " + said);
                Latency after{"after the failed reload", {}, 0};
                measure_latency(check, *mouse, *out, &model, 20, after);
                const std::size_t at = said.find("reload failed: ");
                if (at != std::string::npos) said = said.substr(at, said.find('\n', at) - at);
                check.note("said \"" + said + "\"; 20 frames after it as before");
              });

  // A stop during a reload does not wait for the load: here one that never ends (the scene file a FIFO no one writes;
  // a large image takes seconds), as systemd's stop timeout would run out.
  session.run(
      "[8] SIGTERM during a reload that does not end: exit 0 at once, devices gone, mouse let go", [&](Check& check) {
        const std::filesystem::path fifo = options.scratch / "reload.fifo";
        if (::mkfifo(fifo.c_str(), 0600) != 0) throw Fatal("mkfifo: " + errno_text(errno));
        std::filesystem::rename(fifo, config);
        notify->clear();
        const std::size_t log_before = daemon->log().size();
        daemon->signal(SIGHUP);
        if (!notify->expect("RELOADING=1", 10s)) throw Fatal("no RELOADING=1 within 10 s of SIGHUP");
        const auto sent = Clock::now();
        daemon->signal(SIGTERM);
        const std::optional<int> status = daemon->wait_exit(30s);
        const double took = std::chrono::duration<double>(Clock::now() - sent).count();
        check.expect(status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0,
                     "expected exit status 0 within 30 s, got " +
                         (status ? describe_wait_status(*status) : "still running (waiting for the load)"));
        check.expect(notify->expect("STOPPING=1", 1s), "expected STOPPING=1, got none");
        check.expect(wait_for_device_gone(virtual_name, kDeviceTimeout, uevents), "the virtual device is still there");
        const int grab = try_grab(mouse->node());
        check.expect(grab == 0, "EVIOCGRAB on the test mouse after the exit: expected success, got " +
                                    std::string(grab == 0 ? "success" : errno_text(grab)));
        check.expect(!std::filesystem::exists(control_path), "the control socket was left behind");
        const std::string said = daemon->log().substr(std::min(log_before, daemon->log().size()));
        check.expect(said.find("stopped (the scene load under way is not waited for)") != std::string::npos,
                     "expected 'stopped (the scene load under way is not waited for)', got: " + said);
        check.note(
            fmt::format("{} {:.2f} s after SIGTERM, the load still waiting on the FIFO; the virtual "
                        "device gone, the mouse grabbable, the control socket removed",
                        status ? describe_wait_status(*status) : "?", took));
      });
}

int usage() {
  std::fprintf(stderr,
               "usage: daemon_e2e DAEMON [--tool PSEUDOHAPTIC] [--cycles N] [--latency-frames N] [--rounds N]\n"
               "                  [--baseline BARE_REEMITTER] [--baseline-polls] [--profile-side daemon|bare]\n"
               "                  [--parts pfdr] [--scene-dir DIR] [-v]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--cycles" || arg == "--latency-frames" || arg == "--rounds") && i + 1 < argc) {
      (arg == "--cycles"   ? options.cycles
       : arg == "--rounds" ? options.rounds
                           : options.latency_frames) = std::atoi(argv[++i]);
    } else if (arg == "--baseline-polls") {
      options.baseline_polls = true;
    } else if (arg == "--profile-side" && i + 1 < argc) {
      options.profile_side = argv[++i];
      if (options.profile_side != "daemon" && options.profile_side != "bare") return usage();
    } else if (arg == "--baseline" && i + 1 < argc) {
      options.baseline = argv[++i];
    } else if (arg == "--scene-dir" && i + 1 < argc) {
      options.scene_dir = std::filesystem::absolute(argv[++i]);
    } else if (arg == "--parts" && i + 1 < argc) {
      options.parts = argv[++i];
    } else if (arg == "--tool" && i + 1 < argc) {
      options.tool = argv[++i];
    } else if (arg == "-v" || arg == "--verbose") {
      options.verbose = true;
    } else if (!arg.empty() && arg[0] != '-' && options.daemon.empty()) {
      options.daemon = arg;
    } else {
      return usage();
    }
  }
  if (options.daemon.empty() || options.cycles < 1 || options.latency_frames < 1 || options.rounds < 1) return usage();
  if (options.baseline.empty())
    options.baseline = (std::filesystem::path(argv[0]).parent_path() / "bare_reemitter").string();
  options.baseline = std::filesystem::absolute(options.baseline).string();
  options.daemon = std::filesystem::absolute(options.daemon).string();
  if (options.tool.empty()) {  // the build tree's: build/ci/daemon/pseudohapticd -> build/ci/tools/pseudohaptic
    const std::filesystem::path sibling =
        std::filesystem::path(options.daemon).parent_path().parent_path() / "tools" / "pseudohaptic";
    if (std::filesystem::exists(sibling)) options.tool = sibling.string();
  }
  options.scratch = own_scratch("ph-e2e");
  std::printf("daemon e2e: scratch folder %s\n", options.scratch.c_str());
  if (options.scene_dir.empty()) options.scene_dir = options.scratch;
  ::signal(SIGPIPE, SIG_IGN);

  std::printf("daemon e2e: %s, %d hotplug cycles, %d frames per latency figure\n", options.daemon.c_str(),
              options.cycles, options.latency_frames);
  const auto start = Clock::now();
  Report report;
  Latency passthrough{"passthrough (the test mouse's own node, no daemon)", {}, 0};
  Latency flat{"daemon, flat scene", {}, 0};
  LatencyRatio ratio;
  Latency texture{"daemon, default scene's texture", {}, 0};
  Latency steady{"daemon, full-HD region (frames beside it), no reload", {}, 0};
  Latency reloading{"daemon, the same while it reloads the region", {}, 0};
  try {
    if (options.parts.find('p') != std::string::npos) passthrough_part(report, options, passthrough);
    if (options.parts.find('f') != std::string::npos) flat_part(report, options, flat, ratio);
    if (options.parts.find('d') != std::string::npos) default_scene_part(report, options, texture);
    if (options.parts.find('r') != std::string::npos) reload_part(report, options, steady, reloading);
  } catch (const std::exception& e) {
    report.not_run("the rest", e.what());
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "latency, write into the test mouse -> read from the output node (guest clock under TCG: emulated "
      "times, compare only within one run):\n");
  for (const Latency* l : {&passthrough, &flat, &texture, &ratio.daemon, &ratio.bare, &steady, &reloading}) {
    std::printf("  %-52s %s\n", l->label.c_str(), l->us.empty() ? "not measured" : latency_text(*l).c_str());
  }
  std::printf("daemon over a flat scene / bare re-emitter%s (%d interleaved rounds): %s\n",
              options.baseline_polls ? " waiting in poll()" : "", options.rounds, ratio.text().c_str());
  std::printf("daemon e2e: %d passed, %d failed, %.1f s\n", report.passed(), report.failed(), seconds);
  return report.failed() == 0 ? 0 : 1;
}
