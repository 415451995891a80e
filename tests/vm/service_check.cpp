// Run inside the systemd VM (tests/vm/run-in-systemd-vm), as root, after `scripts/install`: drives the
// installed pseudohapticd.service through systemctl and checks what a user of the service relies on: the
// sandboxed user and its capabilities, hotplug of a mouse plugged in after the start, reloads (journal
// lines and the output frames), stop with a held button, and a crash (SIGKILL) with systemd's restart.
// Where the daemon rescales motion, the expected output is what ph::Pipeline computes here for the same
// frames over the same scene file. One PASS or FAIL line per step; the first failure stops the run (exit 1).
//
//   service_check [SCENE_DIR]     SCENE_DIR: where the scene and its images go (default /etc/pseudohaptic)
#include <grp.h>
#include <sched.h>
#include <spawn.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/desktop_geometry.hpp"
#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "control/client.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/pipeline.hpp"
#include "core/engine/targets.hpp"
#include "tests/vm/e2e_support.hpp"

namespace {

using namespace ph::e2e;
using ph::Frame;
namespace ev = ph::ev;

constexpr auto kFrameTimeout = 5s;    // a frame through the daemon under TCG
constexpr auto kDeviceTimeout = 20s;  // a virtual device appearing or going away
constexpr auto kJournalTimeout = 60s;
const std::string kUnit = "pseudohapticd.service";
const std::string kMouseName = "ph-svc mouse";
const std::string kVirtualName = "pseudohaptic ph-svc mouse";

// ---- commands ----------------------------------------------------------------------------------------------

struct CommandResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

CommandResult run(const std::string& command) {
  CommandResult result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) throw Fatal("cannot run " + command);
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  const int status = ::pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  while (!result.output.empty() && result.output.back() == '\n') result.output.pop_back();
  return result;
}

CommandResult must_run(const std::string& command) {
  CommandResult result = run(command);
  if (result.status != 0) throw Fatal(fmt::format("'{}' failed ({}): {}", command, result.status, result.output));
  return result;
}

std::string unit_property(const std::string& name) {
  return must_run(fmt::format("systemctl show -p {} --value {}", name, kUnit)).output;
}

pid_t main_pid() { return static_cast<pid_t>(std::stol(unit_property("MainPID"))); }

// The unit's journal as plain messages.
std::string journal() { return run("journalctl -u " + kUnit + " -o cat --no-pager").output; }

// Waits for a journal line containing `phrase` written after `before` (an earlier journal()); returns
// that line. Fatal on timeout.
std::string expect_journal(const std::string& before, const std::string& phrase) {
  std::string line;
  const bool found = wait_until(
      [&] {
        const std::string now = journal();
        const std::size_t at = now.find(phrase, std::min(before.size(), now.size()));
        if (at == std::string::npos) return false;
        const std::size_t begin = now.rfind('\n', at), end = now.find('\n', at);
        line = now.substr(begin == std::string::npos ? 0 : begin + 1,
                          end == std::string::npos ? std::string::npos : end - begin - 1);
        return true;
      },
      kJournalTimeout, nullptr, 250ms);
  if (!found) {
    const std::string now = journal();
    throw Fatal(fmt::format("no journal line with '{}' within {} s; new lines:\n{}", phrase, kJournalTimeout.count(),
                            now.substr(std::min(before.size(), now.size()))));
  }
  return line;
}

// ---- frames ------------------------------------------------------------------------------------------------

void pass(const std::string& step, const std::string& what) {
  std::printf("PASS %s: %s\n", step.c_str(), what.c_str());
  std::fflush(stdout);
}

// Sends `in` and checks that the virtual device emits what `model` computes. Fatal on a mismatch.
void expect_through(TestMouse& mouse, EventReader& out, ph::Pipeline& model, const Frame& in,
                    const std::string& label) {
  const Frame expected = untimed(model.process(in));
  mouse.send(in);
  if (!delivers_something(expected)) return;
  const std::optional<Frame> got = out.next_frame(kFrameTimeout);
  if (!got || !same_events(*got, expected)) {
    throw Fatal(fmt::format("{}: sent [{}], expected [{}] (offline pipeline), got [{}]", label, describe(in),
                            describe(expected), got ? describe(*got) : std::string("nothing")));
  }
}

