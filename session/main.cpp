// pseudohaptic-session: runs in the user's desktop session and tells pseudohapticd, over its control
// socket, the desktop's layout and where the real cursor is: at start, when the layout changes, and
// whenever the daemon asks. Reconnects when the daemon restarts; exits on SIGTERM, SIGINT or SIGHUP (which unloads
// the script KWin ran for it). Backends: X11 (x11_desktop.hpp) and Wayland (wayland_desktop.hpp), each
// built where its libraries are found.
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <sys/signalfd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/unique_fd.hpp"
#include "control/protocol.hpp"
#include "session/control_connection.hpp"
#include "session/desktop.hpp"
#include "session/protocol.hpp"
#ifdef PH_SESSION_X11
#include "session/x11_desktop.hpp"
#endif
#ifdef PH_SESSION_WAYLAND
#include "session/compositor_cursor.hpp"
#include "session/kwin_cursor.hpp"
#include "session/wayland_desktop.hpp"
#endif

namespace {

using Clock = std::chrono::steady_clock;
using namespace ph::session;

// One line per message on stderr; "<N>" syslog prefixes when stderr is the journal (JOURNAL_STREAM).
class Log {
 public:
  explicit Log(bool verbose) : verbose_(verbose), journal_(stderr_is_journal()) {}
  void error(const std::string& m) const { write(3, "error", m); }
  void notice(const std::string& m) const { write(5, "notice", m); }
  void info(const std::string& m) const { write(6, "info", m); }
  void debug(const std::string& m) const {
    if (verbose_) write(7, "debug", m);
  }

 private:
  static bool stderr_is_journal() {
    const char* stream = std::getenv("JOURNAL_STREAM");  // "DEVICE:INODE"
    struct stat st {};
    unsigned long long device = 0, inode = 0;
    return stream != nullptr && ::fstat(STDERR_FILENO, &st) == 0 &&
           std::sscanf(stream, "%llu:%llu", &device, &inode) == 2 && device == st.st_dev && inode == st.st_ino;
  }
  void write(int priority, const char* level, const std::string& message) const {
    if (journal_) {
      fmt::print(stderr, "<{}>{}\n", priority, message);
    } else {
      fmt::print(stderr, "pseudohaptic-session: {}: {}\n", level, message);
    }
    std::fflush(stderr);
  }
  bool verbose_, journal_;
};

// The connection to the daemon and what it has said so far; empty while there is none.
struct Link {
  std::optional<ControlConnection> connection;
  Conversation conversation;
  ph::control::LineBuffer lines;
  std::optional<std::pair<ph::Rect, std::vector<ph::Rect>>> layout_sent;  // the desktop and its outputs
  bool outputs_refused = false;  // the daemon reads `layout X Y W H` alone: layouts go without their outputs
  std::optional<bool> passthrough_sent;
  int failures = 0;  // connection attempts failed in a row
  Clock::time_point next_attempt = Clock::now();
};

class Helper {
 public:
  Helper(std::string control, std::vector<std::string> passthrough, Desktop& desktop, const Log& log)
      : control_(std::move(control)), passthrough_(std::move(passthrough)), desktop_(desktop), log_(log) {}

  // Runs until SIGTERM, SIGINT or SIGHUP arrives on `signals`; returns the exit status.
  int run(int signals) {
    for (;;) {
      if (!link_.connection && Clock::now() >= link_.next_attempt) connect();
      const Desktop::Changes changes = desktop_.read_events();
      if (changes.layout && link_.connection) send_layout();
      if (changes.focus && link_.connection) send_passthrough();
      const Watch watch = desktop_.watch();  // the session bus, where KWin's script reports the pointer
      pollfd fds[4] = {{signals, POLLIN, 0}, {desktop_.fd(), POLLIN, 0}, {-1, POLLIN, 0}, {watch.fd, watch.events, 0}};
      if (link_.connection) fds[2].fd = link_.connection->fd();
      int timeout = watch.timeout_ms;
      if (desktop_.events_queued()) {
        timeout = 0;  // read while answering: handle them before sleeping
      } else if (!link_.connection) {
        const int until_attempt = static_cast<int>(std::max<long long>(
            0, std::chrono::ceil<std::chrono::milliseconds>(link_.next_attempt - Clock::now()).count()));
        timeout = timeout < 0 ? until_attempt : std::min(timeout, until_attempt);
      }
      if (::poll(fds, 4, timeout) < 0 && errno != EINTR) {
        log_.error(fmt::format("poll: {}", std::strerror(errno)));
        return 1;
      }
      if (fds[0].revents != 0) {
        log_.info("stopping");
        return 0;
      }
      if (link_.connection && fds[2].revents != 0) read_daemon();
    }
  }

