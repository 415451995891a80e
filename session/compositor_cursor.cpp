#include "session/compositor_cursor.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "common/unique_fd.hpp"
#include "session/compositor_answers.hpp"

namespace ph::session {

namespace {

using Clock = std::chrono::steady_clock;

UniqueFd connect_unix(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) return UniqueFd();
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  UniqueFd fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!fd || ::connect(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) return UniqueFd();
  return fd;
}

// Waits until `fd` is ready for `events` or the deadline passes.
bool wait_for(int fd, short events, Clock::time_point deadline) {
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, events, 0};
    const int n = ::poll(&p, 1, static_cast<int>(left));
    if (n > 0) return true;
    if (n < 0 && errno != EINTR) return false;
  }
}

bool send_all(int fd, std::string_view data, Clock::time_point deadline) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n > 0) {
      data.remove_prefix(static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      if (!wait_for(fd, POLLOUT, deadline)) return false;
    } else {
      return false;
    }
  }
  return true;
}

// Reads until `done` says the bytes so far are complete, the peer closes, or the deadline passes;
// `limit` bounds what is kept. Returns what arrived and whether it ended as `done` or at the peer's close.
struct ReadResult {
  std::string data;
  bool complete = false;
};
template <typename Done>
ReadResult read_until(int fd, Clock::time_point deadline, std::size_t limit, Done done) {
  ReadResult result;
  char buffer[4096];
  for (;;) {
    if (done(result.data)) {
      result.complete = true;
      return result;
    }
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      result.data.append(buffer, static_cast<std::size_t>(n));
      if (result.data.size() > limit) return result;
    } else if (n == 0) {
      result.complete = !result.data.empty();  // Hyprland closes after its answer
      return result;
    } else if (errno == EINTR) {
      continue;
    } else if (errno != EAGAIN && errno != EWOULDBLOCK) {
      return result;
    } else if (!wait_for(fd, POLLIN, deadline)) {
      return result;
    }
  }
}

}  // namespace

std::optional<Vec2> HyprlandCursor::position() {
  const auto deadline = Clock::now() + timeout_;
  const UniqueFd fd = connect_unix(socket_);
  if (!fd || !send_all(fd.get(), "cursorpos", deadline)) return std::nullopt;
  // The answer is one short line and the end of the connection.
  const ReadResult answer = read_until(fd.get(), deadline, 256, [](const std::string&) { return false; });
  if (!answer.complete) return std::nullopt;
  return parse_hyprland_cursorpos(answer.data);
}

std::optional<Vec2> WayfireCursor::position() {
  const auto deadline = Clock::now() + timeout_;
  const UniqueFd fd = connect_unix(socket_);
  if (!fd || !send_all(fd.get(), wayfire_cursor_request(), deadline)) return std::nullopt;
  bool too_long = false;
  const ReadResult reply =
      read_until(fd.get(), deadline, kWayfireHeader + kWayfireMaxMessage, [&](const std::string& d) {
        if (d.size() < kWayfireHeader) return false;
        const std::optional<std::size_t> length = wayfire_message_length(std::string_view(d).substr(0, kWayfireHeader));
        too_long = !length;
        return too_long || d.size() >= kWayfireHeader + *length;
      });
  if (!reply.complete || too_long || reply.data.size() < kWayfireHeader) return std::nullopt;
  const std::size_t length = *wayfire_message_length(std::string_view(reply.data).substr(0, kWayfireHeader));
  if (reply.data.size() < kWayfireHeader + length) return std::nullopt;
  return parse_wayfire_cursor_position(std::string_view(reply.data).substr(kWayfireHeader, length));
}

std::unique_ptr<CursorSource> cursor_source_from_environment(std::string* unmet) {
  if (unmet != nullptr) unmet->clear();
  const auto env = [](const char* name) -> std::string_view {
    const char* value = std::getenv(name);
    return value != nullptr ? value : "";
  };
  const auto is_socket = [](const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode);
  };
  std::string said;
  const std::vector<std::string> hyprland =
      hyprland_socket_candidates(env("XDG_RUNTIME_DIR"), env("HYPRLAND_INSTANCE_SIGNATURE"));
  for (const std::string& path : hyprland) {
    if (is_socket(path)) return std::make_unique<HyprlandCursor>(path);
  }
  if (!hyprland.empty()) {
    said = "HYPRLAND_INSTANCE_SIGNATURE is set, but no Hyprland socket is there (" + hyprland.front();
    for (std::size_t i = 1; i < hyprland.size(); ++i) said += ", " + hyprland[i];
    said += ")";
  }
  // Where the variable names no socket (left in the user manager by a Wayfire session that has ended), none.
  const std::string wayfire(env("WAYFIRE_SOCKET"));
  if (!wayfire.empty() && is_socket(wayfire)) return std::make_unique<WayfireCursor>(wayfire);
  if (!wayfire.empty())
    said += (said.empty() ? "" : "; ") + std::string("WAYFIRE_SOCKET names no socket (") + wayfire + ")";
  if (unmet != nullptr) *unmet = said;
  return nullptr;
}

}  // namespace ph::session
