// pseudohaptic-session's KWin backend against a real KWin: kwin_wayland (Debian 12: KWin 5.27) with its
// virtual backend (one 1600x900 output, no GPU, no seat) on a private session bus, and a stand-in for the
// daemon's control socket. Runs in the VM of tests/vm/run-in-vm (scripts/vm-test), or anywhere
// kwin_wayland, dbus-daemon and plasma-wayland-protocols are installed; prints SKIP and exits 0 where
// kwin_wayland or dbus-daemon is missing:
//
//   kwin_session_check SESSION [--kwin PATH] [--scratch DIR]
//
// KWin's virtual backend has no input backend (only its DRM backend reads devices, through libinput, and
// only with a logind or ConsoleKit session to open them), so a uinput mouse, or the daemon's virtual
// device, does not reach it. The pointer is moved through KWin's own input pipeline instead, with the
// fake-input Wayland protocol (org_kde_kwin_fake_input, which KWin 5 offers to any client once
// KWIN_WAYLAND_NO_PERMISSION_CHECKS=1 lifts its desktop-file check, and then authenticates): what KWin does
// with a real device's motion after libinput, acceleration aside.
//
// Cases: (1) with XDG_CURRENT_DESKTOP=KDE the helper loads its script into the real KWin and says
// `helper wayland-kwin`, the layout and KWin's start position (the output's QRect::center(), 799 449);
// after absolute and relative moves a `query` gets where KWin's pointer is (whole pixels, rounded from
// KWin's fractional position, kept at 1599 at the right edge); KWin says the script is loaded while the
// helper runs, and not after SIGTERM (exit 0, the script's file gone). (2) when KWin stops, the helper
// exits with status 1. tests/vm/README.md, "KWin", has the figures.
#include <fmt/format.h>
#include <sys/stat.h>
#include <systemd/sd-bus.h>
#include <wayland-client.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "fake-input-client-protocol.h"
#include "tests/kwin_stand_in.hpp"
#include "tests/vm/control_stub.hpp"
#include "tests/vm/e2e_support.hpp"

namespace {

using namespace ph::e2e;
namespace fs = std::filesystem;

constexpr const char* kSocketName = "ph-kwin-1";
constexpr const char* kLayout = "layout 0 0 1600 900";
constexpr const char* kPlugin = "pseudohaptic-session";  // session/kwin_cursor.hpp's kKWinScriptPlugin

struct Options {
  std::string session;
  std::string kwin = "/usr/bin/kwin_wayland";
  fs::path scratch;
};

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

struct Case {
  std::string label;
  std::vector<std::string> problems;
  Clock::time_point start = Clock::now();
  // Reads lines until `want` (answering each with ok); what came before it is a problem.
  void expect(ControlStub& stub, const std::string& want, const std::string& when) {
    std::vector<std::string> before;
    while (const std::optional<std::string> line = stub.next_line(20s)) {
      stub.send("ok");
      if (*line == want) {
        if (!before.empty())
          problems.push_back(fmt::format("{}: '{}' came after [{}]", when, want, fmt::join(before, " | ")));
        return;
      }
      before.push_back(*line);
    }
    problems.push_back(
        fmt::format("{}: expected '{}', got [{}] and then nothing for 20 s", when, want, fmt::join(before, " | ")));
  }
  bool verdict(const ChildProcess* helper) const {
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (problems.empty()) {
      std::printf("PASS %s (%.1f s)\n", label.c_str(), seconds);
    } else {
      std::printf("FAIL %s (%.1f s):\n", label.c_str(), seconds);
      for (const std::string& p : problems) std::printf("    %s\n", p.c_str());
      if (helper != nullptr) std::printf("    the helper's log:\n%s", helper->log().c_str());
    }
    std::fflush(stdout);
    return problems.empty();
  }
};

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
    c.expect(stub, "position 799 449", "at start");  // KWin starts at QRect(0, 0, 1600, 900).center()
    if (kwin_script_loaded(bus_address, kPlugin) != std::optional<bool>(true))
      c.problems.push_back("KWin does not say that the script is loaded while the helper runs");