// As daemon_e2e: wheel notches until one comes out (the grab holds from then on), then a marker frame
// read up to, so that nothing is left queued. Frames without motion leave the cursor model alone.
void wait_taken(TestMouse& mouse, EventReader& out) {
  const auto deadline = Clock::now() + kDeviceTimeout;
  bool through = false;
  while (!through && Clock::now() < deadline) {
    mouse.send(make_frame({rel(ev::kRelWheel, 1)}));
    through = out.next_frame(250ms).has_value();
  }
  if (!through) throw Fatal("nothing came out of " + out.node() + " within 20 s");
  const Frame marker = make_frame({rel(ev::kRelHWheel, 1)});
  mouse.send(marker);
  while (const std::optional<Frame> got = out.next_frame(kFrameTimeout)) {
    if (same_events(*got, marker)) return;
  }
  throw Fatal("the marker frame did not come out of " + out.node());
}

// The daemon's cursor starts where this check cannot see (the desktop's centre, whatever the desktop
// is). A long move up and left pins it at the desktop's top-left corner; the model starts there.
ph::Pipeline pin_to_corner(TestMouse& mouse, EventReader& out, const std::string& scene_file) {
  mouse.send(make_frame({rel(ev::kRelX, -5000), rel(ev::kRelY, -5000)}));
  if (!out.next_frame(kFrameTimeout)) throw Fatal("the move to the corner did not come out");
  const ph::SceneSpec spec = ph::parse_scene_file(scene_file);
  ph::PipelineConfig config;
  config.desktop = *spec.daemon.desktop;
  config.mode = spec.daemon.output;
  config.pointer_gain = spec.daemon.pointer_speed;
  config.start = ph::Vec2{static_cast<double>(config.desktop.x), static_cast<double>(config.desktop.y)};
  return ph::Pipeline(std::make_shared<const ph::Scene>(ph::load_scene(spec)), config);
}

// Frames moving `dx`, `dy` each (with a button pressed and released on the way): `count` of them.
std::vector<Frame> stroke(int count, std::int32_t dx, std::int32_t dy) {
  std::vector<Frame> frames;
  for (int i = 0; i < count; ++i) {
    std::vector<ph::InputEvent> events{rel(ev::kRelX, dx)};
    if (dy != 0) events.push_back(rel(ev::kRelY, dy));  // the kernel passes no REL event of value 0
    if (i == 3) events.push_back(key(ev::kBtnLeft, 1));
    if (i == 5) events.push_back(key(ev::kBtnLeft, 0));
    frames.push_back(make_frame(std::move(events)));
  }
  return frames;
}

// Runs the stroke through mouse and model; returns how many frames came out changed, and how many the
// `other` model would have emitted differently (to tell two scenes apart).
struct StrokeCount {
  int changed = 0, differ_from_other = 0;
};
StrokeCount run_stroke(TestMouse& mouse, EventReader& out, ph::Pipeline& model, ph::Pipeline* other,
                       const std::vector<Frame>& frames, const std::string& label) {
  StrokeCount count;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    ph::Pipeline before = model;
    const Frame expected = untimed(before.process(frames[i]));
    if (!same_events(expected, frames[i])) ++count.changed;
    if (other != nullptr && !same_events(untimed(other->process(frames[i])), expected)) ++count.differ_from_other;
    expect_through(mouse, out, model, frames[i], fmt::format("{} frame {}", label, i));
  }
  return count;
}

// ---- the scene files ---------------------------------------------------------------------------------------

ph::TargetSpec target(const std::string& name) {
  for (const ph::TargetSpec& spec : ph::all_targets()) {
    if (spec.name() == name) return spec;
  }
  throw Fatal("no target " + name);
}

// Only the test mice, a fixed desktop and relative output (what the checks' model assumes), one target
// region at (1285, 290) with `method`: right of the desktop's centre, so that the daemon's first move
// (from the centre to the corner, pin_to_corner) crosses no texture and leaves no fractional count behind.
std::string scene_text(const ph::TargetSpec& spec, const std::string& method) {
  std::string region = ph::target_scene_text(spec);
  const auto replace = [&](const std::string& from, const std::string& to) {
    const auto pos = region.find(from);
    if (pos == std::string::npos) throw Fatal("unexpected target scene text:\n" + region);
    region.replace(pos, from.size(), to);
  };
  replace("x = 0\ny = 0\n", "x = 1285\ny = 290\n");
  replace("method = \"curvature\"", "method = \"" + method + "\"");
  return "[daemon]\n"
         "devices = [\"name:ph-svc*\"]\n"
         "output = \"relative\"\n"
         "desktop = [0, 0, 1920, 1080]\n"
         "pointer_speed = 1.0\n\n" +
         region;
}

