#include "control/client.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>

namespace ph::control {

Client::Client(const std::string& path, std::chrono::milliseconds timeout) : path_(path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (path.size() >= sizeof address.sun_path) throw ControlError(fmt::format("{}: path too long", path));
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  // Non-blocking: a Unix socket whose listener's queue is full (a daemon that has stopped accepting, a hung one)
  // makes a blocking connect wait for ever, and a non-blocking one fail with EAGAIN, tried again until `timeout`.
  fd_ = UniqueFd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!fd_) throw ControlError(fmt::format("cannot create a socket: {}", std::strerror(errno)));
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int connected = 0;
  while ((connected = ::connect(fd_.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address)) != 0 &&
         (errno == EAGAIN || errno == EINTR) && std::chrono::steady_clock::now() < deadline) {
    ::usleep(20'000);
  }
  if (connected != 0 && errno == EAGAIN) {
    throw ControlError(
        fmt::format("pseudohapticd at {} takes no connection (its queue is full): is it hung? "
                    "`systemctl status pseudohapticd`",
                    path));
  }
  if (connected != 0) {
    const int error = errno;
    // A path that is there but is no socket (a folder, a file) refuses the connection too: not the daemon's
    // being down.
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && !S_ISSOCK(st.st_mode)) {
      throw ControlError(
          fmt::format("cannot connect to {}: {}, not a socket (the daemon's is {} unless its --control "
                      "says otherwise)",
                      path, S_ISDIR(st.st_mode) ? "a folder" : "a file", kDefaultSocket));
    }
    // (The daemon's own rule, root and the active local session's user, is its answer once connected: a refusal
    // by the file system is a folder's or the socket's mode.)
    const char* advice = error == ENOENT || error == ECONNREFUSED
                             ? " (is pseudohapticd running? `systemctl status pseudohapticd`)"
                         : error == EACCES ? " (the file system's permissions: a folder on the path, or the socket's "
                                             "mode; the daemon's own socket is open to every user)"
                                           : "";
    throw ControlError(fmt::format("cannot connect to {}: {}{}", path, std::strerror(error), advice));
  }
  const int flags = ::fcntl(fd_.get(), F_GETFL);
  ::fcntl(fd_.get(), F_SETFL, flags & ~O_NONBLOCK);
}

bool Client::send_line(std::string_view line) {
  std::string text(line);
  text += '\n';
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::send(fd_.get(), text.data() + done, text.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

std::optional<std::string> Client::read_line(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    if (auto line = lines_.next_line()) return line;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return std::nullopt;
    pollfd p{fd_.get(), POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) return std::nullopt;
    std::array<char, 4096> buffer{};
    const ssize_t n = ::recv(fd_.get(), buffer.data(), buffer.size(), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw ControlError(fmt::format("pseudohapticd at {} closed the connection", path_));
    if (!lines_.append({buffer.data(), static_cast<std::size_t>(n)}))
      throw ControlError("pseudohapticd sent a line longer than the protocol allows");
  }
}

Reply Client::request(std::string_view line, std::chrono::milliseconds timeout) {
  if (!send_line(line)) {
    const int error = errno;
    // The daemon may have answered and closed before reading the request (a refusal, too many connections):
    // its reason is waiting to be read.
    try {
      if (const std::optional<std::string> got = read_line(std::chrono::milliseconds(100))) {
        if (auto reply = parse_reply(*got)) return *reply;
      }
    } catch (const ControlError&) {
    }
    throw ControlError(fmt::format("cannot send to pseudohapticd: {}", std::strerror(error)));
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    const std::optional<std::string> got = read_line(std::max(left, std::chrono::milliseconds(0)));
    if (!got) throw ControlError(fmt::format("pseudohapticd at {} did not answer in time", path_));
    if (auto reply = parse_reply(*got)) return *reply;
    if (*got == "query") continue;  // the daemon's own question, to a helper
    throw ControlError(
        fmt::format("{} answered \"{}\", which is no reply of pseudohapticd's: is it its control socket?", path_,
                    printable(got->substr(0, 80))));
  }
}

}  // namespace ph::control
