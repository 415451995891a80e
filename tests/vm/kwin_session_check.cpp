// pseudohaptic-session's KWin backend against a real KWin: kwin_wayland (Debian 12: KWin 5.27) on a private
// session bus, with a stand-in for the daemon's control socket. Runs in the VM of tests/vm/run-in-vm under
// tests/vm/with-drm (scripts/vm-test); without --daemon it runs anywhere kwin_wayland, dbus-daemon and
// plasma-wayland-protocols are installed, as any user. Prints SKIP and exits 0 where kwin_wayland or
// dbus-daemon is missing:
//
//   kwin_session_check SESSION [--daemon PSEUDOHAPTICD] [--kwin PATH] [--scratch DIR]
//
// First KWin's virtual backend (one 1600x900 output, no GPU, no seat). It has no input backend, so the
// pointer is moved through KWin's own input pipeline with the fake-input Wayland protocol
// (org_kde_kwin_fake_input, which KWin 5 authenticates by itself). (1) With XDG_CURRENT_DESKTOP=KDE the
// helper loads its script into KWin and says `helper wayland-kwin`, the layout and KWin's start position
// (the output's QRect::center(), 799 449, reported as 798.5 448.5: KWin 5 rounds half up, the helper
// reports n - 0.5); after absolute and relative moves a `query` gets where KWin's pointer is (fractions
// kept by KWin and rounded, KWin's pointer kept at 1599 on the right edge); KWin says the script is loaded
// while the helper runs and not after SIGTERM (exit 0, the script's file gone). (2) When KWin stops, the
// helper exits with status 1.
// With --daemon, then KWin's DRM backend on the VM's bochs device (1280x800) with libinput, which opens
// its devices through logind: a stand-in logind (tests/vm/logind_stand_in.hpp) on a private system bus
// hands them over. (3) pseudohapticd (absolute output, flat acceleration, the desktop the helper said)
// takes a uinput test mouse; after each stroke the helper's report of KWin's pointer is the centre of the
// daemon's model's pixel (one pixel short on the right and bottom edges, where KWin keeps the pointer at
// W - 1); then with the helper on the daemon's own socket, five pauses and strokes (each pause makes the
// daemon ask the helper) leave the model exactly where the strokes take it.
// tests/vm/README.md, "KWin", has the figures.
#include <fmt/format.h>
#include <sys/stat.h>
#include <systemd/sd-bus.h>
#include <wayland-client.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "fake-input-client-protocol.h"
#include "tests/kwin_stand_in.hpp"
#include "tests/vm/control_stub.hpp"
#include "tests/vm/e2e_support.hpp"
#include "tests/vm/logind_stand_in.hpp"

namespace {

using namespace ph::e2e;
namespace fs = std::filesystem;
namespace ev = ph::ev;

constexpr const char* kSocketName = "ph-kwin-1";
constexpr const char* kLayout = "layout 0 0 1600 900";
constexpr const char* kPlugin = "pseudohaptic-session";  // session/kwin_cursor.hpp's kKWinScriptPlugin

// compositor: kwin_wayland; daemon: pseudohapticd, for KWin on DRM driven by the daemon as well.
using Options = SessionCheckOptions;

// A client of KWin's fake-input protocol: moves KWin's pointer as an input device would.
class FakePointer {
 public:
  explicit FakePointer(const std::string& socket_path) : display_(wl_display_connect(socket_path.c_str())) {
    if (!display_) throw Fatal("cannot connect to KWin's Wayland socket " + socket_path);
    registry_.reset(wl_display_get_registry(display_.get()));
    static const wl_registry_listener listener{&FakePointer::global, [](void*, wl_registry*, std::uint32_t) {}};
    wl_registry_add_listener(registry_.get(), &listener, this);
    wl_display_roundtrip(display_.get());
    if (!input_) throw Fatal("KWin offers no org_kde_kwin_fake_input");
    org_kde_kwin_fake_input_authenticate(input_.get(), "pseudohaptic kwin_session_check", "moves the pointer");
    sync();
  }
  void move_to(double x, double y) {
    if (version_ < 3) throw Fatal("KWin's fake input has no absolute motion (version < 3)");
    org_kde_kwin_fake_input_pointer_motion_absolute(input_.get(), wl_fixed_from_double(x), wl_fixed_from_double(y));
    sync();
  }
  void move_by(double dx, double dy) {
    org_kde_kwin_fake_input_pointer_motion(input_.get(), wl_fixed_from_double(dx), wl_fixed_from_double(dy));
    sync();
  }

