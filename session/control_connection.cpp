#include "session/control_connection.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>

#include <cerrno>
#include <cstring>

#include "control/protocol.hpp"

namespace ph::session {

static_assert(sizeof(sockaddr_un{}.sun_path) == control::kMaxSocketPath + 1);

std::optional<ControlConnection> ControlConnection::connect(const std::string& path, std::string& why) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) {
    why = "the socket path is empty or too long";
    return std::nullopt;
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  UniqueFd fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!fd) {
    why = std::strerror(errno);
    return std::nullopt;
  }
  // connect(2) on a unix stream socket completes at once, or fails at once when nothing listens.
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0 && errno != EINPROGRESS) {
    why = std::strerror(errno);
    // A file or a folder there refuses the connection too, and no daemon will listen there until it is gone.
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && !S_ISSOCK(st.st_mode))
      why = S_ISDIR(st.st_mode) ? "a folder, not a socket" : "a file, not a socket";
    return std::nullopt;
  }
  return ControlConnection(std::move(fd));
}

bool ControlConnection::send(std::string_view line) {
  while (!line.empty()) {
    const ssize_t n = ::send(fd_.get(), line.data(), line.size(), MSG_NOSIGNAL);
    if (n > 0) {
      line.remove_prefix(static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {  // the daemon is slow to read: wait for room
      pollfd p{fd_.get(), POLLOUT, 0};
      if (::poll(&p, 1, 2000) <= 0) return false;
      continue;
    }
    return false;
  }
  return true;
}

ControlConnection::Received ControlConnection::read_available() {
  Received received;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::recv(fd_.get(), buffer, sizeof buffer, 0);
    if (n > 0) {
      received.data.append(buffer, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    received.closed = n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK);
    return received;
  }
}

}  // namespace ph::session
