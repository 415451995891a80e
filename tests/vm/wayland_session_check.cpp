// pseudohaptic-session's Wayland backend against a real compositor: weston's headless backend (one output,
// 3200x1800 at scale 2: 1600x900 logical pixels, so only a client that reads xdg-output's logical size
// gets it right) and a stand-in for the daemon's control socket. Runs in the VM of tests/vm/run-in-vm
// (scripts/vm-test), or anywhere weston is installed, as any user:
//
//   wayland_session_check SESSION [--daemon PSEUDOHAPTICD] [--weston PATH] [--scratch DIR]
//
// Cases: (1) with weston alone the helper picks the wayland backend by itself (WAYLAND_DISPLAY set, DISPLAY
// too), says the layout and nothing else (no `helper` line: weston gives no pointer position); reconnects
// after the socket goes away and comes back; exits 0 on SIGTERM. (2) with a stand-in Hyprland request socket
// beside it ($XDG_RUNTIME_DIR/hypr/SIGNATURE/.socket.sock), it says `helper wayland-hyprland`, the layout
// and the position Hyprland gives, and answers a `query` with the new one. (3) with a stand-in Wayfire IPC
// socket ($WAYFIRE_SOCKET), `helper wayland-wayfire` and its position; with one that answers as Wayfire
// without its ipc-rules plugin does, the layout only. (4) with --daemon (it needs /dev/uinput: the VM), the
// real daemon on its default scene takes weston's layout from the helper: `status` says
// desktop=0,0,1600,900 and helper=no, and the daemon logs that its third target is partly off that desktop. (5) with a
// stand-in KWin (tests/kwin_stand_in.hpp) on a private session bus and XDG_CURRENT_DESKTOP=KDE, `helper wayland-kwin`,
// the layout and the position the script sends, the newest one for a `query`, and the script unloaded at SIGTERM; with
// a KWin that refuses the script, the layout only and KWin's refusal in the helper's log (skipped without dbus-daemon).
// (6) when weston stops, the helper exits with status 1. tests/vm/README.md, "Wayland: weston", has the figures.
#include <fmt/format.h>
#include <sys/stat.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "tests/kwin_stand_in.hpp"
#include "tests/vm/control_stub.hpp"
#include "tests/vm/e2e_support.hpp"

namespace {

using namespace ph::e2e;
namespace fs = std::filesystem;

constexpr const char* kSocketName = "ph-wayland-1";
constexpr const char* kLayout = "layout 0 0 1600 900";  // weston's logical size, not its 3200x1800 mode

using Options = SessionCheckOptions;  // compositor: weston

// A listening, non-blocking Unix socket at `path` for a stand-in compositor.
Fd listen_on(const std::string& what, const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  Fd listener(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!listener || ::bind(listener.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0 ||
      ::listen(listener.get(), 8) < 0) {
    throw Fatal(what + " at " + path + ": " + errno_text(errno));
  }
  return listener;
}

// A stand-in compositor's socket at `path`: hands each connection to `answer` on a thread of its own until it is
// destroyed, then removes the socket file. Declared last in its owner, so that the thread ends before the state
// `answer` uses.
class StandInSocket {
 public:
  StandInSocket(const std::string& what, const std::string& path, std::function<void(int client)> answer)
      : path_(path), answer_(std::move(answer)), listener_(listen_on(what, path)), thread_([this] { serve(); }) {}
  ~StandInSocket() {
    stop_ = true;
    thread_.join();
    ::unlink(path_.c_str());
  }
  StandInSocket(const StandInSocket&) = delete;
  StandInSocket& operator=(const StandInSocket&) = delete;

 private:
  void serve() {
    while (!stop_) {
      pollfd p{listener_.get(), POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      const Fd client(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC));
      if (client) answer_(client.get());
    }
  }

  std::string path_;
  std::function<void(int client)> answer_;
  Fd listener_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A stand-in for Hyprland's request socket: each connection reads a request and gets "X, Y" for
// `cursorpos` (then the end of the connection, as Hyprland does); counts the questions.
class FakeHyprland {
 public:
  explicit FakeHyprland(const std::string& path)
      : socket_("fake Hyprland socket", path, [this](int client) { answer(client); }) {}

  void move_to(int x, int y) { at_ = (static_cast<long long>(x) << 32) | static_cast<unsigned>(y); }
  int questions() const { return questions_; }

 private:
  void answer(int client) {
    char request[64] = {};
    pollfd c{client, POLLIN, 0};
    if (::poll(&c, 1, 2000) <= 0) return;
    const ssize_t n = ::recv(client, request, sizeof request - 1, 0);
    if (n <= 0 || std::string_view(request, static_cast<std::size_t>(n)) != "cursorpos") return;
    ++questions_;
    const long long at = at_;
    const std::string reply = fmt::format("{}, {}", static_cast<int>(at >> 32), static_cast<int>(at & 0xffffffff));
    (void)::send(client, reply.data(), reply.size(), MSG_NOSIGNAL);
  }

  std::atomic<long long> at_{0};
  std::atomic<int> questions_{0};
  StandInSocket socket_;
};

// A stand-in for Wayfire's IPC socket: each message (a 32-bit length in the machine's byte order, then
// JSON) that asks for window-rules/get_cursor_position gets `reply`, framed the same way.
class FakeWayfire {
 public:
  FakeWayfire(const std::string& path, std::string reply)
      : reply_(std::move(reply)), socket_("fake Wayfire socket", path, [this](int client) { answer(client); }) {}

  int questions() const { return questions_; }

 private:
  static std::string read_exactly(int fd, std::size_t n) {
    std::string data;
    char buffer[512];
    while (data.size() < n) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 2000) <= 0) break;
      const ssize_t got = ::recv(fd, buffer, std::min(sizeof buffer, n - data.size()), 0);
      if (got <= 0) break;
      data.append(buffer, static_cast<std::size_t>(got));
    }
    return data;
  }
  void answer(int client) {
    const std::string header = read_exactly(client, 4);
    if (header.size() != 4) return;
    std::uint32_t length = 0;
    std::memcpy(&length, header.data(), 4);
    if (length > 4096) return;
    const std::string request = read_exactly(client, length);
    if (request.find("\"window-rules/get_cursor_position\"") == std::string::npos) return;
    ++questions_;
    const auto reply_length = static_cast<std::uint32_t>(reply_.size());
    std::string framed(4, '\0');
    std::memcpy(framed.data(), &reply_length, 4);
    framed += reply_;
    (void)::send(client, framed.data(), framed.size(), MSG_NOSIGNAL);
  }

