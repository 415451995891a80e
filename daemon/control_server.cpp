#include "daemon/control_server.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string_view>

namespace ph {

namespace {

[[noreturn]] void fail(std::string_view what, const std::string& path) {
  throw std::runtime_error(fmt::format("control socket {}: {}: {}", path, what, std::strerror(errno)));
}

// Whether a process accepts connections on the socket at `address`: a socket file whose listener is gone
// refuses them (ECONNREFUSED). Anything else (a connection, a full backlog, a refusal by permissions) is taken
// for a live one, to be left alone.
bool socket_answers(const sockaddr_un& address) {
  const UniqueFd probe(::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!probe) return false;
  if (::connect(probe.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) return true;
  return errno != ECONNREFUSED && errno != ENOENT;
}

}  // namespace

std::string default_control_path() {
  if (const char* runtime = std::getenv("RUNTIME_DIRECTORY"); runtime != nullptr && *runtime != '\0') {
    std::string dir(runtime);
    if (const std::size_t colon = dir.find(':'); colon != std::string::npos) dir.resize(colon);
    return dir + "/control";
  }
  return std::string(control::kDefaultSocket);
}

ControlServer::ControlServer(std::string path, int epoll, const SessionDirectory& sessions, const Logger& log)
    : path_(std::move(path)), epoll_(epoll), sessions_(sessions), log_(log) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (path_.size() >= sizeof address.sun_path) {
    errno = ENAMETOOLONG;
    fail("cannot use the path", path_);
  }
  std::memcpy(address.sun_path, path_.c_str(), path_.size() + 1);
  // Its own folder, one level: a mistyped --control deeper down still fails, naming the path. 0755 whatever the
  // umask: every user's helper and tool must reach the socket.
  if (const std::string folder = std::filesystem::path(path_).parent_path().string();
      !folder.empty() && ::mkdir(folder.c_str(), 0755) == 0) {
    ::chmod(folder.c_str(), 0755);
    log_.info("made the control socket's folder {}", folder);
  }
  listener_ = UniqueFd(::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!listener_) fail("cannot create the socket", path_);
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0 && !S_ISSOCK(st.st_mode)) {
    // bind() would say "Address already in use", which sends one looking for another daemon.
    throw std::runtime_error(
        fmt::format("control socket {}: {} is there, not a socket; remove it or give another "
                    "--control",
                    path_, S_ISDIR(st.st_mode) ? "a folder" : "a file"));
  }
  if (::lstat(path_.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) {
    if (socket_answers(address)) {
      throw ControlSocketInUse(fmt::format(
          "control socket {}: another pseudohapticd answers there; stop it first (`systemctl stop pseudohapticd`) "
          "or give this one another --control",
          path_));
    }
    ::unlink(path_.c_str());  // left by a daemon that is gone
  }
  if (::bind(listener_.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
    fail("cannot bind", path_);
  // Everyone may connect; who may talk is decided per connection from its credentials.
  if (::chmod(path_.c_str(), 0666) != 0) fail("cannot set its permissions", path_);
  if (::listen(listener_.get(), 8) != 0) fail("cannot listen", path_);
  spare_ = UniqueFd(::open("/dev/null", O_RDONLY | O_CLOEXEC));
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = listener_.get();
  if (::epoll_ctl(epoll_, EPOLL_CTL_ADD, listener_.get(), &event) != 0) fail("cannot watch it", path_);
}

ControlServer::~ControlServer() {
  if (listener_) ::unlink(path_.c_str());
}

void ControlServer::on_readable(int fd, ControlHandler& handler) {
  if (fd == listener_.get()) {
    accept_client();
  } else {
    read_client(fd, handler);
  }
}

void ControlServer::accept_client() {
  while (true) {
    UniqueFd fd(::accept4(listener_.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
    if (!fd && (errno == EINTR || errno == ECONNABORTED)) continue;
    if (!fd && (errno == EMFILE || errno == ENFILE) && spare_) {
      // The connection waits in the backlog and the listener stays readable: the loop would spin. Take it with
      // the spare descriptor's room and close it (the client sees its end), then hold the spare again.
      spare_ = UniqueFd();
      const bool took = UniqueFd(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC)).get() >= 0;  // closed
      spare_ = UniqueFd(::open("/dev/null", O_RDONLY | O_CLOEXEC));
      // accept fails with EMFILE before it looks at the backlog: once none waits, it says EMFILE still, and going
      // round again would spin here (and take the next connection that comes while it does).
      if (!took) return;
      if (!told_out_of_descriptors_) {
        log_.warning("control socket: out of file descriptors; closing connections unanswered until some are free");
        told_out_of_descriptors_ = true;
      }
      continue;
    }
    if (!fd) return;  // EAGAIN: no more waiting
    told_out_of_descriptors_ = false;
    ucred peer{};
    socklen_t length = sizeof peer;
    if (::getsockopt(fd.get(), SOL_SOCKET, SO_PEERCRED, &peer, &length) != 0) continue;
    if (const auto refusal = control_refusal(peer.uid, sessions_)) {
      log_refusal(peer, *refusal);
      send_line(fd.get(), control::format_error("permission denied: " + *refusal));
      continue;
    }
    // Root gets in beyond the limit (up to as many again): connections that sit idle must not lock out root's
    // `pseudohaptic status`.
    if (clients_.size() >= (peer.uid == 0 ? 2 * kMaxClients : kMaxClients)) {
      send_line(fd.get(), control::format_error("too many connections"));
      continue;
    }
    epoll_event event{};
    event.events = EPOLLIN;
    event.data.fd = fd.get();
    if (::epoll_ctl(epoll_, EPOLL_CTL_ADD, fd.get(), &event) != 0) continue;
    log_.debug("control socket: pid {} (uid {}) connected", peer.pid, peer.uid);
    auto client = std::make_unique<Client>();
    client->uid = peer.uid;
    const int key = fd.get();
    client->fd = std::move(fd);
    clients_.emplace(key, std::move(client));
  }
}

void ControlServer::log_refusal(const ucred& peer, const std::string& why) {
  const auto now = std::chrono::steady_clock::now();
  const auto [it, first] = refusals_.try_emplace(peer.uid);
  Refusals& refusals = it->second;
  if (!first && now - refusals.logged < kRefusalLogEvery) {
    ++refusals.unlogged;
    return;
  }
  const std::string left_out =
      refusals.unlogged == 0
          ? std::string()
          : fmt::format("; {} more of uid {} refused since the last one logged", refusals.unlogged, peer.uid);
  log_.warning("control socket: refused pid {} ({}){}", peer.pid, why, left_out);
  refusals.logged = now;
  refusals.unlogged = 0;
}

namespace {

// Whether more bytes wait to be read on the socket now.
bool bytes_waiting(int fd) {
  char byte = 0;
  return ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT) == 1;
}

}  // namespace

void ControlServer::read_client(int fd, ControlHandler& handler) {
  const auto it = clients_.find(fd);
  if (it == clients_.end()) return;
  Client& client = *it->second;
  // At most 512 bytes a wake-up: what is left wakes the loop again, after it has let go of the state lock, so that a
  // flood of short requests holds up the mice for a fraction of a millisecond at a time (bench/bench_control.cpp).
  std::array<char, 512> buffer{};
  const ssize_t n = ::recv(fd, buffer.data(), buffer.size(), 0);
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) return;
  if (n <= 0) {
    drop(fd, handler);
    return;
  }
  // Line by line, so that the requests read whole before a line too long are still answered (and applied) before the
  // connection is closed on it.
  std::vector<std::variant<control::Request, std::string>> requests;
  bool too_long = false;
  for (std::string_view data(buffer.data(), static_cast<std::size_t>(n)); !data.empty();) {
    const std::size_t end = std::min(data.find('\n'), data.size() - 1) + 1;  // through the newline, or the rest
    if (!client.lines.append(data.substr(0, end))) {
      too_long = true;
      break;
    }
    data.remove_prefix(end);
    while (auto line = client.lines.next_line()) requests.push_back(control::parse_request(*line));
  }
  // Of a run of layouts sent at once only the last is applied: each may lay out the scene again on the event loop
  // (the embedded default scene is laid out for the desktop; absolute output remakes the virtual devices), and a
  // burst would hold up the mice. Each is answered. A run may go on in what the next read takes: the last layout of
  // a read waits (answered) while more of the burst waits in the socket, and is applied before whatever follows it
  // unless another layout does.
  const auto is_layout = [](const std::variant<control::Request, std::string>& parsed) {
    const auto* request = std::get_if<control::Request>(&parsed);
    return request != nullptr && std::holds_alternative<control::LayoutRequest>(*request);
  };
  // (Unless another connection has sent a layout since, which is then the latest and applied.)
  const auto apply_deferred = [&] {
    if (client.layout_deferred && layouts_.latest() == fd)
      handler.layout(client.layout->desktop, client.layout->outputs);
    client.layout_deferred = false;
  };
  const bool more_waiting = !too_long && static_cast<std::size_t>(n) == buffer.size() && bytes_waiting(fd);
  // The answers go back in one send(): a flood of requests costs one system call a read, not one a line.
  std::string replies;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const bool layout = is_layout(requests[i]);
    if (layout) {
      client.layout_deferred = false;  // superseded by this one
    } else {
      apply_deferred();
    }
    const bool last = i + 1 == requests.size();
    const bool superseded = layout && (last ? more_waiting : is_layout(requests[i + 1]));
    replies += answer(fd, requests[i], handler, superseded);
    replies += '\n';
    if (superseded && last) client.layout_deferred = true;
  }
  if (!more_waiting) apply_deferred();
  if (too_long) {
    log_.warning("control socket: a line over {} bytes; closing that connection", control::kMaxLine);
    replies += control::format_error("line too long");
    replies += '\n';
  }
  if (!send_text(fd, replies) || too_long) drop(fd, handler);
}

std::string ControlServer::answer(int fd, const std::variant<control::Request, std::string>& parsed,
                                  ControlHandler& handler, bool superseded) {
  if (const auto* error = std::get_if<std::string>(&parsed)) return control::format_error(*error);
  const control::Request& request = std::get<control::Request>(parsed);
  if (const auto* l = std::get_if<control::LayoutRequest>(&request)) {
    clients_.at(fd)->layout = *l;
    layouts_.sent(fd);
    if (!superseded) handler.layout(l->desktop, l->outputs);
    return control::format_ok();
  }
  if (std::holds_alternative<control::StatusRequest>(request)) {
    control::Status status = handler.status();
    status.helper = has_helper();
    return control::format_status(status);
  }
  if (std::holds_alternative<control::CursorRequest>(request)) return control::format_cursor(handler.cursor());
  if (const auto* p = std::get_if<control::PositionRequest>(&request)) {
    handler.position(p->position, fd == helpers_.latest());
    return control::format_ok();
  }
  if (const auto* p = std::get_if<control::PassthroughRequest>(&request)) {
    clients_.at(fd)->passthrough = p->on;
    passthroughs_.sent(fd);
    handler.passthrough(p->on);
    return control::format_ok();
  }
  const auto& h = std::get<control::HelperRequest>(request);
  const bool had = has_helper();
  const bool again = helpers_.latest() == fd;  // (said once: a loop of `helper` lines would fill the journal)
  helpers_.sent(fd);                           // the newest helper wins: a restarted session replaces the old one
  if (!again) log_.info("control socket: session helper '{}' connected (uid {})", h.backend, clients_.at(fd)->uid);
  if (!had) handler.helper_changed(true);
  return control::format_ok();
}

bool ControlServer::send_line(int fd, const std::string& line) { return send_text(fd, line + '\n'); }

bool ControlServer::send_text(int fd, const std::string& text) {
  if (text.empty()) return true;
  // Never block the event loop: a client whose socket buffer is full has stopped reading.
  const ssize_t n = ::send(fd, text.data(), text.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  return n == static_cast<ssize_t>(text.size());
}

void ControlServer::query_helper() {
  if (!has_helper()) return;
  if (!send_line(helpers_.latest(), "query")) log_.debug("control socket: the session helper did not take a query");
}

// What the closed connection had set gives way to what the latest one still open set before it, or, where none is
// left, to the daemon's own state: no helper, a layout nothing keeps up to date, no pass-through.
void ControlServer::drop(int fd, ControlHandler& handler) {
  ::epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
  if (helpers_.closed(fd)) {
    if (has_helper()) {
      log_.info(
          "control socket: the session helper went away; the one connected before it (uid {}) is the helper "
          "again",
          clients_.at(helpers_.latest())->uid);
      query_helper();  // the cursor may be anywhere on that session's desktop
    } else {
      log_.info("control socket: the session helper went away");
      handler.helper_changed(false);
    }
  }
  if (layouts_.closed(fd)) {
    if (const int before = layouts_.latest(); before >= 0) {
      const control::LayoutRequest& kept = *clients_.at(before)->layout;
      handler.layout(kept.desktop, kept.outputs);
    } else {
      handler.layout_source_gone();
    }
  }
  if (passthroughs_.closed(fd)) {
    const int before = passthroughs_.latest();
    const bool on = before >= 0 && clients_.at(before)->passthrough;
    if (clients_.at(fd)->passthrough && !on)
      log_.info("control socket: the connection that asked for pass-through has closed");
    handler.passthrough(on);
  }
  clients_.erase(fd);
}

}  // namespace ph