 private:
  void connect() {
    std::string why;
    std::optional<ControlConnection> connection = ControlConnection::connect(control_, why);
    if (!connection) {
      ++link_.failures;
      link_.next_attempt = Clock::now() + reconnect_delay(link_.failures);
      const std::string message = fmt::format("no pseudohapticd at {} ({}); trying again", control_, why);
      if (link_.failures == 1) {
        log_.notice(message);
      } else {
        log_.debug(message);
      }
      return;
    }
    // The failures in a row go on until the daemon takes a request: one that accepts the connection and then
    // refuses the helper (a session in the background, too many clients) is tried again ever more slowly.
    const int failures = link_.failures;
    link_ = Link{};
    link_.failures = failures;
    link_.connection = std::move(connection);
    // Said once, not on every reconnection of a helper the daemon keeps refusing; a daemon that restarted is said.
    const std::string connected = fmt::format("connected to pseudohapticd at {}", control_);
    if (!refused_) {
      log_.info(connected);
    } else {
      log_.debug(connected);
    }
    // A desktop that cannot say where the pointer is reports the layout only: as the daemon's helper it
    // would be asked for positions it cannot give, and the daemon would wait for each answer.
    if (desktop_.knows_pointer() && !send(helper_request(desktop_.backend_name()))) return;
    send_layout();
    if (link_.connection) send_position();
    if (link_.connection) send_passthrough();
  }

  void drop(const std::string& why) {
    link_.connection.reset();
    ++link_.failures;
    const std::chrono::milliseconds delay = reconnect_delay(link_.failures);
    const std::string message = fmt::format("{}; reconnecting in {} ms", why, delay.count());
    if (link_.failures == 1) {
      log_.notice(message);
    } else {
      log_.debug(message);
    }
    link_.next_attempt = Clock::now() + delay;
  }

  bool send(const std::string& line) {
    if (!link_.connection->send(line)) {
      drop("the daemon went away");
      return false;
    }
    link_.conversation.sent(line);
    log_.debug(fmt::format("sent: {}", std::string_view(line).substr(0, line.size() - 1)));
    return true;
  }

  void send_layout() {
    const std::optional<ph::Rect> desktop = desktop_.layout();
    if (!desktop) return;  // no output yet: the next change brings one
    const std::pair<ph::Rect, std::vector<ph::Rect>> layout{
        *desktop, link_.outputs_refused ? std::vector<ph::Rect>{} : desktop_.outputs()};
    if (link_.layout_sent == layout) return;
    const std::optional<std::string> line = layout_request(layout.first, layout.second);
    if (line && send(*line)) link_.layout_sent = layout;
  }

  void send_position() {
    if (!desktop_.knows_pointer()) return;
    const std::optional<ph::Vec2> at = desktop_.pointer();
    const std::optional<std::string> line = at ? position_request(*at) : std::nullopt;
    // On another X screen, or the compositor did not answer (or said a position no desktop has): nothing the daemon
    // can use. Said once when it starts and once when it ends, since without it the daemon's resync goes on from
    // its model alone.
    if (!line) {
      const std::string why =
          at ? fmt::format("the desktop said the pointer is at {}, {}, off any desktop", at->x, at->y)
             : std::string("the desktop did not say where the pointer is");
      if (!pointer_lost_) {
        log_.notice(why + "; the daemon goes on from its model until it says again");
      } else {
        log_.debug(why);
      }
      pointer_lost_ = true;
      return;
    }
    if (pointer_lost_) log_.notice("the desktop says where the pointer is again");
    pointer_lost_ = false;
    send(*line);
  }

