// The daemon's end of the control socket (docs/SERVICE.md, "The control socket"): accepts connections
// from root and the active local user, reads their requests line by line and answers each through a
// ControlHandler, on the daemon's event loop. A client that floods it or stops reading is dropped: the
// cursor never waits for a client.
#pragma once

#include <sys/socket.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "common/unique_fd.hpp"
#include "control/protocol.hpp"
#include "daemon/control_access.hpp"
#include "daemon/log.hpp"

namespace ph {

class ControlHandler {
 public:
  virtual ~ControlHandler() = default;
  virtual control::Status status() const = 0;
  virtual Vec2 cursor() const = 0;
  // from_helper: the session helper's report (filtered against what the daemon emitted itself);
  // otherwise a user's explicit `pseudohaptic cursor --set`.
  virtual void position(Vec2 position, bool from_helper) = 0;
  // `outputs`: where on the desktop the pointer may be, where they do not cover it (control::LayoutRequest).
  virtual void layout(Rect desktop, const std::vector<Rect>& outputs) = 0;
  // The connection that sent the last layout has closed (the session ended, the helper stopped): nothing keeps
  // that layout up to date any more.
  virtual void layout_source_gone() = 0;
  virtual void helper_changed(bool present) = 0;
  // An application that reads raw relative motion (a game holding a pointer grab) has the focus: the
  // mice's frames go unchanged through relative devices until it is off again, or until the connection that
  // asked for it closes (the session ended with the game in focus).
  virtual void passthrough(bool on) = 0;
};

// The open connections that sent one kind of request, the latest last: the daemon follows the latest, and when
// that one closes, the latest of those still open (a second session's helper gone, the first one's is still there).
class LatestSenders {
 public:
  void sent(int fd) {
    std::erase(fds_, fd);
    fds_.push_back(fd);
  }
  int latest() const { return fds_.empty() ? -1 : fds_.back(); }
  // Forgets `fd`; true when it was the latest.
  bool closed(int fd) {
    const bool was_latest = latest() == fd;
    std::erase(fds_, fd);
    return was_latest;
  }

 private:
  std::vector<int> fds_;
};

// Another process (another pseudohapticd) accepts connections on the control socket's path.
class ControlSocketInUse : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ControlServer {
 public:
  // Binds and listens at `path` and adds the socket to `epoll`. The socket's own folder is made (0755) where it is
  // missing, as systemd's RuntimeDirectory= makes it for the service: a daemon started by hand has its default
  // /run/pseudohaptic/control too. The folders above it must exist. A socket left
  // there by a daemon that is gone is replaced; one that a running process still accepts on is left alone
  // (ControlSocketInUse): replacing it would cut that daemon off from its helper and from the tool, and
  // this one would remove it again when it ends. Throws std::runtime_error saying what else failed.
  ControlServer(std::string path, int epoll, const SessionDirectory& sessions, const Logger& log);
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  bool owns(int fd) const { return fd == listener_.get() || clients_.contains(fd); }
  void on_readable(int fd, ControlHandler& handler);
  bool has_helper() const { return helpers_.latest() >= 0; }
  // Asks the session helper where the real cursor is; it answers with `position X Y` later.
  void query_helper();
  const std::string& path() const { return path_; }

 private:
  struct Client {
    UniqueFd fd;
    control::LineBuffer lines;
    uid_t uid = 0;
    std::optional<control::LayoutRequest> layout;  // the last layout it sent
    bool layout_deferred = false;  // answered, not yet applied: more of the burst it came in waits to be read
    bool passthrough = false;      // what its last passthrough request asked
  };
  static constexpr std::size_t kMaxClients = 16;
  // A refused uid's refusals are logged once in this time, with a count of those left out: any local user can
  // connect, and a loop of connections would fill the journal (and set off journald's rate limit, which would
  // silence the daemon's other messages with it).
  static constexpr std::chrono::seconds kRefusalLogEvery{10};
  struct Refusals {
    std::chrono::steady_clock::time_point logged;
    long unlogged = 0;
  };

  void accept_client();
  void log_refusal(const ucred& peer, const std::string& why);
  void read_client(int fd, ControlHandler& handler);
  // The reply to one request; a layout that `superseded` (another follows it at once) is answered, not applied.
  std::string answer(int fd, const std::variant<control::Request, std::string>& parsed, ControlHandler& handler,
                     bool superseded);
  bool send_line(int fd, const std::string& line);
  bool send_text(int fd, const std::string& text);  // all of it at once, or false (the client is not reading)
  void drop(int fd, ControlHandler& handler);

  std::string path_;
  int epoll_;
  const SessionDirectory& sessions_;
  const Logger& log_;
  UniqueFd listener_;
  // A descriptor held in reserve: out of descriptors (EMFILE), closing it makes room to accept a waiting
  // connection and close it at once, which the listener's readiness would otherwise report again and again.
  UniqueFd spare_;
  bool told_out_of_descriptors_ = false;
  std::map<uid_t, Refusals> refusals_;
  std::map<int, std::unique_ptr<Client>> clients_;
  LatestSenders helpers_;       // the connections that said `helper`: the latest is the session helper
  LatestSenders layouts_;       // the connections that sent a layout (a helper, or a layout-only one)
  LatestSenders passthroughs_;  // the connections that sent `passthrough on` or `off`
};

// The socket's path: `--control` if given, else $RUNTIME_DIRECTORY/control under systemd, else
// control::kDefaultSocket.
std::string default_control_path();

}  // namespace ph
