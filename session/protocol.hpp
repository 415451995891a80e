// The session helper's side of pseudohapticd's control socket (docs/SERVICE.md, "The control socket"),
// pure: the lines it sends (control/protocol.hpp formats them), the layout it reports, how long it waits
// before reconnecting, and what it makes of the daemon's lines. No I/O here; main.cpp does that.
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph::session {

// The requests, each a whole line with its '\n'.
std::string helper_request(std::string_view backend);  // "helper x11"
// "layout X Y W H", then each output's X Y W H; nullopt for a layout the daemon refuses (is_valid_desktop: W and H
// from 1 to 2^20, X and Y within ±2^20). `outputs` as outputs_to_report gives them.
std::optional<std::string> layout_request(Rect layout, const std::vector<Rect>& outputs = {});

// The outputs to tell the daemon on `desktop` (core/engine/desktop_outputs.hpp): none where they cover it (or are
// too many, or reach past it), and none where they do not touch one another: X then lets the pointer roam the whole
// root window, and wlroots moves it across a gap to the nearest output where the model, stopped at the edge of the
// output it left, would never cross.
std::vector<Rect> outputs_to_report(Rect desktop, const std::vector<Rect>& outputs);
// "position X Y"; nullopt for a coordinate the daemon refuses (not finite, or past ±2^20: a compositor that
// misbehaves), which would only earn an error for every query.
std::optional<std::string> position_request(Vec2 position);
std::string passthrough_request(bool on);  // "passthrough on" / "passthrough off"

// Whether a window of this WM_CLASS (its instance and class names) belongs to one of `applications`,
// the names the user listed for pass-through (either name matches, whatever the case).
bool is_listed(const std::vector<std::string>& applications, std::string_view instance, std::string_view class_name);

// The bounding box of the outputs with a positive size; nullopt when there is none.
std::optional<Rect> bounding_box(const std::vector<Rect>& outputs);

// The backend to use: `requested` ("x11", "wayland"), or for "auto" the one the options or the session name: wayland
// where a Wayland display was given with --wayland-display, or WAYLAND_DISPLAY is set (unless an X display was
// given with --display), else x11 where DISPLAY is set or an X display was given; empty when none applies. The
// option and environment values are empty when not given or unset.
std::string choose_backend(std::string_view requested, std::string_view x_display_option,
                           std::string_view wayland_display_option, std::string_view wayland_display_env,
                           std::string_view display_env);

// The backend to try when the one chosen cannot open its display: x11 where "auto" chose wayland from a
// WAYLAND_DISPLAY alone (a variable left in the user manager by an earlier Wayland session) and an X display is at
// hand (DISPLAY, or --display); empty otherwise.
std::string fallback_backend(std::string_view requested, std::string_view chosen, std::string_view x_display_option,
                             std::string_view wayland_display_option, std::string_view display_env);

// A message the helper logs at its level only when it is not the one it logged last: a daemon that refuses every
// reconnection (a session it does not let in) would otherwise log the same line every 5 s for as long as the session
// runs. forget() when things went well again, so that the next failure is said.
class Repeats {
 public:
  bool is_new(std::string_view message);
  void forget() { last_.clear(); }

 private:
  std::string last_;
};

// How long to wait before the next connection attempt after `failures` failed ones in a row: 250 ms,
// doubling, at most 5 s.
std::chrono::milliseconds reconnect_delay(int failures);

// One connection's conversation: the requests the helper has sent and awaits replies to, in order, and
// what a line from the daemon asks of it.
class Conversation {
 public:
  // What the helper does about one line from the daemon.
  struct Reaction {
    bool send_position = false;       // "query": answer with the real cursor's position
    bool accepted = false;            // an `ok` reply: the daemon takes this helper's requests
    bool refused_connection = false;  // the daemon refused the connection itself, before any request
    std::string complaint;            // non-empty: a line to log (an error reply, or a line not understood)
    // A layout with its outputs refused: a daemon that reads `layout X Y W H` alone (one older than this helper).
    bool outputs_refused = false;
  };
  // What a batch of lines read at once asks: a position once however many `query` lines came (each answer costs
  // a compositor query, which may take its whole time limit, and one position answers them all), whether any
  // request was accepted, and the complaints in order.
  struct Reactions {
    bool send_position = false;
    bool accepted = false;
    bool refused_connection = false;
    bool outputs_refused = false;
    std::vector<std::string> complaints;
  };

  // Notes a request sent (its line, with or without '\n'), to pair with its reply.
  void sent(std::string_view request);
  Reaction on_line(std::string_view line);
  Reactions on_lines(const std::vector<std::string>& lines);
  // Requests still waiting for their reply.
  std::size_t awaiting() const { return awaiting_.size(); }

 private:
  std::deque<std::string> awaiting_;  // the requests' lines without '\n'
};

}  // namespace ph::session