 private:
  // KWin has handled every request once it answers a roundtrip sent after them.
  void sync() {
    if (wl_display_roundtrip(display_.get()) < 0) throw Fatal("KWin's Wayland connection failed");
  }
  static void global(void* data, wl_registry* registry, std::uint32_t name, const char* interface,
                     std::uint32_t version) {
    auto& self = *static_cast<FakePointer*>(data);
    if (std::string_view(interface) != org_kde_kwin_fake_input_interface.name) return;
    self.version_ = std::min<std::uint32_t>(version, 4);
    self.input_.reset(static_cast<org_kde_kwin_fake_input*>(
        wl_registry_bind(registry, name, &org_kde_kwin_fake_input_interface, self.version_)));
  }

  struct DisplayCloser {
    void operator()(wl_display* d) const { wl_display_disconnect(d); }
  };
  struct RegistryCloser {
    void operator()(wl_registry* r) const { wl_registry_destroy(r); }
  };
  struct InputCloser {
    void operator()(org_kde_kwin_fake_input* i) const { org_kde_kwin_fake_input_destroy(i); }
  };
  std::unique_ptr<wl_display, DisplayCloser> display_;  // first, so that it goes last
  std::unique_ptr<wl_registry, RegistryCloser> registry_;
  std::unique_ptr<org_kde_kwin_fake_input, InputCloser> input_;
  std::uint32_t version_ = 0;
};

// Asks KWin over the session bus whether a script is loaded under `plugin`; nullopt when it does not answer.
std::optional<bool> kwin_script_loaded(const std::string& bus_address, const char* plugin) {
  const ph::kwin_stand_in::BusPtr bus = ph::kwin_stand_in::connect_bus(bus_address);
  if (!bus) return std::nullopt;
  sd_bus_message* raw = nullptr;
  const int r = sd_bus_call_method(bus.get(), "org.kde.KWin", "/Scripting", "org.kde.kwin.Scripting", "isScriptLoaded",
                                   nullptr, &raw, "s", plugin);
  const ph::kwin_stand_in::MessagePtr reply(raw);
  int loaded = 0;
  if (r < 0 || sd_bus_message_read(reply.get(), "b", &loaded) < 0) return std::nullopt;
  return loaded != 0;
}

using Case = HelperCase;

// What KWin and the helper share: the runtime folder, a home of their own (the guest's is read-only), the bus.
std::vector<std::string> kde_environment(const Options& options, const std::string& bus_address) {
  const fs::path home = options.scratch / "home";
  return {"XDG_RUNTIME_DIR=" + (options.scratch / "runtime").string(),
          "HOME=" + home.string(),
          "XDG_CONFIG_HOME=" + (home / ".config").string(),
          "XDG_CACHE_HOME=" + (home / ".cache").string(),
          "XDG_DATA_HOME=" + (home / ".local/share").string(),
          "DBUS_SESSION_BUS_ADDRESS=" + bus_address,
          "XDG_CURRENT_DESKTOP=KDE",
          "PATH=/usr/bin:/bin"};
}

bool real_kwin_case(const Options& options, const std::string& bus_address) {
  Case c{"real KWin: script loaded, KWin's start position, absolute and relative moves, unloaded at SIGTERM", {}};
  ControlStub stub((options.scratch / "control").string());
  std::vector<std::string> env = kde_environment(options, bus_address);
  env.push_back(std::string("WAYLAND_DISPLAY=") + kSocketName);
  ChildProcess helper({options.session, "--control", stub.path(), "-v"}, env,
                      (options.scratch / "session-kwin.log").string());
  try {
    if (!stub.accept(60s)) throw Fatal("the helper did not connect within 60 s");
    c.expect(stub, "helper wayland-kwin", "at start");
    c.expect(stub, kLayout, "at start");
    c.expect(stub, "position 798.5 448.5", "at start");  // KWin starts at QRect(0, 0, 1600, 900).center(), 799 449
    if (kwin_script_loaded(bus_address, kPlugin) != std::optional<bool>(true))
      c.problems.push_back("KWin does not say that the script is loaded while the helper runs");

    FakePointer pointer((options.scratch / "runtime" / kSocketName).string());
    // Each move, then where KWin's workspace.cursorPos says the pointer is, as the helper answers a query:
    // KWin 5 names whole pixels, rounded half up from its position, which the helper reports as n - 0.5.
    // The script's call crosses the bus after KWin has moved the pointer, so the first answers may still
    // name the previous position: the helper is asked every 2 ms until it names the new one.
    std::vector<double> lags_ms;
    const auto check = [&](const std::string& move, const std::string& want) {
      const auto moved = Clock::now();
      std::vector<std::string> answers;
      while (Clock::now() - moved < 5s) {
        stub.send("query");
        const std::optional<std::string> answer = stub.next_line(5s);
        if (!answer) break;
        stub.send("ok");
        if (*answer == want) {
          lags_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - moved).count());
          return;
        }
        if (answers.empty() || answers.back() != *answer) answers.push_back(*answer);
        std::this_thread::sleep_for(2ms);
      }
      c.problems.push_back(
          fmt::format("after {}: expected '{}' within 5 s, got [{}]", move, want, fmt::join(answers, " | ")));
    };
    pointer.move_to(400, 300);
    check("an absolute move to (400, 300)", "position 399.5 299.5");
    pointer.move_by(25, -10);
    check("a relative move by (25, -10)", "position 424.5 289.5");
    pointer.move_by(0.375, 0.375);  // KWin keeps the fraction; cursorPos rounds it to the nearest pixel
    check("a move by (0.375, 0.375)", "position 424.5 289.5");
    pointer.move_by(0.375, 0.375);
    check("a second move by (0.375, 0.375)", "position 425.5 290.5");
    pointer.move_by(5000, 0);  // KWin keeps the pointer on the output: its last column is 1599
    check("a move by (5000, 0)", "position 1598.5 290.5");
    pointer.move_to(0, 899);
    check("an absolute move to (0, 899)", "position -0.5 898.5");
    if (!lags_ms.empty()) {
      std::sort(lags_ms.begin(), lags_ms.end());
      std::printf("    from KWin's move to the helper's answer: %.1f to %.1f ms over %zu moves\n", lags_ms.front(),
                  lags_ms.back(), lags_ms.size());
    }

