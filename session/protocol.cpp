#include "session/protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ph::session {

namespace {

// A coordinate in the C locale: up to three decimals, trailing zeros dropped ("960", "960.5").
std::string coordinate(double v) {
  std::string text = fmt::format("{:.3f}", v);  // fmt ignores the locale unless asked
  while (!text.empty() && text.back() == '0') text.pop_back();
  if (!text.empty() && text.back() == '.') text.pop_back();
  if (text == "-0") text = "0";
  return text;
}

bool starts_with_word(std::string_view line, std::string_view word) {
  return line.substr(0, word.size()) == word && (line.size() == word.size() || line[word.size()] == ' ');
}

}  // namespace

void LineSplitter::feed(std::string_view bytes) {
  if (overflowed_) return;
  if (start_ > 0 && start_ >= buffer_.size() / 2) {  // keep the buffer from growing with what was read
    buffer_.erase(0, start_);
    start_ = 0;
  }
  buffer_.append(bytes);
}

std::optional<std::string> LineSplitter::next() {
  if (overflowed_) return std::nullopt;
  const std::size_t end = buffer_.find('\n', start_);
  if (end == std::string::npos) {
    if (buffer_.size() - start_ > kMaxLine) overflowed_ = true;
    return std::nullopt;
  }
  if (end - start_ > kMaxLine) {
    overflowed_ = true;
    return std::nullopt;
  }
  std::string line = buffer_.substr(start_, end - start_);
  start_ = end + 1;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

std::string helper_request(std::string_view backend) { return fmt::format("helper {}\n", backend); }

std::optional<std::string> layout_request(Rect layout) {
  if (layout.w <= 0 || layout.h <= 0) return std::nullopt;
  return fmt::format("layout {} {} {} {}\n", layout.x, layout.y, layout.w, layout.h);
}

std::optional<std::string> position_request(Vec2 position) {
  if (!is_finite(position)) return std::nullopt;
  return fmt::format("position {} {}\n", coordinate(position.x), coordinate(position.y));
}

std::optional<Rect> bounding_box(const std::vector<Rect>& outputs) {
  std::int64_t x0 = std::numeric_limits<std::int64_t>::max(), y0 = x0;
  std::int64_t x1 = std::numeric_limits<std::int64_t>::min(), y1 = x1;
  bool any = false;
  for (const Rect& r : outputs) {
    if (r.w <= 0 || r.h <= 0) continue;
    any = true;
    x0 = std::min<std::int64_t>(x0, r.x);
    y0 = std::min<std::int64_t>(y0, r.y);
    x1 = std::max<std::int64_t>(x1, std::int64_t{r.x} + r.w);
    y1 = std::max<std::int64_t>(y1, std::int64_t{r.y} + r.h);
  }
  if (!any) return std::nullopt;
  constexpr std::int64_t kMax = std::numeric_limits<std::int32_t>::max();
  return Rect{static_cast<std::int32_t>(x0), static_cast<std::int32_t>(y0),
              static_cast<std::int32_t>(std::min(x1 - x0, kMax)), static_cast<std::int32_t>(std::min(y1 - y0, kMax))};
}

std::chrono::milliseconds reconnect_delay(int failures) {
  const int doublings = std::clamp(failures - 1, 0, 5);
  return std::min(std::chrono::milliseconds(250 << doublings), std::chrono::milliseconds(5000));
}

void Conversation::sent(std::string_view request) {
  if (!request.empty() && request.back() == '\n') request.remove_suffix(1);
  awaiting_.emplace_back(request);
}

Conversation::Reaction Conversation::on_line(std::string_view line) {
  Reaction reaction;
  if (line == "query") {
    reaction.send_position = true;
    return reaction;
  }
  const bool ok = starts_with_word(line, "ok"), error = starts_with_word(line, "error");
  if (!ok && !error) {
    reaction.complaint = fmt::format("the daemon sent a line not understood: '{}'", line);
    return reaction;
  }
  std::string request = "(nothing)";
  if (!awaiting_.empty()) {
    request = std::move(awaiting_.front());
    awaiting_.pop_front();
  }
  if (error)
    reaction.complaint =
        fmt::format("the daemon refused '{}': {}", request, line.substr(std::min<std::size_t>(6, line.size())));
  return reaction;
}

}  // namespace ph::session
