// pseudohaptic-session's side of the control socket: line splitting, the requests it formats, the
// layout's bounding box, the reconnection back-off and what it makes of the daemon's lines.
#include <gtest/gtest.h>

#include <clocale>
#include <string>

#include "session/protocol.hpp"

namespace ph::session {
namespace {

TEST(SessionLines, SplitsWhereverTheBytesBreak) {
  LineSplitter lines;
  lines.feed("ok\nque");
  EXPECT_EQ(lines.next(), "ok");
  EXPECT_EQ(lines.next(), std::nullopt);  // "que" is not a line yet
  lines.feed("ry\r\nerror bad");
  EXPECT_EQ(lines.next(), "query");  // a '\r' before the '\n' goes too
  EXPECT_EQ(lines.next(), std::nullopt);
  lines.feed(" thing\n\n");
  EXPECT_EQ(lines.next(), "error bad thing");
  EXPECT_EQ(lines.next(), "");
  EXPECT_FALSE(lines.overflowed());
}

TEST(SessionLines, ManyLinesInOneReadAndOneByteAtATime) {
  LineSplitter lines;
  std::string stream;
  for (int i = 0; i < 500; ++i) stream += "ok " + std::to_string(i) + "\n";
  for (char c : stream) lines.feed(std::string(1, c));
  for (int i = 0; i < 500; ++i) ASSERT_EQ(lines.next(), "ok " + std::to_string(i));
  EXPECT_EQ(lines.next(), std::nullopt);
}

TEST(SessionLines, ALineOfTheLimitPassesOneMoreByteBreaksTheStream) {
  LineSplitter at_limit;
  at_limit.feed(std::string(kMaxLine, 'a') + "\n");
  EXPECT_EQ(at_limit.next()->size(), kMaxLine);
  EXPECT_FALSE(at_limit.overflowed());

  LineSplitter over;
  over.feed(std::string(kMaxLine + 1, 'a'));  // no newline yet, already too long
  EXPECT_EQ(over.next(), std::nullopt);
  EXPECT_TRUE(over.overflowed());
  over.feed("\nok\n");  // nothing after a broken line is trusted
  EXPECT_EQ(over.next(), std::nullopt);

  LineSplitter over_with_newline;
  over_with_newline.feed(std::string(kMaxLine + 1, 'a') + "\nok\n");
  EXPECT_EQ(over_with_newline.next(), std::nullopt);
  EXPECT_TRUE(over_with_newline.overflowed());
}

TEST(SessionRequests, AreWholeLinesInTheCLocale) {
  EXPECT_EQ(helper_request("x11"), "helper x11\n");
  EXPECT_EQ(layout_request({0, 0, 1920, 1080}), "layout 0 0 1920 1080\n");
  EXPECT_EQ(layout_request({-1280, -200, 3200, 1280}), "layout -1280 -200 3200 1280\n");
  EXPECT_EQ(position_request({960, 540}), "position 960 540\n");
  EXPECT_EQ(position_request({960.5, 0.25}), "position 960.5 0.25\n");
  EXPECT_EQ(position_request({-0.0001, 1919.9999}), "position 0 1920\n");  // three decimals at most
  EXPECT_EQ(position_request({-12.125, 3}), "position -12.125 3\n");
  // A locale with a decimal comma changes nothing (where the system has one).
  if (std::setlocale(LC_ALL, "de_DE.UTF-8") != nullptr) {
    EXPECT_EQ(position_request({960.5, 0.25}), "position 960.5 0.25\n");
    std::setlocale(LC_ALL, "C");
  }
}

TEST(SessionRequests, RefuseWhatTheDaemonWouldRefuse) {
  EXPECT_EQ(layout_request({0, 0, 0, 1080}), std::nullopt);
  EXPECT_EQ(layout_request({0, 0, 1920, -1}), std::nullopt);
  EXPECT_EQ(position_request({std::nan(""), 1}), std::nullopt);
  EXPECT_EQ(position_request({1, HUGE_VAL}), std::nullopt);
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
  EXPECT_EQ(c.awaiting(), 3u);

  EXPECT_TRUE(c.on_line("ok").complaint.empty());
  const Conversation::Reaction refused = c.on_line("error layout: width must be > 0");
  EXPECT_FALSE(refused.send_position);
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
  EXPECT_EQ(c.on_line("error permission denied: uid 1001 is not in the active session").complaint,
            "the daemon refused '(nothing)': permission denied: uid 1001 is not in the active session");
}

}  // namespace
}  // namespace ph::session
