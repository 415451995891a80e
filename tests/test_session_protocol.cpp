// pseudohaptic-session's side of the control socket: the requests it sends (which the daemon's parser
// must read back), the layout's bounding box, the backend `--backend auto` picks, the reconnection
// back-off and what it makes of the daemon's lines. Splitting the stream into lines is control/'s
// (tests/test_control_protocol.cpp).
#include <gtest/gtest.h>

#include <clocale>
#include <cmath>
#include <string>
#include <variant>

#include "control/protocol.hpp"
#include "session/protocol.hpp"

namespace ph::session {
namespace {

TEST(SessionRequests, AreWholeLinesTheDaemonParses) {
  EXPECT_EQ(helper_request("x11"), "helper x11\n");
  EXPECT_EQ(layout_request({0, 0, 1920, 1080}), "layout 0 0 1920 1080\n");
  EXPECT_EQ(layout_request({-1280, -200, 3200, 1280}), "layout -1280 -200 3200 1280\n");
  EXPECT_EQ(layout_request({0, 0, 4480, 1440}, {{0, 0, 2560, 1440}, {2560, 0, 1920, 1080}}),
            "layout 0 0 4480 1440 0 0 2560 1440 2560 0 1920 1080\n");
  EXPECT_EQ(position_request({960, 540}), "position 960 540\n");
  EXPECT_EQ(position_request({960.5, 0.25}), "position 960.5 0.25\n");
  // Whatever it sends, the daemon's parser reads back the same request.
  for (const std::string& line :
       {helper_request("x11"), *layout_request({-1280, -200, 3200, 1280}),
        *layout_request({-1280, -200, 3200, 1280}, {{-1280, -200, 1280, 720}, {0, 0, 1920, 1080}}),
        *position_request({-12.125, 1919.75}), *position_request({3, 0}), passthrough_request(true),
        passthrough_request(false)}) {
    const auto parsed = control::parse_request(std::string_view(line).substr(0, line.size() - 1));  // no '\n'
    ASSERT_TRUE(std::holds_alternative<control::Request>(parsed)) << line << ": " << std::get<std::string>(parsed);
    EXPECT_EQ(control::format_request(std::get<control::Request>(parsed)) + "\n", line);
  }
  // A locale with a decimal comma changes nothing (where the system has one).
  if (std::setlocale(LC_ALL, "de_DE.UTF-8") != nullptr) {
    EXPECT_EQ(position_request({960.5, 0.25}), "position 960.5 0.25\n");
    std::setlocale(LC_ALL, "C");
  }
}

// The outputs told: where they leave part of the desktop uncovered, and touch one another (X lets the pointer roam the
// whole root window otherwise, and wlroots crosses a gap the model would stop at).
TEST(SessionRequests, OutputsAreToldWhereTheyLeaveDeadSpace) {
  const Rect desktop{0, 0, 4480, 1440};
  const std::vector<Rect> uneven{{0, 0, 2560, 1440}, {2560, 0, 1920, 1080}};
  EXPECT_EQ(outputs_to_report(desktop, uneven), uneven);
  EXPECT_TRUE(outputs_to_report({0, 0, 3840, 1080}, {{0, 0, 1920, 1080}, {1920, 0, 1920, 1080}}).empty());
  EXPECT_TRUE(outputs_to_report({0, 0, 1920, 1080}, {{0, 0, 1920, 1080}, {0, 0, 1920, 1080}}).empty());
  EXPECT_TRUE(outputs_to_report({0, 0, 3920, 1080}, {{0, 0, 1920, 1080}, {2000, 0, 1920, 1080}}).empty());  // a gap
  // X's root window larger than its one CRTC (xrandr --fb): the CRTC is told.
  EXPECT_EQ(outputs_to_report(desktop, {{0, 0, 1920, 1080}}), (std::vector<Rect>{{0, 0, 1920, 1080}}));
  // A CRTC switched off (no size) is no output.
  EXPECT_TRUE(outputs_to_report({0, 0, 1920, 1080}, {{0, 0, 1920, 1080}, {1920, 0, 0, 0}}).empty());
}

// A daemon older than the outputs refuses a layout that carries them: the helper is told, to send it without them.
TEST(SessionConversation, ARefusedLayoutWithOutputsIsSaid) {
  Conversation c;
  c.sent("layout 0 0 4480 1440 0 0 2560 1440 2560 0 1920 1080\n");
  const Conversation::Reaction refused = c.on_line("error layout needs X Y W H (whole px)");
  EXPECT_TRUE(refused.outputs_refused);
  c.sent("layout 0 0 0 1080\n");
  EXPECT_FALSE(c.on_line("error layout: W and H must be from 1").outputs_refused);  // no outputs in it
  c.sent("layout 0 0 4480 1440 0 0 2560 1440 2560 0 1920 1080\n");
  EXPECT_FALSE(c.on_line("ok").outputs_refused);
}

TEST(SessionRequests, RefuseWhatTheDaemonWouldRefuse) {
  EXPECT_EQ(layout_request({0, 0, 0, 1080}), std::nullopt);
  EXPECT_EQ(layout_request({0, 0, 1920, -1}), std::nullopt);
  EXPECT_EQ(position_request({std::nan(""), 1}), std::nullopt);
  EXPECT_EQ(position_request({1, HUGE_VAL}), std::nullopt);
  // What a misbehaving compositor says (Hyprland's int32 maximum, a Wayfire reply of 1e308): past the daemon's
  // ±2^20, which would answer each with an error.
  EXPECT_EQ(position_request({2147483647.5, 2147483647.5}), std::nullopt);
  EXPECT_EQ(position_request({1e308, 0}), std::nullopt);
  EXPECT_EQ(position_request({-1048576, 1048576}), "position -1048576 1048576\n");
  EXPECT_EQ(layout_request({0, 0, (1 << 20) + 1, 1080}), std::nullopt);
  EXPECT_EQ(layout_request({-(1 << 20) - 1, 0, 1920, 1080}), std::nullopt);
}

TEST(SessionBackend, AutoPrefersWaylandThenX11) {
  EXPECT_EQ(choose_backend("auto", "", "", "wayland-0", ":0"), "wayland");  // Xwayland sets both
  EXPECT_EQ(choose_backend("auto", "", "", "wayland-0", ""), "wayland");
  EXPECT_EQ(choose_backend("auto", "", "", "", ":0"), "x11");
  EXPECT_EQ(choose_backend("auto", ":1", "", "wayland-0", ""), "x11");  // --display names an X display
  EXPECT_EQ(choose_backend("auto", "", "", "", ""), "");
  EXPECT_EQ(choose_backend("x11", "", "", "wayland-0", ""), "x11");  // asked for: taken as it is
  EXPECT_EQ(choose_backend("wayland", "", "", "", ":0"), "wayland");
  // --wayland-display names a Wayland display: taken, with or without WAYLAND_DISPLAY, and over DISPLAY.
  EXPECT_EQ(choose_backend("auto", "", "wayland-1", "", ""), "wayland");
  EXPECT_EQ(choose_backend("auto", "", "wayland-1", "", ":0"), "wayland");
}

// A WAYLAND_DISPLAY that auto followed and that cannot be opened (left in the user manager by an earlier Wayland
// session, in an X session now): X is tried where an X display is at hand, and only then.
TEST(SessionBackend, AWaylandDisplayFromTheEnvironmentAloneFallsBackToX11) {
  EXPECT_EQ(fallback_backend("auto", "wayland", "", "", ":0"), "x11");
  EXPECT_EQ(fallback_backend("auto", "wayland", "", "", ""), "");             // no X display
  EXPECT_EQ(fallback_backend("auto", "wayland", "", "wayland-1", ":0"), "");  // --wayland-display: meant
  EXPECT_EQ(fallback_backend("wayland", "wayland", "", "", ":0"), "");        // --backend wayland: meant
  EXPECT_EQ(fallback_backend("auto", "x11", "", "", ":0"), "");
}

// A refusal the daemon says on every reconnection is logged once, and again after things went well.
TEST(SessionLog, ARepeatedMessageIsNewOnlyAfterAnother) {
  Repeats r;
  EXPECT_TRUE(r.is_new("the daemon refused the connection: permission denied"));
  EXPECT_FALSE(r.is_new("the daemon refused the connection: permission denied"));
  EXPECT_TRUE(r.is_new("the daemon refused 'layout 0 0 0 0': layout: W and H must be from 1"));
  EXPECT_TRUE(r.is_new("the daemon refused the connection: permission denied"));
  r.forget();  // a request accepted
  EXPECT_TRUE(r.is_new("the daemon refused the connection: permission denied"));
}

TEST(SessionPassthrough, ListedApplicationsMatchEitherNameInAnyCase) {
  EXPECT_EQ(passthrough_request(true), "passthrough on\n");
  EXPECT_EQ(passthrough_request(false), "passthrough off\n");
  const std::vector<std::string> listed{"steam_app_570", "Xonotic"};
  EXPECT_TRUE(is_listed(listed, "steam_app_570", "steam_app_570"));
  EXPECT_TRUE(is_listed(listed, "xonotic-glx", "XONOTIC"));  // the class name, another case
  EXPECT_FALSE(is_listed(listed, "firefox-esr", "firefox-esr"));
  EXPECT_FALSE(is_listed(listed, "steam_app_57", "Steam"));  // whole names only
  EXPECT_FALSE(is_listed({}, "xonotic", "Xonotic"));
  EXPECT_FALSE(is_listed({""}, "", ""));  // an empty name lists nothing
}

TEST(SessionLayout, IsTheBoundingBoxOfTheOutputs) {
  EXPECT_EQ(bounding_box({}), std::nullopt);
  EXPECT_EQ(bounding_box({{0, 0, 0, 0}}), std::nullopt);  // a disabled output
  EXPECT_EQ(bounding_box({{0, 0, 1920, 1080}}), (Rect{0, 0, 1920, 1080}));
  // Side by side, the second one taller and lower; one left of the origin; a mirror; a disabled one.
  EXPECT_EQ(bounding_box({{0, 0, 1920, 1080}, {1920, 200, 1280, 1024}}), (Rect{0, 0, 3200, 1224}));
  EXPECT_EQ(bounding_box({{0, 0, 1920, 1080}, {-1280, 0, 1280, 720}, {0, 0, 1920, 1080}, {5000, 5000, 0, 0}}),
            (Rect{-1280, 0, 3200, 1080}));
}

TEST(SessionReconnect, BacksOffUpToFiveSeconds) {
  using std::chrono::milliseconds;
  EXPECT_EQ(reconnect_delay(0), milliseconds(250));
  EXPECT_EQ(reconnect_delay(1), milliseconds(250));
  EXPECT_EQ(reconnect_delay(2), milliseconds(500));
  EXPECT_EQ(reconnect_delay(3), milliseconds(1000));
  EXPECT_EQ(reconnect_delay(5), milliseconds(4000));
  EXPECT_EQ(reconnect_delay(6), milliseconds(5000));
  EXPECT_EQ(reconnect_delay(1000000), milliseconds(5000));
}

TEST(SessionConversation, AnswersQueriesAndPairsRepliesWithRequests) {
  Conversation c;
  c.sent("helper x11\n");
  c.sent("layout 0 0 1920 1080\n");
  c.sent("position 960 540");
  EXPECT_EQ(c.awaiting(), 3u);

  // A query may come before the replies; it asks for a position and is no reply itself.
  const Conversation::Reaction query = c.on_line("query");
  EXPECT_TRUE(query.send_position);
  EXPECT_TRUE(query.complaint.empty());
  EXPECT_FALSE(query.accepted);
  EXPECT_EQ(c.awaiting(), 3u);

  const Conversation::Reaction ok = c.on_line("ok");
  EXPECT_TRUE(ok.complaint.empty());
  EXPECT_TRUE(ok.accepted);  // the daemon takes this helper: the reconnect back-off starts over
  const Conversation::Reaction refused = c.on_line("error layout: width must be > 0");
  EXPECT_FALSE(refused.send_position);
  EXPECT_FALSE(refused.accepted);
  EXPECT_EQ(refused.complaint, "the daemon refused 'layout 0 0 1920 1080': layout: width must be > 0");
  EXPECT_TRUE(c.on_line("ok extra words").complaint.empty());
  EXPECT_EQ(c.awaiting(), 0u);
}

TEST(SessionConversation, ComplainsAboutLinesItDoesNotKnow) {
  Conversation c;
  for (const char* line : {"", "okay", "querying", "QUERY", "errors"}) {
    const Conversation::Reaction r = c.on_line(line);
    EXPECT_FALSE(r.send_position) << line;
    EXPECT_NE(r.complaint.find("not understood"), std::string::npos) << line;
  }
  // An error with no request waiting still gets logged.
  EXPECT_EQ(c.on_line("error layout: W and H must be from 1 to 1048576").complaint,
            "the daemon refused '(nothing)': layout: W and H must be from 1 to 1048576");
}

// The daemon refuses a connection as it accepts it, before it reads a request: said as the connection's refusal, not
// blamed on the helper's first request, which stays waiting for its reply.
TEST(SessionConversation, ARefusedConnectionIsNotARefusedRequest) {
  Conversation c;
  c.sent("helper x11\n");
  EXPECT_EQ(
      c.on_line("error permission denied: uid 1001 is neither root nor the user of an active local session").complaint,
      "the daemon refused the connection: permission denied: uid 1001 is neither root nor the user of an active "
      "local session");
  EXPECT_EQ(c.on_line("error too many connections").complaint,
            "the daemon refused the connection: too many connections");
  EXPECT_EQ(c.awaiting(), 1u);
  EXPECT_TRUE(c.on_lines({"error too many connections"}).refused_connection);
  EXPECT_FALSE(c.on_line("error layout: W and H must be from 1 to 1048576").refused_connection);  // a request's
}

// Lines read at once: one position for however many queries (each costs a compositor query, up to its time limit),
// and every complaint.
TEST(SessionConversation, QueriesReadAtOnceAskForOnePosition) {
  Conversation c;
  c.sent("layout 0 0 1920 1080\n");
  c.sent("position 1 2\n");
  const Conversation::Reactions r =
      c.on_lines({"query", "query", "ok", "query", "error position: X and Y", "nonsense"});
  EXPECT_TRUE(r.send_position);
  EXPECT_TRUE(r.accepted);
  EXPECT_FALSE(r.refused_connection);
  EXPECT_EQ(r.complaints, (std::vector<std::string>{"the daemon refused 'position 1 2': position: X and Y",
                                                    "the daemon sent a line not understood: 'nonsense'"}));
  const Conversation::Reactions none = c.on_lines({});
  EXPECT_FALSE(none.send_position || none.accepted);
  EXPECT_TRUE(none.complaints.empty());
}

}  // namespace
}  // namespace ph::session
