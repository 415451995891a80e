// The control socket's protocol (docs/SERVICE.md, "The control socket"): one request per line, one reply
// line per request, words separated by spaces, numbers in the C locale. Pure: parsing and formatting
// only; the daemon, the tool and the session helper do the I/O.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/engine/desktop_outputs.hpp"
#include "core/engine/geometry.hpp"

namespace ph::control {

inline constexpr std::size_t kMaxLine = 1024;  // bytes, without the newline
inline constexpr std::string_view kDefaultSocket = "/run/pseudohaptic/control";
// The longest path a Unix socket can have (sockaddr_un's sun_path, 108 bytes with its terminating zero).
inline constexpr std::size_t kMaxSocketPath = 107;

// Why `path` can never be a control socket's ("" when it can): empty, or longer than kMaxSocketPath.
std::string socket_path_problem(std::string_view path);

struct StatusRequest {};
struct CursorRequest {};
struct PositionRequest {  // the desktop's real cursor, logical px
  Vec2 position;
};
struct LayoutRequest {  // logical px
  Rect desktop;         // what absolute axes span: the outputs' bounding box (X: the root window)
  // Where the pointer may be, where the outputs do not cover the desktop (monitors of different sizes); none: all
  // of it (core/engine/desktop_outputs.hpp). At most kMaxOutputs, each within the desktop.
  std::vector<Rect> outputs;
  bool operator==(const LayoutRequest&) const = default;
};
struct HelperRequest {  // this connection is the session helper, with this backend
  std::string backend;
};
struct PassthroughRequest {  // an application that reads raw relative motion has the focus (or had)
  bool on = false;
};
using Request =
    std::variant<StatusRequest, CursorRequest, PositionRequest, LayoutRequest, HelperRequest, PassthroughRequest>;

// A request, or the reason it is malformed (sent back as `error REASON`).
std::variant<Request, std::string> parse_request(std::string_view line);
std::string format_request(const Request& request);  // without the newline

// What `status` answers.
struct Status {
  bool absolute = true;
  int mice = 0;            // taken
  int held_elsewhere = 0;  // found, but another program holds its grab (taken once it lets go)
  int regions = 0;
  Rect desktop;
  Vec2 cursor;
  bool helper = false;
  bool passthrough = false;
  std::string scene;  // a path, or "default"
};

std::string format_ok(std::string_view words = {});
std::string format_error(std::string_view reason);
std::string format_status(const Status& status);
std::string format_cursor(Vec2 cursor);

// A reply: ok with its words, or an error with its reason.
struct Reply {
  bool ok = false;
  std::string text;  // the words after `ok`, or the error's reason
};
std::optional<Reply> parse_reply(std::string_view line);
std::optional<Status> parse_status(std::string_view words);
// `text` for one line of a reply or a terminal: each control character (a newline would end the reply; an escape
// sequence would drive the terminal) shows as '?'.
std::string printable(std::string text);
std::optional<Vec2> parse_cursor(std::string_view words);

// Splits a byte stream into lines of at most kMaxLine bytes.
class LineBuffer {
 public:
  // False when a line grew past kMaxLine without its newline: the peer is not speaking the protocol.
  bool append(std::string_view bytes);
  std::optional<std::string> next_line();

 private:
  std::string pending_;
};

}  // namespace ph::control