  std::string reply_;
  std::atomic<int> questions_{0};
  StandInSocket socket_;
};

using Case = HelperCase;

std::vector<std::string> session_environment(const fs::path& runtime, const std::string& signature,
                                             const std::string& wayfire_socket = "") {
  std::vector<std::string> env{"XDG_RUNTIME_DIR=" + runtime.string(), std::string("WAYLAND_DISPLAY=") + kSocketName,
                               "DISPLAY=:99",  // an X display too, as under Xwayland: auto must still pick wayland
                               "PATH=/usr/bin:/bin"};
  if (!signature.empty()) env.push_back("HYPRLAND_INSTANCE_SIGNATURE=" + signature);
  if (!wayfire_socket.empty()) env.push_back("WAYFIRE_SOCKET=" + wayfire_socket);
  return env;
}

void check_sigterm(ChildProcess& helper, Case& c) {
  helper.signal(SIGTERM);
  const std::optional<int> status = helper.wait_exit(10s);
  if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 0)
    c.problems.push_back("SIGTERM: " + (status ? describe_wait_status(*status) : std::string("still running")));
}

// A helper started into `helper` against a fresh control stub that tells the daemon the layout and nothing more, and
// says why in its log (`notice`, e.g. the plugin or the answer it lacked); then exits 0 on SIGTERM. `when` names the
// setting in the problems.
void expect_layout_only(const Options& options, std::optional<ChildProcess>& helper, std::vector<std::string> env,
                        const std::string& log, const std::string& when, const std::string& notice, Case& c) {
  ControlStub stub((options.scratch / "control").string());
  helper.reset();
  helper.emplace(std::vector<std::string>{options.session, "--control", stub.path(), "-v"}, std::move(env),
                 (options.scratch / log).string());
  if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
  c.expect(stub, kLayout, when + ", at start");
  c.expect_silence(stub, 1s, when + ", after the layout");
  if (helper->log().find(notice) == std::string::npos)
    c.problems.push_back(when + ": no notice with '" + notice + "' in the helper's log");
  check_sigterm(*helper, c);
}

