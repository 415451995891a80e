// `pseudohaptic status`, `pseudohaptic cursor` and `pseudohaptic passthrough`: ask the running daemon through its
// control socket (docs/SERVICE.md, "The control socket").
#include <fmt/format.h>
#include <poll.h>
#include <sys/signalfd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/unique_fd.hpp"
#include "control/client.hpp"
#include "control/protocol.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/finite_check.hpp"
#include "tools/number_tuple.hpp"

namespace ph::tools {

namespace {

struct ControlOptions {
  std::string socket{control::kDefaultSocket};
  std::vector<double> set;
};

void add_socket_option(CLI::App& app, ControlOptions& o) {
  // --control as well: the daemon and the session helper call the same path by that name.
  app.add_option("--socket,--control", o.socket, "The daemon's control socket (pseudohapticd's --control)")
      ->check(CLI::Validator([](std::string& path) { return control::socket_path_problem(path); }, ""))
      ->capture_default_str();
}

// The reply's words, or a runtime_error with the daemon's reason.
std::string ask(const ControlOptions& o, const control::Request& request) {
  control::Client client(o.socket);
  const control::Reply reply = client.request(control::format_request(request));
  if (!reply.ok) throw std::runtime_error("pseudohapticd: " + control::printable(reply.text));
  return reply.text;
}

int run_status(const ControlOptions& o) {
  const std::string words = ask(o, control::StatusRequest{});
  const std::optional<control::Status> s = control::parse_status(words);
  if (!s) {
    throw std::runtime_error("pseudohapticd answered something this tool does not understand: " +
                             control::printable(words));
  }
  fmt::print("output:  {}\n", s->absolute ? "absolute" : "relative");
  fmt::print("mice:    {} taken{}\n", s->mice,
             s->held_elsewhere == 0
                 ? std::string()
                 : fmt::format("; {} held by another program (taken once it lets go)", s->held_elsewhere));
  fmt::print("scene:   {} ({} regions)\n",
             s->scene == "default" ? "the embedded default scene" : control::printable(s->scene), s->regions);
  fmt::print("desktop: {}x{} at {},{}\n", s->desktop.w, s->desktop.h, s->desktop.x, s->desktop.y);
  fmt::print("cursor:  {:.2f},{:.2f} (the daemon's model)\n", s->cursor.x, s->cursor.y);
  fmt::print("helper:  {}\n", s->helper ? "connected (the model follows the desktop's cursor)"
                                        : "none (the first motion puts the cursor where the model is)");
  if (s->passthrough) fmt::print("pass-through: on (an application holds the pointer; no textures)\n");
  return 0;
}

int run_cursor(const ControlOptions& o) {
  if (o.set.size() == 2) {
    ask(o, control::PositionRequest{{o.set[0], o.set[1]}});
  }
  const std::string words = ask(o, control::CursorRequest{});
  const std::optional<Vec2> at = control::parse_cursor(words);
  if (!at) {
    throw std::runtime_error("pseudohapticd answered something this tool does not understand: " +
                             control::printable(words));
  }
  fmt::print("{},{}\n", at->x, at->y);
  return 0;
}

// Pass-through on for as long as this runs: the daemon keeps it on while the connection that asked for it is open
// (docs/SERVICE.md, "Applications that lock the pointer"), so the command holds the connection until a signal
// ends it (Ctrl-C, SIGTERM from a key binding's second press) or the daemon goes.
int run_passthrough(const ControlOptions& o) {
  sigset_t stop;
  sigemptyset(&stop);
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&stop, signal);
  sigprocmask(SIG_BLOCK, &stop, nullptr);
  const UniqueFd signals(::signalfd(-1, &stop, SFD_CLOEXEC));
  if (!signals) throw std::runtime_error(std::string("signalfd: ") + std::strerror(errno));
  control::Client client(o.socket);
  const control::Reply on = client.request(control::format_request(control::PassthroughRequest{true}));
  if (!on.ok) throw std::runtime_error("pseudohapticd: " + control::printable(on.text));
  fmt::print(stderr,
             "pseudohaptic: pass-through on: the mice's motion goes unchanged to the application that holds the "
             "pointer, no textures, until this command ends (Ctrl-C)\n");
  for (;;) {
    pollfd fds[2] = {{signals.get(), POLLIN, 0}, {client.fd(), POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("poll: ") + std::strerror(errno));
    }
    if (fds[0].revents != 0) break;
    try {
      while (client.read_line(std::chrono::milliseconds(0))) {  // what the daemon says on its own: nothing to do
      }
    } catch (const control::ControlError&) {
      throw std::runtime_error("pseudohapticd closed the connection (it stopped or restarted): pass-through is off");
    }
  }
  // Off at once; the connection's close would end it too.
  try {
    client.request(control::format_request(control::PassthroughRequest{false}));
  } catch (const control::ControlError&) {
  }
  fmt::print(stderr, "pseudohaptic: pass-through off: the textures are back\n");
  return 0;
}

}  // namespace

Run add_passthrough_command(CLI::App& app) {
  auto o = std::make_shared<ControlOptions>();
  app.description(
      "Turn the daemon's pass-through on for as long as this command runs (until Ctrl-C, SIGTERM or SIGHUP): the\n"
      "mice's motion goes unchanged, through a relative device, to an application that holds the pointer (a game,\n"
      "a 3D viewer), where the session helper cannot tell (on Wayland; on X11 pseudohaptic-session --passthrough\n"
      "does it by the focused window). A later passthrough request of another connection (the helper's) wins while\n"
      "that connection is open. Only root and the user of the active local session may ask.");
  add_socket_option(app, *o);
  return [o] { return run_passthrough(*o); };
}

Run add_status_command(CLI::App& app) {
  auto o = std::make_shared<ControlOptions>();
  app.description(
      "Ask the running pseudohapticd what it does: output mode, mice taken, scene, desktop, its cursor model and\n"
      "whether a session helper is connected. Only root and the user of the active local session may ask.");
  add_socket_option(app, *o);
  return [o] { return run_status(*o); };
}

Run add_cursor_command(CLI::App& app) {
  auto o = std::make_shared<ControlOptions>();
  app.description(
      "Print the daemon's cursor model as X,Y (px), or with --set move the model there first (with absolute\n"
      "output the desktop's cursor follows at the next motion of the mouse).");
  add_socket_option(app, *o);
  // The daemon's range (a layout's): beyond it the daemon refuses, and the error would not name --set.
  add_number_tuple(app, "--set", o->set, "X,Y", "Move the cursor model here (px)",
                   {finite_from(-static_cast<double>(kMaxDesktopCoordinate), kMaxDesktopCoordinate)});
  return [o] { return run_cursor(*o); };
}

}  // namespace ph::tools