    FakePointer pointer((options.scratch / "runtime" / kSocketName).string());
    // Each move, then where KWin's workspace.cursorPos says the pointer is, as the helper answers a query.
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
    check("an absolute move to (400, 300)", "position 400 300");
    pointer.move_by(25, -10);
    check("a relative move by (25, -10)", "position 425 290");
    pointer.move_by(0.375, 0.375);  // KWin keeps the fraction; cursorPos rounds it to the nearest pixel
    check("a move by (0.375, 0.375)", "position 425 290");
    pointer.move_by(0.375, 0.375);
    check("a second move by (0.375, 0.375)", "position 426 291");
    pointer.move_by(5000, 0);  // KWin keeps the pointer on the output: its last column is 1599
    check("a move by (5000, 0)", "position 1599 291");
    pointer.move_to(0, 899);
    check("an absolute move to (0, 899)", "position 0 899");
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

// KWin is up once it listens on its socket and answers on the bus as org.kde.KWin with /Scripting.
bool kwin_ready(const Options& options, const std::string& bus_address) {
  return fs::exists(options.scratch / "runtime" / kSocketName) && kwin_script_loaded(bus_address, kPlugin).has_value();
}

int usage() {
  std::fprintf(stderr, "usage: kwin_session_check SESSION [--kwin PATH] [--scratch DIR]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--kwin" && i + 1 < argc) {
      options.kwin = argv[++i];
    } else if (arg == "--scratch" && i + 1 < argc) {
      options.scratch = argv[++i];
    } else if (options.session.empty() && arg.rfind("-", 0) != 0) {
      options.session = arg;
    } else {
      return usage();
    }
  }
  if (options.session.empty()) return usage();
  if (options.scratch.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    options.scratch = fs::path(tmp != nullptr ? tmp : "/tmp") / "ph-kwin";
  }
  if (::access(options.kwin.c_str(), X_OK) != 0) {
    std::printf("SKIP kwin_session_check: no %s (Debian: kwin-wayland)\n", options.kwin.c_str());
    return 0;
  }
  const std::optional<std::string> dbus_daemon = ph::kwin_stand_in::find_dbus_daemon();
  if (!dbus_daemon) {
    std::printf("SKIP kwin_session_check: no dbus-daemon (Debian: dbus-daemon)\n");
    return 0;
  }
  try {
    fs::remove_all(options.scratch);
    fs::create_directories(options.scratch / "runtime");
    fs::permissions(options.scratch / "runtime", fs::perms::owner_all);  // as XDG_RUNTIME_DIR must be
    fs::create_directories(options.scratch / "home");
    // Debian gives kwin_wayland the file capability cap_sys_resource; where the bounding set lacks it (a
    // container) exec fails with EPERM. A copy has no capability and runs anywhere.
    const fs::path kwin = options.scratch / "kwin_wayland";
    fs::copy_file(options.kwin, kwin);
    const ph::kwin_stand_in::PrivateBus bus(*dbus_daemon, options.scratch);
    if (bus.address().empty()) throw Fatal("dbus-daemon printed no address");
    std::vector<std::string> env = kde_environment(options, bus.address());
    env.push_back("KWIN_COMPOSE=Q");  // QPainter: no OpenGL, which is slow without a GPU
    // KWin offers fake input only to programs whose desktop file lists it (X-KDE-Wayland-Interfaces);
    // this test program has none.
    env.push_back("KWIN_WAYLAND_NO_PERMISSION_CHECKS=1");
    const auto start = Clock::now();
    ChildProcess kwin_process({kwin.string(), "--virtual", "--socket", kSocketName, "--width", "1600", "--height",
                               "900", "--no-lockscreen", "--no-global-shortcuts", "--no-kactivities"},
                              env, (options.scratch / "kwin.log").string());
    const bool up =
        wait_until([&] { return kwin_ready(options, bus.address()) || !kwin_process.running(); }, 180s, nullptr, 100ms);
    if (!up || !kwin_process.running()) {
      std::printf("FAIL KWin did not start within 180 s; its log:\n%s", kwin_process.log().c_str());
      return 1;
    }
    std::printf("KWin listens and answers on the bus after %.1f s\n",
                std::chrono::duration<double>(Clock::now() - start).count());
    std::fflush(stdout);
    int failed = 0;
    failed += !real_kwin_case(options, bus.address());
    failed += !kwin_gone_case(options, bus.address(), kwin_process);
    if (failed != 0) std::printf("KWin's log:\n%s", kwin_process.log().c_str());
    std::printf("kwin_session_check: %d passed, %d failed\n", 2 - failed, failed);
    return failed == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::printf("FAIL %s\n", e.what());
    return 1;
  }
}