void write_file(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path next = path.string() + ".new";
  {
    std::ofstream out(next, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out) throw Fatal("cannot write " + next.string());
  }
  std::filesystem::rename(next, path);
}

// ---- the steps ---------------------------------------------------------------------------------------------

std::map<std::string, std::string> proc_status(pid_t pid) {
  std::map<std::string, std::string> fields;
  std::istringstream text(read_text_file("/proc/" + std::to_string(pid) + "/status"));
  for (std::string line; std::getline(text, line);) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    fields[line.substr(0, colon)] = value;
  }
  return fields;
}

void check_sandbox() {
  const std::string step = "the unit runs as its DynamicUser without capabilities";
  if (run("systemctl is-active --quiet " + kUnit).status != 0) {
    throw Fatal(step + ": the unit is not active: " + run("systemctl status --no-pager " + kUnit).output);
  }
  const pid_t pid = main_pid();
  std::map<std::string, std::string> status = proc_status(pid);
  std::istringstream uids(status["Uid"]);
  std::string uid;
  while (uids >> uid) {
    if (uid == "0") throw Fatal(step + ": a uid of the daemon is 0: Uid: " + status["Uid"]);
  }
  for (const char* cap : {"CapInh", "CapPrm", "CapEff", "CapBnd", "CapAmb"}) {
    if (status[cap] != "0000000000000000") throw Fatal(fmt::format("{}: {} is {}", step, cap, status[cap]));
  }
  if (status["NoNewPrivs"] != "1") throw Fatal(step + ": NoNewPrivs is " + status["NoNewPrivs"]);
  std::string groups_named;
  for (const char* name : {"input", "uinput"}) {
    const ::group* g = ::getgrnam(name);
    if (g == nullptr) throw Fatal(step + fmt::format(": no group {}", name));
    const std::string gid = std::to_string(g->gr_gid);
    if ((" " + status["Groups"] + " ").find(" " + gid + " ") == std::string::npos) {
      throw Fatal(
          fmt::format("{}: group {} ({}) not among the daemon's groups: {}", step, name, gid, status["Groups"]));
    }
    groups_named += fmt::format("{}{} ({})", groups_named.empty() ? "" : ", ", name, gid);
  }
  const std::string user = unit_property("User");
  pass(step, fmt::format("MainPID {}, User={} with uid {}, supplementary groups {}, CapInh/Prm/Eff/Bnd/Amb 0, "
                         "NoNewPrivs 1; /dev/uinput is {}",
                         pid, user, status["Uid"].substr(0, status["Uid"].find_first_of(" \t")), groups_named,
                         must_run("stat -c '%G %a' /dev/uinput").output));
}

// The embedded default scene the install started with, laid out for the displays the sandboxed daemon found under
// /sys/class/drm: the same desktop as the connectors say to this test (root, outside the sandbox), and its targets
// where default_scene_layout puts them on it.
void check_default_scene_layout() {
  const std::string step = "the embedded default scene is laid out for the VM's display";
  std::string no_display;
  const ph::Rect desktop = ph::resolve_desktop(std::nullopt, ph::kDrmDir, no_display);
  const std::string expected =
      fmt::format("the embedded default scene on the desktop {},{} {}x{} px: {}", desktop.x, desktop.y, desktop.w,
                  desktop.h, ph::default_scene_places(ph::default_scene(desktop)));
  const std::string line = expect_journal("", expected);
  pass(step, fmt::format("{} ({})", line, no_display.empty() ? "DRM connectors read in the sandbox" : no_display));
}

// The connector the VM's display is on, and the command that forces it `off` or back to `detect` (as the kernel's
// sysfs lets root do) followed by the DRM device's change event (which udev also sends for a real plug).
struct Connector {
  std::string path;  // /sys/class/drm/card0-Virtual-1
  std::string hotplug(std::string_view state) const {
    const std::string card = path.substr(0, path.find('-'));  // /sys/class/drm/card0
    return fmt::format("echo {} > {}/status && echo change > {}/uevent", state, path, card);
  }
};