    helper.signal(SIGTERM);
    const std::optional<int> status = helper.wait_exit(10s);
    if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 0)
      c.problems.push_back("SIGTERM: " + (status ? describe_wait_status(*status) : std::string("still running")));
    if (kwin_script_loaded(bus_address, kPlugin) != std::optional<bool>(false))
      c.problems.push_back("KWin does not say that the script is gone after the helper exited");
    for (const auto& entry : fs::directory_iterator(options.scratch / "runtime")) {
      if (entry.path().filename().string().rfind("pseudohaptic-kwin-", 0) == 0)
        c.problems.push_back("the script's file is still there: " + entry.path().string());
    }
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

bool kwin_gone_case(const Options& options, const std::string& bus_address, ChildProcess& kwin) {
  Case c{"KWin stops: the helper exits with status 1", {}};
  ControlStub stub((options.scratch / "control").string());
  std::vector<std::string> env = kde_environment(options, bus_address);
  env.push_back(std::string("WAYLAND_DISPLAY=") + kSocketName);
  ChildProcess helper({options.session, "--control", stub.path()}, env,
                      (options.scratch / "session-gone.log").string());
  try {
    if (!stub.accept(60s)) throw Fatal("the helper did not connect within 60 s");
    c.expect(stub, "helper wayland-kwin", "at start");
    kwin.signal(SIGTERM);
    const std::optional<int> status = helper.wait_exit(30s);
    if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 1)
      c.problems.push_back("after KWin stopped: " +
                           (status ? describe_wait_status(*status) : std::string("still running")));
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

// "X Y" of a `position X Y` or `ok X Y` line, nullopt for anything else.
std::optional<std::pair<double, double>> point_in(const std::string& line) {
  const std::size_t first = line.find(' ');
  if (first == std::string::npos) return std::nullopt;
  double x = 0, y = 0;
  if (std::sscanf(line.c_str() + first, " %lf %lf", &x, &y) != 2) return std::nullopt;
  return std::pair{x, y};
}

// The layout line's width and height ("layout 0 0 W H").
std::optional<std::pair<int, int>> layout_size(const std::string& line) {
  int x = 0, y = 0, w = 0, h = 0;
  if (std::sscanf(line.c_str(), "layout %d %d %d %d", &x, &y, &w, &h) != 4 || x != 0 || y != 0) return std::nullopt;
  return std::pair{w, h};
}

// The real daemon, absolute output, drives KWin's real pointer: the test mouse's strokes go through
// pseudohapticd's model to its absolute device, then libinput and KWin; the helper (on a stand-in control
// socket, so that the daemon runs without one) reports where KWin put the pointer, which must be within
// 1 px of the daemon's model on each axis.
bool daemon_drm_case(const Options& options, const std::string& bus_address,
                     const ph::logind_stand_in::StandInLogind& logind, ChildProcess& kwin_process) {
  Case c{"real KWin on DRM and libinput, driven by pseudohapticd's absolute device: the helper reports it", {}};
  ControlStub stub((options.scratch / "control").string());
  std::vector<std::string> env = kde_environment(options, bus_address);
  env.push_back(std::string("WAYLAND_DISPLAY=") + kSocketName);
  ChildProcess helper({options.session, "--control", stub.path(), "-v"}, env,
                      (options.scratch / "session-drm.log").string());
  std::optional<ChildProcess> daemon;
  try {
    if (!stub.accept(60s)) throw Fatal("the helper did not connect within 60 s");
    c.expect(stub, "helper wayland-kwin", "at start");
    const std::optional<std::string> layout = stub.next_line(20s);
    stub.send("ok");
    const std::optional<std::pair<int, int>> size = layout ? layout_size(*layout) : std::nullopt;
    if (!size) throw Fatal("expected the layout of KWin's one output, got '" + layout.value_or("nothing") + "'");
    const auto [width, height] = *size;
    // KWin starts at the output's QRect::center(), which rounds down.
    c.expect(stub, fmt::format("position {}.5 {}.5", (width - 1) / 2 - 1, (height - 1) / 2 - 1), "at start");

    const fs::path config = options.scratch / "daemon.toml";
    std::ofstream(config) << fmt::format(
        "[daemon]\ndevices = [\"name:ph-kwin*\"]\noutput = \"absolute\"\nacceleration = \"flat\"\n"
        "desktop = [0, 0, {}, {}]\npointer_speed = 1.0\n",
        width, height);
    const std::string control = (options.scratch / "daemon.sock").string();
    TestMouse mouse("ph-kwin mouse");
    daemon.emplace(std::vector<std::string>{options.daemon, "-c", config.string(), "--control", control, "-v"},
                   std::vector<std::string>{"PATH=/usr/bin:/bin"}, (options.scratch / "daemon.log").string());
    ControlClient client(control, 30s);
    // KWin has the daemon's device once libinput opened it through logind.
    std::string device;
    const bool opened = wait_until(
        [&] {
          const std::vector<std::string> nodes = input_devices_named("pseudohaptic");
          device = nodes.empty() ? "" : find_input_node(nodes.front());
          const std::vector<std::string> taken = logind.taken();
          return !device.empty() && std::find(taken.begin(), taken.end(), device) != taken.end();
        },
        60s, nullptr, 100ms);
    if (!opened) throw Fatal("KWin did not open the daemon's virtual device within 60 s (" + device + ")");
    std::this_thread::sleep_for(500ms);  // libinput adds the device after opening it

    // Strokes of the test mouse, one frame every 8 ms: then the daemon's model and KWin's pointer.
    const auto stroke = [&](const std::string& what, int frames, int dx, int dy) {
      for (int i = 0; i < frames; ++i) {
        mouse.send(make_frame({rel(ev::kRelX, dx), rel(ev::kRelY, dy)}));
        std::this_thread::sleep_for(8ms);
      }
      std::this_thread::sleep_for(300ms);  // the daemon, KWin, the script's call and the helper
      const std::string model_line = client.request("cursor");
      stub.send("query");
      const std::optional<std::string> kwin_line = stub.next_line(20s);
      stub.send("ok");
      const auto model = point_in(model_line);
      const auto kwin = kwin_line ? point_in(*kwin_line) : std::nullopt;
      std::printf("    %s: the daemon's model %s, KWin's pointer %s\n", what.c_str(), model_line.c_str(),
                  kwin_line.value_or("(no answer)").c_str());
      // The daemon's device puts KWin's pointer on the centre of the model's pixel, which the helper reports;
      // KWin keeps the pointer at W - 1 (H - 1) on the right (bottom) edge, which KWin 5 names as it names
      // the centre of the pixel before, so there the report is one pixel short.
      const auto expected = [](double model_coordinate, int size) {
        const double pixel = std::floor(model_coordinate);
        return pixel >= size - 1 ? size - 1.5 : pixel + 0.5;
      };
      if (!model || !kwin || kwin->first != expected(model->first, width) ||
          kwin->second != expected(model->second, height))
        c.problems.push_back(
            fmt::format("{}: the daemon's model '{}', so the helper should say ({}, {}), but it says '{}'", what,
                        model_line, model ? expected(model->first, width) : 0.0,
                        model ? expected(model->second, height) : 0.0, kwin_line.value_or("(no answer)")));
    };
    stroke("30 frames of (+7, -3)", 30, 7, -3);
    stroke("25 frames of (-11, +9)", 25, -11, 9);
    // Against one edge at a time: pushed into the bottom right corner, KWin on bochs died of SIGSEGV
    // (tests/vm/README.md, "KWin").
    stroke("100 frames of (+40, 0), against the right edge", 100, 40, 0);
    stroke("100 frames of (-9, -40), against the top edge", 100, -9, -40);
    stroke("100 frames of (0, +40), against the bottom edge", 100, 0, 40);
    stroke("13 frames of (+3, -5)", 13, 3, -5);

    // Now the helper is the daemon's: after each pause the daemon asks it where the cursor is before the
    // next frame goes out, and a report of where the daemon's own device put KWin's pointer must leave
    // the model where the strokes alone take it (flat acceleration at speed 1: their sum).
    helper.signal(SIGTERM);
    helper.wait_exit(10s);
    ChildProcess daemons_helper({options.session, "--control", control, "-v"}, env,
                                (options.scratch / "session-daemon.log").string());
    const bool has_helper = wait_until(
        [&] { return client.request("status").find(" helper=yes ") != std::string::npos; }, 60s, nullptr, 100ms);
    if (!has_helper) throw Fatal("the daemon has no helper after 60 s: " + client.request("status"));
    const std::optional<std::pair<double, double>> before = point_in(client.request("cursor"));
    std::pair<double, double> sum{0, 0};
    for (int pause = 0; pause < 5; ++pause) {
      std::this_thread::sleep_for(700ms);  // past the daemon's pause, so that it asks the helper
      for (int i = 0; i < 4; ++i) {
        mouse.send(make_frame({rel(ev::kRelX, 5), rel(ev::kRelY, -3)}));
        sum.first += 5;
        sum.second -= 3;
        std::this_thread::sleep_for(8ms);
      }
    }
    std::this_thread::sleep_for(300ms);
    const std::string after_line = client.request("cursor");
    const std::optional<std::pair<double, double>> after = point_in(after_line);
    std::printf(
        "    5 pauses, each followed by 4 frames of (+5, -3), the daemon asking the helper: model %s, "
        "then %s\n",
        before ? fmt::format("{} {}", before->first, before->second).c_str() : "?", after_line.c_str());
    if (!before || !after || std::abs(after->first - before->first - sum.first) > 1e-6 ||
        std::abs(after->second - before->second - sum.second) > 1e-6)
      c.problems.push_back(
          fmt::format("with the daemon asking the helper, the model moved by ({}, {}) instead of "
                      "({}, {}): a report of its own position moved it",
                      after ? after->first - before.value_or(*after).first : 0.0,
                      after ? after->second - before.value_or(*after).second : 0.0, sum.first, sum.second));
    if (c.problems.size() > 0) std::printf("    the daemon's helper's log:\n%s", daemons_helper.log().c_str());
    daemon->signal(SIGTERM);
    const std::optional<int> exit = daemon->wait_exit(10s);
    if (!exit || !WIFEXITED(*exit) || WEXITSTATUS(*exit) != 0)
      c.problems.push_back("the daemon on SIGTERM: " +
                           (exit ? describe_wait_status(*exit) : std::string("still running")));
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  if (!c.problems.empty() && daemon) std::printf("    the daemon's log:\n%s", daemon->log().c_str());
  if (!kwin_process.running())
    std::printf("    KWin exited: %s\n", describe_wait_status(*kwin_process.wait_exit(0s)).c_str());
  return c.verdict(&helper);
}

// KWin is up once it listens on its socket and answers on the bus as org.kde.KWin with /Scripting.
bool kwin_ready(const Options& options, const std::string& bus_address) {
  return fs::exists(options.scratch / "runtime" / kSocketName) && kwin_script_loaded(bus_address, kPlugin).has_value();
}

// Starts KWin (its virtual backend, or with `drm` its DRM backend with libinput under a stand-in logind)
// on a private session bus and runs the cases for it; the number that failed, `cases` counts them.
int run_kwin(const Options& options, const std::string& dbus_daemon, bool drm, int& cases) {
  fs::create_directories(options.scratch / "runtime");
  fs::permissions(options.scratch / "runtime", fs::perms::owner_all);  // as XDG_RUNTIME_DIR must be
  fs::create_directories(options.scratch / "home");
  // Debian gives kwin_wayland the file capability cap_sys_resource; where the bounding set lacks it (a
  // container) exec fails with EPERM. A copy has no capability and runs anywhere.
  const fs::path kwin = options.scratch / "kwin_wayland";
  fs::copy_file(options.compositor, kwin);
  const ph::kwin_stand_in::PrivateBus bus(dbus_daemon, options.scratch);
  if (bus.address().empty()) throw Fatal("dbus-daemon printed no address");
  std::vector<std::string> env = kde_environment(options, bus.address());
  std::optional<ph::kwin_stand_in::PrivateBus> system_bus;
  std::optional<ph::logind_stand_in::StandInLogind> logind;
  std::vector<std::string> argv{kwin.string(),           "--socket",        kSocketName, "--no-lockscreen",
                                "--no-global-shortcuts", "--no-kactivities"};
  if (drm) {
    cases += 1;
    if (!fs::exists("/dev/dri/card0") || !fs::exists("/run/udev/control")) {
      std::printf("FAIL KWin on DRM: no /dev/dri/card0 or no udevd (run it under tests/vm/with-drm in the VM)\n");
      return 1;
    }
    fs::create_directories(options.scratch / "system");
    system_bus.emplace(dbus_daemon, options.scratch / "system");
    logind.emplace(system_bus->address());
    if (!logind->started()) throw Fatal("the stand-in logind did not start");
    env.push_back("DBUS_SYSTEM_BUS_ADDRESS=" + system_bus->address());
    argv.emplace_back("--drm");
  } else {
    cases += 2;
    for (const char* a : {"--virtual", "--width", "1600", "--height", "900"}) argv.emplace_back(a);
  }
  env.push_back("KWIN_COMPOSE=Q");  // QPainter: no OpenGL, which is slow without a GPU
  // Without it KWin looks every client's program up among the desktop files (X-KDE-Wayland-Interfaces)
  // as it connects: fake input is for listed programs only, which this one is not, and under TCG the
  // lookup held the helper's connection for over a minute.
  env.push_back("KWIN_WAYLAND_NO_PERMISSION_CHECKS=1");
  const auto start = Clock::now();
  ChildProcess kwin_process(argv, env, (options.scratch / "kwin.log").string());
  const bool up =
      wait_until([&] { return kwin_ready(options, bus.address()) || !kwin_process.running(); }, 180s, nullptr, 100ms);
  if (!up || !kwin_process.running()) {
    std::printf("FAIL KWin (%s) did not start within 180 s; its log:\n%s", drm ? "DRM" : "virtual",
                kwin_process.log().c_str());
    return drm ? 1 : 2;
  }
  std::printf("KWin (%s) listens and answers on the bus after %.1f s\n", drm ? "DRM" : "virtual",
              std::chrono::duration<double>(Clock::now() - start).count());
  std::fflush(stdout);
  int failed = 0;
  if (drm) {
    failed += !daemon_drm_case(options, bus.address(), *logind, kwin_process);
  } else {
    failed += !real_kwin_case(options, bus.address());
    failed += !kwin_gone_case(options, bus.address(), kwin_process);
  }
  if (failed != 0) std::printf("KWin's log:\n%s", kwin_process.log().c_str());
  return failed;
}

int usage() {
  std::fprintf(stderr, "usage: kwin_session_check SESSION [--daemon PSEUDOHAPTICD] [--kwin PATH] [--scratch DIR]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  options.compositor = "/usr/bin/kwin_wayland";
  if (!parse_session_check_options(argc, argv, "--kwin", options)) return usage();

  if (::access(options.compositor.c_str(), X_OK) != 0) {
    std::printf("SKIP kwin_session_check: no %s (Debian: kwin-wayland)\n", options.compositor.c_str());
    return 0;
  }
  const std::optional<std::string> dbus_daemon = ph::kwin_stand_in::find_dbus_daemon();
  if (!dbus_daemon) {
    std::printf("SKIP kwin_session_check: no dbus-daemon (Debian: dbus-daemon)\n");
    return 0;
  }
  try {
    options.scratch = fresh_scratch(options.scratch, "ph-kwin");
    std::printf("kwin_session_check: scratch folder %s\n", options.scratch.c_str());
    int failed = 0, cases = 0;
    Options virtual_options = options;
    virtual_options.scratch = options.scratch / "virtual";
    failed += run_kwin(virtual_options, *dbus_daemon, false, cases);
    if (!options.daemon.empty()) {
      Options drm_options = options;
      drm_options.scratch = options.scratch / "drm";
      failed += run_kwin(drm_options, *dbus_daemon, true, cases);
    }
    std::printf("kwin_session_check: %d passed, %d failed\n", cases - failed, failed);
    return failed == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::printf("FAIL %s\n", e.what());
    return 1;
  }
}
