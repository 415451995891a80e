// A connection to pseudohapticd's control socket (AF_UNIX, SOCK_STREAM): connect, send whole lines,
// read what has arrived. Non-blocking reads; a write waits until the line is out.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "common/unique_fd.hpp"

namespace ph::session {

class ControlConnection {
 public:
  // Connects to the socket at `path`; nullopt (with `why` set) when nothing listens there yet.
  static std::optional<ControlConnection> connect(const std::string& path, std::string& why);

  int fd() const { return fd_.get(); }
  // Sends the whole line; false when the daemon has gone (the connection is then useless).
  bool send(std::string_view line);
  // What has arrived (possibly nothing), and whether the daemon has closed the connection (or it failed).
  struct Received {
    std::string data;
    bool closed = false;
  };
  Received read_available();

 private:
  explicit ControlConnection(UniqueFd fd) : fd_(std::move(fd)) {}
  UniqueFd fd_;
};

}  // namespace ph::session