Connector connected_connector(const std::string& step) {
  for (const auto& entry : std::filesystem::directory_iterator(ph::kDrmDir)) {
    std::ifstream status(entry.path() / "status");
    std::string state;
    if (status >> state && state == "connected") return {entry.path().string()};
  }
  throw Fatal(step + ": no connected connector under /sys/class/drm");
}

std::string displays_changed_line() {
  std::string no_display;
  const ph::Rect desktop = ph::resolve_desktop(std::nullopt, ph::kDrmDir, no_display);
  return fmt::format("desktop {}x{}+{}+{} (the connected displays changed)", desktop.w, desktop.h, desktop.x,
                     desktop.y);
}

// A monitor unplugged and plugged in again, without a session helper: the daemon, with desktop = "auto", reads the
// displays again and lays its default scene out anew.
void check_display_hotplug() {
  const std::string step = "a display unplugged and plugged in again: the daemon follows the connected displays";
  const Connector connector = connected_connector(step);
  std::vector<std::string> lines;
  for (const char* state : {"off", "detect"}) {
    const std::string before = journal();
    must_run(connector.hotplug(state));
    std::string no_display;
    const ph::Rect desktop = ph::resolve_desktop(std::nullopt, ph::kDrmDir, no_display);
    lines.push_back(expect_journal(before, displays_changed_line()));
    lines.push_back(expect_journal(before, "the embedded default scene laid out again for it: " +
                                               ph::default_scene_places(ph::default_scene(desktop))));
  }
  pass(step, fmt::format("{}: journal \"{}\"", connector.path, fmt::join(lines, "\", \"")));
}