  // Pass-through while a listed application has the focus (pseudohaptic-session(1), --passthrough).
  void send_passthrough() {
    if (passthrough_.empty()) return;
    const auto active = desktop_.active_class();
    const bool on = active && is_listed(passthrough_, active->first, active->second);
    log_.debug(fmt::format("the focus is on {}", active ? active->first + " (" + active->second + ")" : "no window"));
    if (link_.passthrough_sent == on) return;
    if (send(passthrough_request(on))) link_.passthrough_sent = on;
  }

  void read_daemon() {
    const ControlConnection::Received received = link_.connection->read_available();
    const bool in_bounds = link_.lines.append(received.data);
    std::vector<std::string> lines;
    while (std::optional<std::string> line = link_.lines.next_line()) lines.push_back(std::move(*line));
    const Conversation::Reactions reactions = link_.conversation.on_lines(lines);
    if (reactions.accepted) {
      link_.failures = 0;
      refusals_.forget();
    }
    refused_ = reactions.refused_connection || (refused_ && !reactions.accepted);
    // A refusal said again on every reconnection is logged once at error, then only with --verbose.
    for (const std::string& complaint : reactions.complaints) {
      if (refusals_.is_new(complaint)) {
        log_.error(complaint);
      } else {
        log_.debug(complaint);
      }
    }
    if (reactions.outputs_refused && !link_.outputs_refused) {
      // An older daemon: the layout without its outputs rather than none (the daemon would keep its own guess).
      log_.notice(
          "the daemon does not read the outputs of a layout (older than this helper?): sending the layout without "
          "them, so the cursor model may go where no monitor shows; restarting pseudohapticd brings its update in");
      link_.outputs_refused = true;
      link_.layout_sent.reset();
      send_layout();
    }
    if (reactions.send_position) send_position();  // once for all the queries read
    if (!link_.connection) return;
    if (!in_bounds) {
      drop(fmt::format("the daemon sent a line longer than {} bytes", ph::control::kMaxLine));
    } else if (received.closed) {
      drop("the daemon closed the connection");
    }
  }

