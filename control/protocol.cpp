#include "control/protocol.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

namespace ph::control {

namespace {

std::vector<std::string_view> words_of(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t at = 0;
  while (at < line.size()) {
    const std::size_t end = std::min(line.find(' ', at), line.size());
    if (end > at) words.push_back(line.substr(at, end - at));
    at = end + 1;
  }
  return words;
}

// A finite number; one too small for a double is 0, as strtod reads it, and -0 is 0 (a coordinate has no sign
// of zero to echo back).
std::optional<double> number(std::string_view text) {
  double v = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (end != text.data() + text.size()) return std::nullopt;
  if (error == std::errc::result_out_of_range) {
    const std::string whole(text);
    // ERANGE with ±HUGE_VAL (too large) or a subnormal or 0 (too small). strtod reads the C locale's decimal point:
    // no program of the project sets another.
    v = std::strtod(whole.c_str(), nullptr);
  } else if (error != std::errc()) {
    return std::nullopt;
  }
  if (!std::isfinite(v)) return std::nullopt;
  return v + 0.0;
}

std::optional<std::int32_t> integer(std::string_view text) {
  std::int32_t v = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return v;
}

// Coordinates past this are not a desktop (core/engine/geometry.hpp).
constexpr double kMaxCoordinate = kMaxDesktopCoordinate;

bool printable_word(std::string_view w) {
  if (w.empty() || w.size() > 32) return false;
  for (const char c : w) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) return false;
  }
  return true;
}

std::variant<Request, std::string> parse_position(const std::vector<std::string_view>& w) {
  if (w.size() != 3) return std::string("position needs X Y (px)");
  const auto x = number(w[1]), y = number(w[2]);
  if (!x || !y) return std::string("position: X and Y must be finite numbers");
  if (std::fabs(*x) > kMaxCoordinate || std::fabs(*y) > kMaxCoordinate)
    return fmt::format("position: X and Y must be within ±{}", kMaxCoordinate);
  return Request{PositionRequest{{*x, *y}}};
}

// "layout X Y W H", then the outputs' X Y W H where they do not cover the desktop (control/protocol.hpp).
std::variant<Request, std::string> parse_layout(const std::vector<std::string_view>& w) {
  if (w.size() < 5 || (w.size() - 5) % 4 != 0 || (w.size() - 5) / 4 > kMaxOutputs)
    return fmt::format("layout needs X Y W H (whole px), then up to {} outputs' X Y W H", kMaxOutputs);
  std::vector<Rect> rects;
  for (std::size_t i = 1; i < w.size(); i += 4) {
    const auto x = integer(w[i]), y = integer(w[i + 1]), width = integer(w[i + 2]), height = integer(w[i + 3]);
    if (!x || !y || !width || !height) return std::string("layout: X Y W H must be whole numbers");
    rects.push_back({*x, *y, *width, *height});
  }
  const Rect desktop = rects.front();
  if (!is_valid_desktop(desktop))
    return fmt::format("layout: W and H must be from 1 to {}, X and Y within ±{}", kMaxDesktopCoordinate,
                       kMaxDesktopCoordinate);
  std::vector<Rect> outputs(rects.begin() + 1, rects.end());
  for (const Rect& o : outputs) {
    if (!output_within(o, desktop)) {
      return fmt::format("layout: the output {} {} {} {} is not a rectangle within the desktop {} {} {} {}", o.x, o.y,
                         o.w, o.h, desktop.x, desktop.y, desktop.w, desktop.h);
    }
  }
  return Request{LayoutRequest{desktop, std::move(outputs)}};
}

}  // namespace

std::string printable(std::string text) {
  for (char& c : text) {
    if (std::iscntrl(static_cast<unsigned char>(c))) c = '?';
  }
  return text;
}

