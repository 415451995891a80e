#include "session/protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <limits>

#include "control/protocol.hpp"
#include "core/engine/desktop_outputs.hpp"

namespace ph::session {

std::string helper_request(std::string_view backend) {
  return control::format_request(control::HelperRequest{std::string(backend)}) + "\n";
}

std::optional<std::string> layout_request(Rect layout, const std::vector<Rect>& outputs) {
  if (!is_valid_desktop(layout)) return std::nullopt;
  return control::format_request(control::LayoutRequest{layout, outputs}) + "\n";
}

std::vector<Rect> outputs_to_report(Rect desktop, const std::vector<Rect>& outputs) {
  std::vector<Rect> shown;
  std::copy_if(outputs.begin(), outputs.end(), std::back_inserter(shown),
               [](const Rect& r) { return r.w > 0 && r.h > 0; });  // a CRTC switched off: no output, not a bad one
  return pointer_outputs(desktop, std::move(shown));
}

std::optional<std::string> position_request(Vec2 position) {
  constexpr double kMax = kMaxDesktopCoordinate;
  if (!is_finite(position) || std::fabs(position.x) > kMax || std::fabs(position.y) > kMax) return std::nullopt;
  return control::format_request(control::PositionRequest{position}) + "\n";
}

std::string passthrough_request(bool on) { return control::format_request(control::PassthroughRequest{on}) + "\n"; }

bool is_listed(const std::vector<std::string>& applications, std::string_view instance, std::string_view class_name) {
  const auto same = [](std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
             return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
           });
  };
  return std::any_of(applications.begin(), applications.end(), [&](const std::string& name) {
    return !name.empty() && (same(name, instance) || same(name, class_name));
  });
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

std::string choose_backend(std::string_view requested, std::string_view x_display_option,
                           std::string_view wayland_display_option, std::string_view wayland_display_env,
                           std::string_view display_env) {
  if (requested != "auto") return std::string(requested);
  if (!wayland_display_option.empty()) return "wayland";
  if (!wayland_display_env.empty() && x_display_option.empty()) return "wayland";
  if (!display_env.empty() || !x_display_option.empty()) return "x11";
  return "";
}

std::string fallback_backend(std::string_view requested, std::string_view chosen, std::string_view x_display_option,
                             std::string_view wayland_display_option, std::string_view display_env) {
  const bool from_environment_alone = requested == "auto" && chosen == "wayland" && wayland_display_option.empty();
  return from_environment_alone && (!display_env.empty() || !x_display_option.empty()) ? "x11" : "";
}

bool Repeats::is_new(std::string_view message) {
  if (message == last_) return false;
  last_ = message;
  return true;
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
  const std::optional<control::Reply> reply = control::parse_reply(line);
  if (!reply) {
    reaction.complaint = fmt::format("the daemon sent a line not understood: '{}'", line);
    return reaction;
  }
  // Refusals of the connection itself, which the daemon sends as it accepts it, before any request is read (and
  // then closes it): no request of the helper's was refused.
  if (!reply->ok && (reply->text.starts_with("permission denied") || reply->text == "too many connections")) {
    reaction.refused_connection = true;
    reaction.complaint = fmt::format("the daemon refused the connection: {}", reply->text);
    return reaction;
  }
  std::string request = "(nothing)";
  if (!awaiting_.empty()) {
    request = std::move(awaiting_.front());
    awaiting_.pop_front();
  }
  reaction.accepted = reply->ok;
  if (!reply->ok) reaction.complaint = fmt::format("the daemon refused '{}': {}", request, reply->text);
  reaction.outputs_refused =
      !reply->ok && request.starts_with("layout ") && std::count(request.begin(), request.end(), ' ') > 4;
  return reaction;
}

Conversation::Reactions Conversation::on_lines(const std::vector<std::string>& lines) {
  Reactions all;
  for (const std::string& line : lines) {
    Reaction one = on_line(line);
    all.send_position = all.send_position || one.send_position;
    all.accepted = all.accepted || one.accepted;
    all.refused_connection = all.refused_connection || one.refused_connection;
    all.outputs_refused = all.outputs_refused || one.outputs_refused;
    if (!one.complaint.empty()) all.complaints.push_back(std::move(one.complaint));
  }
  return all;
}

}  // namespace ph::session