  std::string control_;
  std::vector<std::string> passthrough_;
  Desktop& desktop_;
  const Log& log_;
  Link link_;
  Repeats refusals_;           // the daemon's complaints, said once until it accepts a request again
  bool refused_ = false;       // the daemon refused the last connection itself (see Conversation::on_line)
  bool pointer_lost_ = false;  // the last position asked for could not be given
};

std::string_view env(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr ? value : "";
}

#ifdef PH_SESSION_WAYLAND
// KWin's position through a script it runs (kwin_cursor.hpp); nullptr, with a notice, where KWin does not
// take it (no org.kde.KWin on the session bus, scripting refused, a script that sends nothing).
std::unique_ptr<CursorSource> start_kwin(const Log& log) {
  std::string why;
  std::unique_ptr<KWinCursor> kwin = KWinCursor::start(KWinOptions{}, why);
  if (!kwin) log.notice(fmt::format("no pointer position from KWin: {}; telling the daemon the layout only", why));
  return kwin;
}
#endif

std::unique_ptr<Desktop> open_desktop(const std::string& backend, const std::string& x_display,
                                      const std::string& wayland_display, const Log& log) {
#ifdef PH_SESSION_X11
  if (backend == "x11") {
    auto desktop = std::make_unique<X11Desktop>(x_display, [&log](const std::string& why) { log.error(why); });
    if (!desktop->has_randr()) log.notice("X has no RandR 1.2: the layout is the root window's size");
    return desktop;
  }
#endif
#ifdef PH_SESSION_WAYLAND
  if (backend == "wayland") {
    // A compositor that does not answer now (Wayfire without its ipc-rules plugin, a variable left from another
    // session) would leave every question of the daemon's unanswered, and the daemon waiting: not used.
    bool said_why = false;  // a notice already says why there is no position: not the generic one too
    const auto answering = [&log, &said_why](std::unique_ptr<CursorSource> cursor) {
      if (cursor && !cursor->position()) {
        log.notice(fmt::format("{} did not say where the pointer is ({}){}", cursor->name(), cursor->socket(),
                               cursor->name() == "wayfire" ? "; is Wayfire running, with its ipc-rules plugin?" : ""));
        said_why = true;
        cursor.reset();
      }
      return cursor;
    };
    std::string unmet;
    std::unique_ptr<CursorSource> cursor = answering(cursor_source_from_environment(&unmet));
    if (!unmet.empty()) {
      log.notice(unmet + ": its pointer position is not used");
      said_why = true;
    }
    const bool kwin = !cursor && kde_session(env("KDE_SESSION_VERSION"), env("XDG_CURRENT_DESKTOP"));
    if (kwin) cursor = answering(start_kwin(log));
    auto desktop = std::make_unique<WaylandDesktop>(wayland_display, std::move(cursor));
    if (!desktop->has_xdg_output())
      log.notice("the compositor has no xdg-output: the layout is each wl_output's mode divided by its scale");
    if (const CursorSource* cursor = desktop->cursor()) {
      log.info(fmt::format("the pointer's position from {} ({})", cursor->name(), cursor->socket()));
    } else if (!kwin && !said_why) {  // start_kwin said why
      log.notice(
          "this compositor gives no pointer position (only Hyprland, Wayfire and KWin do): telling the daemon the "
          "layout only");
    }
    return desktop;
  }
#endif
  (void)x_display;
  (void)wayland_display;
  (void)log;
  throw std::runtime_error("the " + backend + " backend is not built into this pseudohaptic-session");
}

// Opens the desktop (`open`) on a thread of its own while this one waits for a stop signal of `stop` (blocked): a
// display server that takes the connection but never answers (a hung X server, a stale compositor socket) keeps
// Xlib and libwayland waiting without a time limit, and the helper must still stop as its page says. On a stop the
// opening is given a few seconds more (on KWin it loads a script, then waits up to 2 s for its first position): a
// desktop opened by then is closed at once, which unloads that script, and nullptr is returned; one still opening
// is left, and the process ends (the thread cannot be joined). An error of the opening is thrown here.
std::unique_ptr<Desktop> open_until_stopped(const sigset_t& stop, const Log& log,
                                            std::function<std::unique_ptr<Desktop>()> open) {
  std::future<std::unique_ptr<Desktop>> opened = std::async(std::launch::async, std::move(open));
  while (opened.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    const timespec wait{0, 20'000'000};  // 20 ms: the opening's answer is that much late at most
    siginfo_t info{};
    if (::sigtimedwait(&stop, &info, &wait) > 0) {
      log.info(fmt::format("SIG{} while opening the desktop: stopping", ::sigabbrev_np(info.si_signo)));
      if (opened.wait_for(std::chrono::seconds(3)) == std::future_status::ready) {
        try {
          opened.get();                    // closed here, its KWin script unloaded
        } catch (const std::exception&) {  // it did not open: nothing to close
        }
        return nullptr;
      }
      std::fflush(stderr);
      std::_Exit(0);
    }
  }
  return opened.get();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pseudohaptic-session: tells pseudohapticd where the desktop's real cursor is and how the desktop is laid\n"
      "out, over its control socket: at start, whenever the layout changes, and whenever the daemon asks.\n"
      "Runs in the user's graphical session (the systemd user unit pseudohaptic-session.service) until\n"
      "SIGTERM, SIGINT or SIGHUP; reconnects when the daemon restarts. On Wayland the position comes from Hyprland,\n"
      "Wayfire or KWin (through a script it loads); other compositors give only the layout. See "
      "pseudohaptic-session(1)."};
  std::string control = "/run/pseudohaptic/control";
  std::string backend = "auto";
  std::string display, wayland_display;
  bool verbose = false;
  app.add_option("--control", control, "The daemon's control socket")
      ->check(CLI::Validator([](std::string& path) { return ph::control::socket_path_problem(path); }, ""))
      ->capture_default_str();
  app.add_option("--backend", backend,
                 "How to ask the desktop: auto (wayland when --wayland-display is given or WAYLAND_DISPLAY is set "
                 "without --display, else x11 when DISPLAY or --display is), x11 or wayland")
      ->check(CLI::IsMember({"auto", "x11", "wayland"}))
      ->capture_default_str();
  app.add_option("--display", display, "The X display (x11 backend; default: $DISPLAY)");
  app.add_option("--wayland-display", wayland_display,
                 "The Wayland display (wayland backend; default: $WAYLAND_DISPLAY)");
  std::vector<std::string> passthrough;
  app.add_option("--passthrough", passthrough,
                 "An application (WM_CLASS instance or class name, any case) that reads raw relative motion, such "
                 "as a game: while it has the focus the daemon passes the mice through unchanged (x11 backend "
                 "only). Repeatable");
  app.add_flag("-v,--verbose", verbose, "Also log every line sent and every connection attempt");
  app.set_version_flag("--version", "pseudohaptic-session 0.1.0");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const Log log(verbose);
  const std::string requested = backend;
  backend = choose_backend(backend, display, wayland_display, env("WAYLAND_DISPLAY"), env("DISPLAY"));
  if (backend.empty()) {
    log.error("no desktop this helper knows: neither WAYLAND_DISPLAY nor DISPLAY is set (see pseudohaptic-session(1))");
    return 1;
  }
  if (backend == "wayland" && !display.empty())
    log.notice("--display names an X display: the wayland backend ignores it");
  if (backend == "x11" && !wayland_display.empty())
    log.notice("--wayland-display names a Wayland display: the x11 backend ignores it");
  const std::vector<std::string> listed = passthrough;  // for an x11 fallback below
  if (backend != "x11" && !passthrough.empty()) {
    log.notice("--passthrough needs the x11 backend (the focused window's WM_CLASS); ignored");
    passthrough.clear();
  }