// A session helper's layout knows how the displays are arranged, which sysfs does not: while the connection that
// gave it is open, a display change is the helper's to report. Once it has closed (the user logged out), the next
// change is followed from the displays again; before, the helper's desktop stayed until the daemon restarted, and
// the cursor at the login screen was bounded by screens that were gone.
void check_display_hotplug_after_the_helper() {
  const std::string step = "a session helper's layout, kept while it is connected, then the displays followed again";
  const Connector connector = connected_connector(step);
  std::vector<std::string> lines;
  std::string before = journal();
  {
    // Layout only, as the helper sends on a Wayland desktop that gives no pointer position.
    ph::control::Client helper{std::string(ph::control::kDefaultSocket)};
    const ph::control::Reply reply = helper.request("layout 0 0 1000 700");
    if (!reply.ok) throw Fatal(step + ": the layout was refused: " + reply.text);
    lines.push_back(expect_journal(before, "desktop 1000x700+0+0 (from the session helper)"));
    before = journal();
    must_run(connector.hotplug("off"));
    lines.push_back(expect_journal(before, "the session helper's layout stays"));
    const std::optional<ph::control::Status> status = ph::control::parse_status(helper.request("status").text);
    if (!status || status->desktop != ph::Rect{0, 0, 1000, 700})
      throw Fatal(step + ": the daemon left the helper's layout while the helper was connected");
    before = journal();
  }
  lines.push_back(expect_journal(before, "stays until the connected displays change"));
  before = journal();
  must_run(connector.hotplug("detect"));
  lines.push_back(expect_journal(before, "following the displays"));
  lines.push_back(expect_journal(before, displays_changed_line()));
  pass(step, fmt::format("journal \"{}\"", fmt::join(lines, "\", \"")));
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path dir = argc > 1 ? argv[1] : "/etc/pseudohaptic";
  const std::string scene_file = (dir / "scene.toml").string();
  try {
    check_sandbox();
    check_default_scene_layout();
    check_display_hotplug();
    check_display_hotplug_after_the_helper();
    const UeventMonitor uevents;

    // A scene file, applied by `systemctl reload` (the install ran the embedded default scene).
    const ph::TargetSpec hole = target("hole-polynomial-h1-r200");
    ph::write_target_files(dir, {hole});
    write_file(scene_file, scene_text(hole, "curvature"));
    // The first image read loads the image module and its ~270 libraries (in the daemon's image reader
    // child); read over 9p under emulation that takes many seconds. Reading the scene once here puts
    // those files in the page cache first, so that the reload below is quick.
    const auto warm_start = Clock::now();
    must_run("pseudohaptic check-config --quiet " + scene_file);
    const double warm_s = std::chrono::duration<double>(Clock::now() - warm_start).count();
    std::string before = journal();
    must_run("systemctl reload " + kUnit);
    std::string line = expect_journal(before, "reloaded: " + scene_file);
    pass("systemctl reload with a scene file applies it",
         fmt::format("journal: \"{}\" (pseudohaptic check-config on it first: {:.1f} s)", line, warm_s));

    // Hotplug: a mouse plugged in now is taken (udev inside the sandbox tells the daemon).
    const auto plugged = Clock::now();
    TestMouse mouse(kMouseName);
    const std::string node = wait_for_device(kVirtualName, kDeviceTimeout, uevents);
    if (node.empty()) throw Fatal("no virtual device '" + kVirtualName + "' within 20 s of plugging the mouse in");
    std::optional<EventReader> out(std::in_place, node);
    wait_taken(mouse, *out);
    const double taken_s = std::chrono::duration<double>(Clock::now() - plugged).count();
    const int grab = try_grab(mouse.node());
    if (grab != EBUSY) throw Fatal("EVIOCGRAB on the plugged-in mouse: expected EBUSY, got " + errno_text(grab));
    ph::Pipeline model = pin_to_corner(mouse, *out, scene_file);
    // From the corner to the left of the hole, then right across it (x 1200 -> 1680).
    run_stroke(mouse, *out, model, nullptr, {make_frame({rel(ev::kRelX, 1200), rel(ev::kRelY, 540)})}, "approach");
    StrokeCount across = run_stroke(mouse, *out, model, nullptr, stroke(60, 8, 0), "across the hole");
    if (across.changed == 0) throw Fatal("the hole changed no frame of the stroke across it");
    pass("a mouse plugged in after the start is taken and its frames come out as the offline pipeline says",
         fmt::format("{} appeared and the mouse was grabbed (EBUSY) {:.1f} s after the plug; 61 frames equal to "
                     "ph::Pipeline over {}, {} changed by the region",
                     node, taken_s, scene_file, across.changed));

    // A changed scene: the same region with the depth method.
    ph::Pipeline previous = model;
    write_file(scene_file, scene_text(hole, "depth"));
    before = journal();
    must_run("systemctl reload " + kUnit);
    line = expect_journal(before, "reloaded: " + scene_file);
    model.set_scene(std::make_shared<const ph::Scene>(ph::load_scene(ph::parse_scene_file(scene_file))));
    StrokeCount back = run_stroke(mouse, *out, model, &previous, stroke(60, -8, 0), "back across (depth)");
    if (back.differ_from_other == 0) throw Fatal("the depth scene emitted what the curvature scene would have");
    pass("systemctl reload with a changed scene applies it",
         fmt::format("journal: \"{}\"; 60 frames equal to the new scene's pipeline, {} of them different from "
                     "what the previous scene gives",
                     line, back.differ_from_other));

    // An invalid scene: logged, the previous one kept.
    write_file(scene_file, scene_text(hole, "depth") + "bogus_key = 1\n");
    before = journal();
    must_run("systemctl reload " + kUnit);
    line = expect_journal(before, "keeping the previous scene");
    if (run("systemctl is-active --quiet " + kUnit).status != 0) throw Fatal("the unit is not active after it");
    StrokeCount again = run_stroke(mouse, *out, model, nullptr, stroke(60, 8, 0), "across again");
    pass("systemctl reload with an invalid scene keeps the previous one",
         fmt::format("journal: \"{}\"; still active; 60 frames as the depth scene, {} changed", line, again.changed));
    // A scene whose image lies under /root, which the sandbox hides (ProtectHome=yes): check-config reads it; the
    // service cannot, says why and keeps its scene.
    const std::string hidden_dir = "/root/ph-service-check";
    must_run("mkdir -p " + hidden_dir + " && cp " + dir.string() + "/" + hole.name() + ".normal.png " + hidden_dir +
             "/");
    std::string hidden_scene = scene_text(hole, "curvature");
    const std::string image = "normal_map = \"" + hole.name() + ".normal.png\"";
    const std::size_t image_at = hidden_scene.find(image);
    if (image_at == std::string::npos) throw Fatal("the scene text has no '" + image + "'");
    hidden_scene.replace(image_at, image.size(), "normal_map = \"" + hidden_dir + "/" + hole.name() + ".normal.png\"");
    write_file(scene_file, hidden_scene);
    const CommandResult checked = run("pseudohaptic check-config " + scene_file);
    if (checked.status != 0 ||
        checked.output.find("lies under /root, which pseudohapticd.service cannot read") == std::string::npos)
      throw Fatal("pseudohaptic check-config on the scene with an image under /root: " + checked.output);
    before = journal();
    must_run("systemctl reload " + kUnit);
    line = expect_journal(before, "(/root is hidden from pseudohapticd.service, ProtectHome=yes");
    expect_journal(before, "keeping the previous scene");
    if (run("systemctl is-active --quiet " + kUnit).status != 0) throw Fatal("the unit is not active after it");
    pass("an image under /root: check-config warns, the service's reload says the sandbox hides it and keeps its scene",
         fmt::format("journal: \"{}\"", line));
    must_run("rm -r " + hidden_dir);
    write_file(scene_file, scene_text(hole, "depth"));  // valid again, for the starts that follow

    // stop with a button held through the daemon.
    expect_through(mouse, *out, model, make_frame({key(ev::kBtnLeft, 1)}), "press");
    const std::vector<std::uint16_t> down = out->keys_down();
    if (std::find(down.begin(), down.end(), ev::kBtnLeft) == down.end()) throw Fatal("BTN_LEFT is not down");
    // Read while the daemon stops. The kernel discards what is unread when a device goes,
    // and the daemon waits 50 ms after the release: under emulation, with systemd and journald busy with
    // the stop, this reader must be first in line to read within that time (a real-time priority, not
    // inherited by the commands it runs).
    sched_param realtime{};
    realtime.sched_priority = 50;
    if (::sched_setscheduler(0, SCHED_FIFO | SCHED_RESET_ON_FORK, &realtime) != 0) {
      throw Fatal("sched_setscheduler: " + errno_text(errno));
    }
    // And it must be reading when the stop begins, not waiting for systemctl to exit: spawned, reaped later.
    pid_t systemctl = -1;
    {
      const char* args[] = {"systemctl", "stop", kUnit.c_str(), nullptr};
      if (::posix_spawnp(&systemctl, "systemctl", nullptr, nullptr, const_cast<char**>(args), environ) != 0) {
        throw Fatal("cannot run systemctl stop");
      }
    }
    bool released = false;
    std::string seen;
    while (const std::optional<Frame> frame = out->next_frame(kDeviceTimeout)) {
      seen += (seen.empty() ? "" : " | ") + describe(*frame);
      for (const ph::InputEvent& e : frame->events) {
        released = released || (e.type == ev::kKey && e.code == ev::kBtnLeft && e.value == 0);
      }
    }
    sched_param normal{};
    ::sched_setscheduler(0, SCHED_OTHER, &normal);
    int stop_status = 0;
    ::waitpid(systemctl, &stop_status, 0);
    if (!WIFEXITED(stop_status) || WEXITSTATUS(stop_status) != 0) throw Fatal("systemctl stop failed");
    if (!released) throw Fatal("no BTN_LEFT release from the virtual device at stop; got [" + seen + "]");
    if (!wait_for_device_gone(kVirtualName, kDeviceTimeout, uevents)) throw Fatal("the virtual device stayed");
    if (!wait_until([&] { return unit_property("ActiveState") == "inactive"; }, 30s, nullptr, 250ms)) {
      throw Fatal("the unit is " + unit_property("ActiveState") + " 30 s after systemctl stop");
    }
    const int after_stop = try_grab(mouse.node());
    if (after_stop != 0) throw Fatal("EVIOCGRAB on the mouse after stop: " + errno_text(after_stop));
    mouse.send(make_frame({key(ev::kBtnLeft, 0)}));
    pass("systemctl stop releases the held button and the grab",
         fmt::format("the virtual device sent [{}] and went away; EVIOCGRAB on the mouse succeeds; unit {}", seen,
                     unit_property("ActiveState")));

    // kill -9: the kernel lets go, systemd restarts the daemon, the mouse is taken again.
    must_run("systemctl start " + kUnit);
    const std::string node2 = wait_for_device(kVirtualName, kDeviceTimeout, uevents);
    if (node2.empty()) throw Fatal("no virtual device after systemctl start");
    out.emplace(node2);
    wait_taken(mouse, *out);
    const pid_t killed = main_pid();
    const std::string restarts_before = unit_property("NRestarts");
    before = journal();
    ::kill(killed, SIGKILL);
    const auto killed_at = Clock::now();
    while (out->next_frame(kDeviceTimeout)) {
    }
    if (!out->gone()) throw Fatal("the virtual device stayed after kill -9");
    // The dying process closes its descriptors one by one: the mouse's may close a moment after the
    // virtual device's. Systemd restarts it only after RestartSec=2s.
    int after_kill = EBUSY;
    wait_until([&] { return (after_kill = try_grab(mouse.node())) == 0; }, 1500ms, nullptr, 10ms);
    const double released_s = std::chrono::duration<double>(Clock::now() - killed_at).count();
    if (after_kill != 0) {
      throw Fatal(fmt::format("EVIOCGRAB on the mouse {:.2f} s after kill -9: {}", released_s, errno_text(after_kill)));
    }
    line = expect_journal(before, "status=9/KILL");
    std::optional<pid_t> restarted;
    wait_until(
        [&] {
          const pid_t now = main_pid();
          if (now != 0 && now != killed && unit_property("ActiveState") == "active") restarted = now;
          return restarted.has_value();
        },
        60s, nullptr, 250ms);
    if (!restarted) throw Fatal("systemd did not restart the daemon within 60 s: " + unit_property("ActiveState"));
    const std::string node3 = wait_for_device(kVirtualName, kDeviceTimeout, uevents);
    if (node3.empty()) throw Fatal("no virtual device after the restart");
    out.emplace(node3);
    wait_taken(mouse, *out);
    const double back_s = std::chrono::duration<double>(Clock::now() - killed_at).count();
    if (try_grab(mouse.node()) != EBUSY) throw Fatal("the mouse is not grabbed after the restart");
    model = pin_to_corner(mouse, *out, scene_file);
    run_stroke(mouse, *out, model, nullptr, {make_frame({rel(ev::kRelX, 1200), rel(ev::kRelY, 540)})}, "approach");
    StrokeCount restarted_stroke = run_stroke(mouse, *out, model, nullptr, stroke(60, 8, 0), "after the restart");
    pass(
        "kill -9: the kernel drops the grab and the virtual device, systemd restarts the daemon, the mouse is "
        "taken again",
        fmt::format("device gone and EVIOCGRAB free {:.2f} s after SIGKILL; journal: \"{}\"; MainPID {} -> {}, "
                    "NRestarts {} -> {}; mouse taken again {:.1f} s after the kill; 61 frames as the pipeline, {} "
                    "changed",
                    released_s, line, killed, *restarted, restarts_before, unit_property("NRestarts"), back_s,
                    restarted_stroke.changed));

    // Options through a drop-in, with no path in it (docs/SERVICE.md, "Logs"): $PSEUDOHAPTICD_OPTIONS unset gives
    // the daemon no argument; set to --verbose, it runs with it and logs its debug lines.
    const auto arguments = [](pid_t pid) {
      std::string text = read_text_file("/proc/" + std::to_string(pid) + "/cmdline");
      std::replace(text.begin(), text.end(), '\0', ' ');
      return text;
    };
    const std::string plain = arguments(*restarted);
    if (plain.find(' ') != plain.size() - 1) throw Fatal("the daemon has arguments without a drop-in: " + plain);
    const std::string drop_in = "/etc/systemd/system/" + kUnit + ".d/verbose.conf";
    must_run("mkdir -p /etc/systemd/system/" + kUnit +
             ".d && printf '[Service]\\nEnvironment=PSEUDOHAPTICD_OPTIONS="
             "--verbose\\n' > " +
             drop_in + " && systemctl daemon-reload");
    before = journal();
    must_run("systemctl restart " + kUnit);
    const std::string debug_line = expect_journal(before, "not a pointer (needs REL_X, REL_Y and a button)");
    const std::string verbose = arguments(main_pid());
    if (verbose.find(" --verbose ") == std::string::npos) throw Fatal("the drop-in's option is not passed: " + verbose);
    must_run("rm " + drop_in + " && rmdir --ignore-fail-on-non-empty /etc/systemd/system/" + kUnit +
             ".d && systemctl daemon-reload && systemctl restart " + kUnit);
    pass("a drop-in's Environment=PSEUDOHAPTICD_OPTIONS=--verbose reaches the daemon",
         fmt::format("command line '{}' without it, '{}' with it; journal: \"{}\"", plain, verbose, debug_line));
  } catch (const std::exception& e) {
    std::printf("FAIL %s\n", e.what());
    std::printf("---- journal of %s ----\n%s\n", kUnit.c_str(), journal().c_str());
    return 1;
  }
  return 0;
}