bool layout_only_case(const Options& options, const fs::path& runtime) {
  Case c{"weston: the layout from xdg-output, no position, reconnection, SIGTERM", {}};
  ControlStub stub((options.scratch / "control").string());
  ChildProcess helper({options.session, "--control", stub.path(), "-v"}, session_environment(runtime, ""),
                      (options.scratch / "session-weston.log").string());
  try {
    if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
    c.expect(stub, kLayout, "at start");
    c.expect_silence(stub, 1s, "after the layout (weston says nothing of the pointer)");
    stub.send("query");  // not a helper: the daemon would never ask, and it has nothing to say
    c.expect_silence(stub, 1s, "after a query");
    stub.stop();
    std::this_thread::sleep_for(700ms);
    stub.restart();
    if (!stub.accept(20s)) throw Fatal("the helper did not reconnect within 20 s");
    c.expect(stub, kLayout, "after reconnecting");
    check_sigterm(helper, c);
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

// A daemon that takes the connection and then refuses the helper (its session is in the background, or the socket has
// too many clients) and closes it: the helper tries again ever more slowly (250 ms, 0.5, 1, 2, 4 s), not every 250 ms.
bool refused_case(const Options& options, const fs::path& runtime) {
  Case c{"weston: a daemon that refuses the helper: it tries again ever more slowly", {}};
  ControlStub stub((options.scratch / "control").string());
  ChildProcess helper({options.session, "--control", stub.path(), "-v"}, session_environment(runtime, ""),
                      (options.scratch / "session-refused.log").string());
  try {
    if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
    const auto first = Clock::now();
    std::vector<double> at;
    do {
      at.push_back(std::chrono::duration<double>(Clock::now() - first).count());
      stub.next_line(2s);  // its first request (the layout)
      stub.send("error permission denied: uid 1000 is neither root nor the user of an active local session");
      stub.drop_client();
    } while (Clock::now() - first < 5s && stub.accept(first + 5s - Clock::now()));
    // 0, 0.25, 0.75, 1.75 and 3.75 s, give or take the helper's own time; every 250 ms would be about 20.
    if (at.size() > 6 || at.size() < 3)
      c.problems.push_back(fmt::format("{} connections in 5 s, at [{:.2f}] s", at.size(), fmt::join(at, ", ")));
    std::printf("    %zu connections in 5 s, at [%s] s\n", at.size(),
                fmt::format("{:.2f}", fmt::join(at, ", ")).c_str());
    check_sigterm(helper, c);
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

bool hyprland_case(const Options& options, const fs::path& runtime) {
  Case c{"weston's layout with a stand-in Hyprland socket: helper, layout, position, query", {}};
  const std::string signature = "ph_fake_hyprland";
  fs::create_directories(runtime / "hypr" / signature);
  FakeHyprland hyprland((runtime / "hypr" / signature / ".socket.sock").string());
  hyprland.move_to(812, 95);
  ControlStub stub((options.scratch / "control").string());
  ChildProcess helper({options.session, "--control", stub.path(), "--backend", "wayland", "-v"},
                      session_environment(runtime, signature), (options.scratch / "session-hyprland.log").string());
  try {
    if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
    c.expect(stub, "helper wayland-hyprland", "at start");
    c.expect(stub, kLayout, "at start");
    c.expect(stub, "position 812.5 95.5", "at start");
    hyprland.move_to(-3, 1200);
    stub.send("query");
    c.expect(stub, "position -2.5 1200.5", "after a query");
    // Once whether it answers at all, once for the position at start, once for the query.
    if (hyprland.questions() != 3)
      c.problems.push_back(fmt::format("Hyprland was asked {} times, not 3", hyprland.questions()));
    check_sigterm(helper, c);
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

bool wayfire_case(const Options& options, const fs::path& runtime) {
  Case c{"weston's layout with a stand-in Wayfire socket: with ipc-rules, then without", {}};
  const std::string socket = (runtime / "wayfire-ph.socket").string();
  std::optional<ChildProcess> helper;
  try {
    {
      FakeWayfire wayfire(socket, R"({"result": "ok", "pos": {"x": 640.25, "y": -10.5}})");
      ControlStub stub((options.scratch / "control").string());
      helper.emplace(std::vector<std::string>{options.session, "--control", stub.path(), "-v"},
                     session_environment(runtime, "", socket), (options.scratch / "session-wayfire.log").string());
      if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
      c.expect(stub, "helper wayland-wayfire", "with ipc-rules, at start");
      c.expect(stub, kLayout, "with ipc-rules, at start");
      c.expect(stub, "position 640.25 -10.5", "with ipc-rules, at start");
      check_sigterm(*helper, c);
      if (wayfire.questions() != 2)  // whether it answers at all, then the position at start
        c.problems.push_back(fmt::format("Wayfire was asked {} times, not 2", wayfire.questions()));
    }
    // Without the ipc-rules plugin Wayfire answers the method with an error: the layout only.
    FakeWayfire wayfire(socket, R"({"error": "No such method found!"})");
    expect_layout_only(options, helper, session_environment(runtime, "", socket), "session-wayfire-bare.log",
                       "without ipc-rules", "ipc-rules", c);
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(helper ? &*helper : nullptr);
}

bool kwin_case(const Options& options, const fs::path& runtime) {
  using namespace ph::kwin_stand_in;
  Case c{"weston's layout with a stand-in KWin on a private session bus: script, positions, unload; refused", {}};
  const std::optional<std::string> dbus_daemon = find_dbus_daemon();
  if (!dbus_daemon) {
    std::printf("SKIP %s: no dbus-daemon\n", c.label.c_str());
    return true;
  }
  const PrivateBus bus(*dbus_daemon, options.scratch);
  std::vector<std::string> env = session_environment(runtime, "");
  env.push_back("XDG_CURRENT_DESKTOP=KDE");
  env.push_back("DBUS_SESSION_BUS_ADDRESS=" + bus.address());
  std::optional<ChildProcess> helper;
  try {
    if (bus.address().empty()) throw Fatal("dbus-daemon printed no address");
    {
      StandInKWin kwin(bus.address(), {KWinVersion::six, false, Sent{812, 95, "ii"}});
      if (!kwin.started()) throw Fatal("the stand-in KWin did not start");
      ControlStub stub((options.scratch / "control").string());
      helper.emplace(std::vector<std::string>{options.session, "--control", stub.path(), "-v"}, env,
                     (options.scratch / "session-kwin.log").string());
      if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
      c.expect(stub, "helper wayland-kwin", "at start");
      c.expect(stub, kLayout, "at start");
      c.expect(stub, "position 812 95", "at start");  // KWin's whole pixels as they come
      kwin.send({-3.25, 1200.5, "dd"});
      if (!wait_for_stand_in([&] { return kwin.seen().replies_ok == 2; }))
        c.problems.push_back("the helper did not answer the script's second call");
      stub.send("query");
      c.expect(stub, "position -3.25 1200.5", "after a query");
      check_sigterm(*helper, c);
      const Seen seen = kwin.seen();
      if (seen.loaded.size() != 1 || seen.unloaded.size() != 2)
        c.problems.push_back(
            fmt::format("the script was loaded {} and unloaded {} times, not 1 and 2 (a stale one, "
                        "then at exit)",
                        seen.loaded.size(), seen.unloaded.size()));
      if (!seen.loaded.empty() && seen.loaded[0].first.rfind(runtime.string() + "/", 0) != 0)
        c.problems.push_back("the script's file is not in XDG_RUNTIME_DIR: " + seen.loaded[0].first);
      if (!seen.loaded.empty() && fs::exists(seen.loaded[0].first))
        c.problems.push_back("the script's file is still there after the helper exited");
    }
    StandInKWin refusing(bus.address(), {KWinVersion::six, true, Sent{1, 2, "ii"}});
    if (!refusing.started()) throw Fatal("the refusing stand-in KWin did not start");
    expect_layout_only(options, helper, env, "session-kwin-refused.log", "with a refusing KWin",
                       "scripting is disabled here", c);
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(helper ? &*helper : nullptr);
}

bool daemon_case(const Options& options, const fs::path& runtime) {
  Case c{"pseudohapticd takes weston's layout from the helper", {}};
  const std::string control = (options.scratch / "daemon.sock").string();
  ChildProcess daemon({options.daemon, "--default-scene", "--control", control}, {"PATH=/usr/bin:/bin"},
                      (options.scratch / "daemon.log").string());
  std::optional<ChildProcess> helper;
  std::string status;
  try {
    ControlClient client(control, 30s);
    status = client.request("status");
    if (status.find(" desktop=0,0,1600,900 ") != std::string::npos)
      throw Fatal("the daemon's desktop is weston's before the helper said it: " + status);
    helper.emplace(std::vector<std::string>{options.session, "--control", control, "-v"},
                   session_environment(runtime, ""), (options.scratch / "session-daemon.log").string());
    const bool told = wait_until(
        [&] {
          status = client.request("status");
          return status.find(" desktop=0,0,1600,900 ") != std::string::npos;
        },
        20s, nullptr, 100ms);
    if (!told) c.problems.push_back("the daemon's status after 20 s: " + status);
    // The default scene was laid out for the 1920 x 1080 the daemon assumed without a display: once the helper has
    // told it weston's 1600 x 900, it lays the three targets out again in the middle of that, nothing off it.
    const std::string again =
        "the embedded default scene laid out again for it: bump-gaussian-h1-r200 at 25,200, hole-polynomial-h1-r200 "
        "at 550,200, bump-linear-h1-r100 at 1075,200 (500x500 px each)";
    if (!wait_until([&] { return daemon.log().find(again) != std::string::npos; }, 5s, nullptr, 100ms))
      c.problems.push_back("expected in the daemon's log: " + again + "; it logged:\n" + daemon.log());
    if (daemon.log().find("lie on the desktop") != std::string::npos ||
        daemon.log().find("lies outside the desktop") != std::string::npos)
      c.problems.push_back("a region of the default scene was off weston's desktop; the daemon logged:\n" +
                           daemon.log());
    if (status.find(" helper=no ") == std::string::npos)
      c.problems.push_back("a layout-only helper is not the daemon's helper, but status says: " + status);
    check_sigterm(*helper, c);
    daemon.signal(SIGTERM);
    const std::optional<int> exit = daemon.wait_exit(10s);
    if (!exit || !WIFEXITED(*exit) || WEXITSTATUS(*exit) != 0)
      c.problems.push_back("the daemon on SIGTERM: " +
                           (exit ? describe_wait_status(*exit) : std::string("still running")));
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  if (!c.problems.empty()) std::printf("    the daemon's log:\n%s", daemon.log().c_str());
  return c.verdict(helper ? &*helper : nullptr);
}

bool compositor_gone_case(const Options& options, const fs::path& runtime, ChildProcess& weston) {
  Case c{"weston stops: the helper exits with status 1", {}};
  ControlStub stub((options.scratch / "control").string());
  ChildProcess helper({options.session, "--control", stub.path()}, session_environment(runtime, ""),
                      (options.scratch / "session-gone.log").string());
  try {
    if (!stub.accept(20s)) throw Fatal("the helper did not connect within 20 s");
    c.expect(stub, kLayout, "at start");
    weston.signal(SIGTERM);
    const std::optional<int> status = helper.wait_exit(20s);
    if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 1)
      c.problems.push_back("after weston stopped: " +
                           (status ? describe_wait_status(*status) : std::string("still running")));
    if (helper.log().find("went away") == std::string::npos) c.problems.push_back("no 'went away' in the helper's log");
  } catch (const Fatal& e) {
    c.problems.push_back(e.what());
  }
  return c.verdict(&helper);
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  options.compositor = "/usr/bin/weston";
  if (!parse_session_check_options(argc, argv, "--weston", options)) {
    std::fprintf(stderr,
                 "usage: wayland_session_check SESSION [--daemon PSEUDOHAPTICD] [--weston PATH] [--scratch DIR]\n");
    return 2;
  }
  try {
    options.scratch = fresh_scratch(options.scratch, "ph-wayland");
    std::printf("wayland_session_check: scratch folder %s\n", options.scratch.c_str());
    const fs::path runtime = options.scratch / "runtime";
    fs::create_directories(runtime);
    fs::permissions(runtime, fs::perms::owner_all);  // as XDG_RUNTIME_DIR must be
    const auto start = Clock::now();
    ChildProcess weston(
        {options.compositor, "--backend=headless-backend.so", std::string("--socket=") + kSocketName, "--width=1600",
         "--height=900", "--scale=2", "--shell=kiosk-shell.so", "--no-config", "--idle-time=0"},
        {"XDG_RUNTIME_DIR=" + runtime.string(), "PATH=/usr/bin:/bin"}, (options.scratch / "weston.log").string());
    if (!wait_until([&] { return fs::exists(runtime / kSocketName) || !weston.running(); }, 60s) || !weston.running()) {
      std::printf("FAIL weston did not start within 60 s; its log:\n%s", weston.log().c_str());
      return 1;
    }
    std::printf("weston listens after %.1f s\n", std::chrono::duration<double>(Clock::now() - start).count());
    std::fflush(stdout);
    int failed = 0;
    failed += !layout_only_case(options, runtime);
    failed += !refused_case(options, runtime);
    failed += !hyprland_case(options, runtime);
    failed += !wayfire_case(options, runtime);
    failed += !kwin_case(options, runtime);
    const int cases = options.daemon.empty() ? 6 : 7;
    if (!options.daemon.empty()) failed += !daemon_case(options, runtime);
    failed += !compositor_gone_case(options, runtime, weston);
    if (failed != 0) std::printf("weston's log:\n%s", weston.log().c_str());
    std::printf("wayland_session_check: %d passed, %d failed\n", cases - failed, failed);
    return failed == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::printf("FAIL %s\n", e.what());
    return 1;
  }
}
