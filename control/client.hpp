// A connection to pseudohapticd's control socket, for the tool and the session helper (docs/SERVICE.md,
// "The control socket").
#pragma once

#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/unique_fd.hpp"
#include "control/protocol.hpp"

namespace ph::control {

class ControlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Client {
 public:
  // Connects, waiting at most `timeout` for a daemon whose queue of connections is full (one that has stopped
  // accepting them); throws ControlError saying what to do (the daemon not running, no permission, hung).
  explicit Client(const std::string& path, std::chrono::milliseconds timeout = std::chrono::seconds(2));
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Sends one line and waits for the next line that is a reply (`ok ...` or `error ...`), skipping lines
  // the daemon sends on its own (`query`, to a helper). Throws ControlError when the daemon closes the connection,
  // says nothing within the timeout, or says something that is neither (not a pseudohapticd's socket).
  Reply request(std::string_view line, std::chrono::milliseconds timeout = std::chrono::seconds(2));
  bool send_line(std::string_view line);
  // The next line, waiting at most `timeout`; nullopt on a time-out; throws ControlError at the end.
  std::optional<std::string> read_line(std::chrono::milliseconds timeout);

  int fd() const { return fd_.get(); }

 private:
  std::string path_;  // for the messages
  UniqueFd fd_;
  LineBuffer lines_;
};

}  // namespace ph::control
