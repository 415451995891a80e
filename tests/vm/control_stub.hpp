// A stand-in for pseudohapticd's end of the control socket, for checking pseudohaptic-session alone:
// listens at a path, takes one connection at a time, reads its lines and writes lines to it.
#pragma once

#include <sys/socket.h>
#include <sys/un.h>

#include <fmt/format.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "control/protocol.hpp"
#include "tests/vm/e2e_support.hpp"

namespace ph::e2e {

class ControlStub {
 public:
  explicit ControlStub(std::string path) : path_(std::move(path)) { listen(); }
  ~ControlStub() { ::unlink(path_.c_str()); }
  ControlStub(const ControlStub&) = delete;
  ControlStub& operator=(const ControlStub&) = delete;

  const std::string& path() const { return path_; }

  // Waits for a client; false on timeout.
  bool accept(Clock::duration timeout) {
    pollfd p{listener_.get(), POLLIN, 0};
    if (::poll(&p, 1, ms_until(Clock::now() + timeout)) <= 0) return false;
    client_ = Fd(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK));
    lines_ = control::LineBuffer{};
    return static_cast<bool>(client_);
  }

  // The client's next line; nullopt on timeout or when it closed the connection.
  std::optional<std::string> next_line(Clock::duration timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      if (std::optional<std::string> line = lines_.next_line()) return line;
      pollfd p{client_.get(), POLLIN, 0};
      if (::poll(&p, 1, ms_until(deadline)) <= 0) return std::nullopt;
      char buffer[2048];
      const ssize_t n = ::recv(client_.get(), buffer, sizeof buffer, 0);
      if (n <= 0) return std::nullopt;
      lines_.append(std::string_view(buffer, static_cast<std::size_t>(n)));
    }
  }

  void send(const std::string& line) {
    const std::string text = line + "\n";
    if (::send(client_.get(), text.data(), text.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(text.size())) {
      throw Fatal("cannot write to the helper's connection");
    }
  }

  // As the daemon closing one client's connection (after refusing it): the socket stays.
  void drop_client() { client_.reset(); }

  // As the daemon going away: the connection and the socket close. restart() listens again.
  void stop() {
    client_.reset();
    listener_.reset();
    ::unlink(path_.c_str());
  }
  void restart() { listen(); }

 private:
  void listen() {
    listener_ = Fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    if (!listener_ || path_.size() >= sizeof addr.sun_path) throw Fatal("control stub socket: " + errno_text(errno));
    std::memcpy(addr.sun_path, path_.c_str(), path_.size() + 1);
    ::unlink(path_.c_str());
    if (::bind(listener_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0 ||
        ::listen(listener_.get(), 4) < 0) {
      throw Fatal("control stub at " + path_ + ": " + errno_text(errno));
    }
  }

  std::string path_;
  Fd listener_, client_;
  control::LineBuffer lines_;
};

// One case of a session check against the stub: the problems it found, and PASS or FAIL with them.
struct HelperCase {
  std::string label;
  std::vector<std::string> problems;
  Clock::time_point start = Clock::now();
  // Reads lines until `want` (answering each with ok); what came before it is a problem when `exact`.
  void expect(ControlStub& stub, const std::string& want, const std::string& when, bool exact = true) {
    std::vector<std::string> before;
    while (const std::optional<std::string> line = stub.next_line(20s)) {
      stub.send("ok");
      if (*line == want) {
        if (exact && !before.empty())
          problems.push_back(fmt::format("{}: '{}' came after [{}]", when, want, fmt::join(before, " | ")));
        return;
      }
      before.push_back(*line);
    }
    problems.push_back(
        fmt::format("{}: expected '{}', got [{}] and then nothing for 20 s", when, want, fmt::join(before, " | ")));
  }
  void expect_silence(ControlStub& stub, Clock::duration how_long, const std::string& when) {
    if (const std::optional<std::string> line = stub.next_line(how_long))
      problems.push_back(fmt::format("{}: expected nothing, got '{}'", when, *line));
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

}  // namespace ph::e2e

namespace ph::e2e {

// A plain client of the daemon's control socket (not a helper): one request, one reply line.
class ControlClient {
 public:
  // Connects to `path`, retrying until `timeout` (the daemon creates the socket as it starts).
  ControlClient(const std::string& path, Clock::duration timeout) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    if (path.size() >= sizeof addr.sun_path) throw Fatal("control socket path too long: " + path);
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    const bool connected = wait_until(
        [&] {
          fd_ = Fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
          return fd_ && ::connect(fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
        },
        timeout, nullptr, 100ms);
    if (!connected) throw Fatal("cannot connect to the control socket " + path + ": " + errno_text(errno));
  }

  // Sends `request` and returns the reply line; Fatal when none comes within `timeout`.
  std::string request(const std::string& request, Clock::duration timeout = 5s) {
    const std::string text = request + "\n";
    if (::send(fd_.get(), text.data(), text.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(text.size())) {
      throw Fatal("cannot write to the control socket: " + errno_text(errno));
    }
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      if (std::optional<std::string> line = lines_.next_line()) return *line;
      pollfd p{fd_.get(), POLLIN, 0};
      char buffer[2048];
      if (::poll(&p, 1, ms_until(deadline)) <= 0) throw Fatal("no reply to '" + request + "' from the control socket");
      const ssize_t n = ::recv(fd_.get(), buffer, sizeof buffer, 0);
      if (n <= 0) throw Fatal("the control socket closed after '" + request + "'");
      lines_.append(std::string_view(buffer, static_cast<std::size_t>(n)));
    }
  }

  // The daemon's cursor model (`cursor` -> `ok X Y`).
  Vec2 cursor() {
    const std::string reply = request("cursor");
    Vec2 at;
    if (std::sscanf(reply.c_str(), "ok %lf %lf", &at.x, &at.y) != 2)
      throw Fatal("unexpected reply to cursor: " + reply);
    return at;
  }

 private:
  Fd fd_;
  control::LineBuffer lines_;
};

}  // namespace ph::e2e
