// libFuzzer target: the control socket's protocol (control/protocol.cpp) on arbitrary bytes, as a client
// could send them. Every accepted request must format and parse back to itself; no input may crash.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "control/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  ph::control::LineBuffer lines;
  lines.append(bytes);
  while (auto line = lines.next_line()) {
    const auto parsed = ph::control::parse_request(*line);
    if (const auto* request = std::get_if<ph::control::Request>(&parsed)) {
      const std::string text = ph::control::format_request(*request);
      const auto again = ph::control::parse_request(text);
      if (!std::holds_alternative<ph::control::Request>(again) ||
          ph::control::format_request(std::get<ph::control::Request>(again)) != text) {
        std::abort();
      }
    }
    if (const auto reply = ph::control::parse_reply(*line)) {
      (void)ph::control::parse_status(reply->text);
      (void)ph::control::parse_cursor(reply->text);
    }
  }
  return 0;
}