  // SIGTERM, SIGINT and SIGHUP (the terminal it ran in closed) wait for the loop, which then exits cleanly.
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGTERM);
  sigaddset(&stop, SIGINT);
  sigaddset(&stop, SIGHUP);
  sigprocmask(SIG_BLOCK, &stop, nullptr);
  const ph::UniqueFd signals(::signalfd(-1, &stop, SFD_CLOEXEC | SFD_NONBLOCK));
  if (!signals) {
    log.error(fmt::format("signalfd: {}", std::strerror(errno)));
    return 1;
  }
  try {
    const auto open = [&] {
      return open_until_stopped(stop, log, [&] { return open_desktop(backend, display, wayland_display, log); });
    };
    std::unique_ptr<Desktop> desktop;
#ifdef PH_SESSION_WAYLAND
    try {
      desktop = open();
    } catch (const WaylandUnreachable& e) {
      // A WAYLAND_DISPLAY left in the user manager by an earlier Wayland session, in an X session now: only where
      // the display cannot be reached at all (a compositor that went away while it was read is not that).
      const std::string fallback = fallback_backend(requested, backend, display, wayland_display, env("DISPLAY"));
      if (fallback.empty()) throw;
      log.notice(
          fmt::format("{}; trying the X display ({}) instead", e.what(), display.empty() ? env("DISPLAY") : display));
      backend = fallback;
      passthrough = listed;
      desktop = open();
    }
#else
    (void)requested;
    (void)listed;
    desktop = open();
#endif
    if (!desktop) return 0;  // stopped while it opened
    return Helper(control, passthrough, *desktop, log).run(signals.get());
  } catch (const std::runtime_error& e) {  // X11Error, WaylandError: no display, or it went away
    log.error(e.what());
    return 1;
  }
}