std::variant<Request, std::string> parse_request(std::string_view line) {
  if (line.size() > kMaxLine) return std::string("line too long");
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  const std::vector<std::string_view> w = words_of(line);
  if (w.empty()) return std::string("empty request");
  const std::string_view verb = w[0];
  if (verb == "status" || verb == "cursor") {
    if (w.size() != 1) return fmt::format("{} takes no arguments", verb);
    if (verb == "status") return Request{StatusRequest{}};
    return Request{CursorRequest{}};
  }
  if (verb == "position") return parse_position(w);
  if (verb == "layout") return parse_layout(w);
  if (verb == "passthrough") {
    if (w.size() != 2 || (w[1] != "on" && w[1] != "off")) return std::string("passthrough needs on or off");
    return Request{PassthroughRequest{w[1] == "on"}};
  }
  if (verb == "helper") {
    if (w.size() != 2 || !printable_word(w[1]))
      return std::string("helper needs one backend name (letters, digits, -_.)");
    return Request{HelperRequest{std::string(w[1])}};
  }
  return std::string(
      "unknown request; expected status, cursor, position X Y, layout X Y W H, helper NAME or passthrough on|off");
}

std::string format_request(const Request& request) {
  struct Format {
    std::string operator()(const StatusRequest&) const { return "status"; }
    std::string operator()(const CursorRequest&) const { return "cursor"; }
    std::string operator()(const PositionRequest& r) const {
      return fmt::format("position {} {}", r.position.x, r.position.y);
    }
    std::string operator()(const LayoutRequest& r) const {
      std::string line = fmt::format("layout {} {} {} {}", r.desktop.x, r.desktop.y, r.desktop.w, r.desktop.h);
      for (const Rect& o : r.outputs) line += fmt::format(" {} {} {} {}", o.x, o.y, o.w, o.h);
      return line;
    }
    std::string operator()(const HelperRequest& r) const { return "helper " + r.backend; }
    std::string operator()(const PassthroughRequest& r) const { return r.on ? "passthrough on" : "passthrough off"; }
  };
  return std::visit(Format{}, request);
}

std::string socket_path_problem(std::string_view path) {
  if (path.empty()) return "is empty: give a path";
  if (path.size() > kMaxSocketPath)
    return fmt::format("is {} bytes long; a socket's path has at most {}", path.size(), kMaxSocketPath);
  return "";
}

std::string format_ok(std::string_view words) { return words.empty() ? "ok" : fmt::format("ok {}", words); }

std::string format_error(std::string_view reason) {
  std::string clean(reason.substr(0, kMaxLine - 6));
  for (char& c : clean) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return "error " + clean;
}

std::string format_status(const Status& s) {
  const std::string head = fmt::format(
      "mode={} mice={} held_elsewhere={} regions={} desktop={},{},{},{} cursor={},{} helper={} "
      "passthrough={} scene=",
      s.absolute ? "absolute" : "relative", s.mice, s.held_elsewhere, s.regions, s.desktop.x, s.desktop.y, s.desktop.w,
      s.desktop.h, s.cursor.x, s.cursor.y, s.helper ? "yes" : "no", s.passthrough ? "on" : "off");
  std::string scene = printable(s.scene.empty() ? "default" : s.scene);
  // The line stays within kMaxLine, which the reader holds the daemon to: a scene path too long for it (PATH_MAX is
  // 4096) keeps its end, where the file's name is, after "...".
  const std::size_t room = kMaxLine - std::string_view("ok ").size() - head.size();
  if (scene.size() > room) scene = "..." + scene.substr(scene.size() - (room - 3));
  return format_ok(head + scene);
}

std::string format_cursor(Vec2 cursor) { return format_ok(fmt::format("{} {}", cursor.x, cursor.y)); }

std::optional<Reply> parse_reply(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line == "ok") return Reply{true, ""};
  if (line.starts_with("ok ")) return Reply{true, std::string(line.substr(3))};
  if (line.starts_with("error ")) return Reply{false, std::string(line.substr(6))};
  return std::nullopt;
}

std::optional<Vec2> parse_cursor(std::string_view words) {
  const std::vector<std::string_view> w = words_of(words);
  if (w.size() != 2) return std::nullopt;
  const auto x = number(w[0]), y = number(w[1]);
  if (!x || !y) return std::nullopt;
  return Vec2{*x, *y};
}

std::optional<Status> parse_status(std::string_view words) {
  Status s;
  int seen = 0;
  std::set<std::string> given;
  // The scene's path comes last and may hold spaces.
  const std::size_t scene_at = words.starts_with("scene=") ? 0 : words.find(" scene=");
  if (scene_at == std::string_view::npos) return std::nullopt;
  s.scene = std::string(words.substr(scene_at + (scene_at == 0 ? 6 : 7)));
  words = words.substr(0, scene_at);
  ++seen;
  for (const std::string_view word : words_of(words)) {
    const std::size_t eq = word.find('=');
    if (eq == std::string_view::npos) return std::nullopt;
    const std::string_view key = word.substr(0, eq), value = word.substr(eq + 1);
    std::vector<std::string_view> parts;
    for (std::size_t at = 0; at <= value.size();) {
      const std::size_t end = std::min(value.find(',', at), value.size());
      parts.push_back(value.substr(at, end - at));
      at = end + 1;
    }
    bool good = true;
    // Each field once: a repeated one would stand in for one that is missing.
    if (key == "mode" || key == "mice" || key == "regions" || key == "desktop" || key == "cursor" || key == "helper" ||
        key == "held_elsewhere" || key == "passthrough") {
      if (!given.insert(std::string(key)).second) return std::nullopt;
    }
    if (key == "mode") {
      good = value == "absolute" || value == "relative";
      s.absolute = value == "absolute";
    } else if (key == "mice" || key == "regions") {
      const auto n = integer(value);
      good = n.has_value() && *n >= 0;
      (key == "mice" ? s.mice : s.regions) = n.value_or(0);
    } else if (key == "held_elsewhere") {
      const auto n = integer(value);
      if (!n || *n < 0) return std::nullopt;
      s.held_elsewhere = *n;
      continue;  // optional: older daemons do not say
    } else if (key == "desktop") {
      std::int32_t v[4] = {};
      good = parts.size() == 4;
      for (std::size_t i = 0; good && i < 4; ++i) {
        const auto n = integer(parts[i]);
        good = n.has_value();
        v[i] = n.value_or(0);
      }
      s.desktop = {v[0], v[1], v[2], v[3]};
      good = good && is_valid_desktop(s.desktop);
    } else if (key == "cursor") {
      good = parts.size() == 2 && number(parts[0]) && number(parts[1]);
      if (good) s.cursor = {*number(parts[0]), *number(parts[1])};
    } else if (key == "helper") {
      good = value == "yes" || value == "no";
      s.helper = value == "yes";
    } else if (key == "passthrough") {
      if (value != "on" && value != "off") return std::nullopt;
      s.passthrough = value == "on";
      continue;  // optional: older daemons do not say
    } else {
      continue;  // a newer daemon may say more
    }
    if (!good) return std::nullopt;
    ++seen;
  }
  if (seen < 7) return std::nullopt;
  return s;
}

bool LineBuffer::append(std::string_view bytes) {
  // Every line the bytes end or add, not only the last: a long line may come whole within one read.
  std::size_t start = pending_.rfind('\n');
  start = start == std::string::npos ? 0 : start + 1;
  pending_.append(bytes);
  for (std::size_t newline = pending_.find('\n', start); newline != std::string::npos;
       newline = pending_.find('\n', start)) {
    if (newline - start > kMaxLine) return false;
    start = newline + 1;
  }
  return pending_.size() - start <= kMaxLine;
}

std::optional<std::string> LineBuffer::next_line() {
  const std::size_t newline = pending_.find('\n');
  if (newline == std::string::npos) return std::nullopt;
  std::string line = pending_.substr(0, newline);
  pending_.erase(0, newline + 1);
  return line;
}

}  // namespace ph::control
