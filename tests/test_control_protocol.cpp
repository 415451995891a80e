// The control socket's protocol: every request and reply parses back to what was formatted, and what
// is malformed is refused with a reason (docs/SERVICE.md, "The control socket").
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "control/protocol.hpp"

namespace ph::control {
namespace {

Request parsed(std::string_view line) {
  auto result = parse_request(line);
  if (const auto* error = std::get_if<std::string>(&result)) ADD_FAILURE() << line << ": " << *error;
  return std::get<Request>(result);
}

std::string refusal(std::string_view line) {
  auto result = parse_request(line);
  if (std::holds_alternative<Request>(result)) {
    ADD_FAILURE() << "accepted: " << line;
    return "";
  }
  return std::get<std::string>(result);
}

TEST(ControlProtocol, RequestsRoundTrip) {
  EXPECT_TRUE(std::holds_alternative<StatusRequest>(parsed("status")));
  EXPECT_TRUE(std::holds_alternative<CursorRequest>(parsed("cursor\r")));
  const auto p = std::get<PositionRequest>(parsed("position 960.5 -3.25"));
  EXPECT_EQ(p.position, (Vec2{960.5, -3.25}));
  const auto l = std::get<LayoutRequest>(parsed("layout -1920 0 3840 1080"));
  EXPECT_EQ(l.desktop, (Rect{-1920, 0, 3840, 1080}));
  EXPECT_TRUE(l.outputs.empty());
  // Monitors of different sizes: the outputs follow the desktop.
  const auto uneven = std::get<LayoutRequest>(parsed("layout 0 0 4480 1440 0 0 2560 1440 2560 0 1920 1080"));
  EXPECT_EQ(uneven.desktop, (Rect{0, 0, 4480, 1440}));
  EXPECT_EQ(uneven.outputs, (std::vector<Rect>{{0, 0, 2560, 1440}, {2560, 0, 1920, 1080}}));
  EXPECT_EQ(std::get<HelperRequest>(parsed("helper x11")).backend, "x11");
  EXPECT_TRUE(std::get<PassthroughRequest>(parsed("passthrough on")).on);
  EXPECT_FALSE(std::get<PassthroughRequest>(parsed("passthrough off")).on);
  EXPECT_NE(refusal("passthrough yes").find("on or off"), std::string::npos);
  for (const Request& r : {Request{StatusRequest{}}, Request{CursorRequest{}}, Request{PositionRequest{{0.1, 1e-3}}},
                           Request{LayoutRequest{{1, 2, 3, 4}, {}}},
                           Request{LayoutRequest{{-5, 0, 20, 10}, {{-5, 0, 10, 10}, {5, 2, 10, 5}}}},
                           Request{HelperRequest{"wayland-kwin"}}, Request{PassthroughRequest{true}},
                           Request{PassthroughRequest{false}}}) {
    EXPECT_EQ(format_request(parsed(format_request(r))), format_request(r));
  }
  // Extra spaces between words are harmless.
  EXPECT_EQ(std::get<PositionRequest>(parsed("position  1   2")).position, (Vec2{1, 2}));
  // Too small for a double is 0, as strtod reads it (finite, not refused as if it were not); -0 is 0, and a
  // cursor set there reads back without a sign.
  EXPECT_EQ(std::get<PositionRequest>(parsed("position 1e-400 5")).position, (Vec2{0, 5}));
  const Vec2 zero = std::get<PositionRequest>(parsed("position -0 -0.0")).position;
  EXPECT_FALSE(std::signbit(zero.x) || std::signbit(zero.y));
  EXPECT_EQ(format_cursor(zero), "ok 0 0");
  EXPECT_EQ(std::get<PositionRequest>(parsed("position -1e-320 1")).position.x, -1e-320);  // subnormal: kept
}

TEST(ControlProtocol, MalformedRequestsAreRefusedWithAReason) {
  EXPECT_NE(refusal("").find("empty"), std::string::npos);
  EXPECT_NE(refusal("jump 1 2").find("unknown request"), std::string::npos);
  EXPECT_NE(refusal("status now").find("no arguments"), std::string::npos);
  EXPECT_NE(refusal("position 1").find("X Y"), std::string::npos);
  EXPECT_NE(refusal("position 1 nan").find("finite"), std::string::npos);
  EXPECT_NE(refusal("position 1 inf").find("finite"), std::string::npos);
  EXPECT_NE(refusal("position 1,5 2").find("finite"), std::string::npos);
  EXPECT_NE(refusal("position 1e300 2").find("within"), std::string::npos);
  EXPECT_NE(refusal("position 1e400 2").find("finite"), std::string::npos);  // too large: infinite
  EXPECT_NE(refusal("position 1e400x 2").find("finite"), std::string::npos);
  EXPECT_NE(refusal("layout 0 0 0 1080").find("from 1"), std::string::npos);
  EXPECT_NE(refusal("layout 0 0 1.5 1080").find("whole"), std::string::npos);
  EXPECT_NE(refusal("layout 0 0 99999999999 1080").find("whole"), std::string::npos);
  EXPECT_NE(refusal("layout 0 0 1920 1080 0 0 1920").find("outputs' X Y W H"), std::string::npos);  // 3 of 4
  EXPECT_NE(refusal("layout 0 0 1920 1080 0 0 1921 1080").find("not a rectangle within"), std::string::npos);
  EXPECT_NE(refusal("layout 0 0 1920 1080 -1 0 100 100").find("not a rectangle within"), std::string::npos);
  EXPECT_NE(refusal("layout 0 0 1920 1080 0 0 0 100").find("not a rectangle within"), std::string::npos);
  std::string seventeen = "layout 0 0 1920 1080";
  for (int i = 0; i < 17; ++i) seventeen += " 0 0 10 10";
  EXPECT_NE(refusal(seventeen).find("up to 16 outputs"), std::string::npos);
  EXPECT_NE(refusal("helper").find("backend"), std::string::npos);
  EXPECT_NE(refusal("helper x11; rm").find("backend"), std::string::npos);
  EXPECT_NE(refusal(std::string(kMaxLine + 1, 'a')).find("too long"), std::string::npos);
}

TEST(ControlProtocol, StatusAndCursorRepliesRoundTrip) {
  Status s;
  s.absolute = false;
  s.mice = 2;
  s.held_elsewhere = 1;
  s.regions = 3;
  s.desktop = {-1280, 0, 3200, 1080};
  s.cursor = {12.5, 1079.75};
  s.helper = true;
  s.passthrough = true;
  s.scene = "/home/a user/my scene.toml";
  const std::optional<Reply> reply = parse_reply(format_status(s));
  ASSERT_TRUE(reply && reply->ok);
  const std::optional<Status> back = parse_status(reply->text);
  ASSERT_TRUE(back.has_value()) << reply->text;
  EXPECT_EQ(back->absolute, false);
  EXPECT_EQ(back->mice, 2);
  EXPECT_EQ(back->held_elsewhere, 1);
  EXPECT_EQ(back->regions, 3);
  EXPECT_EQ(back->desktop, s.desktop);
  EXPECT_EQ(back->cursor, s.cursor);
  EXPECT_TRUE(back->helper);
  EXPECT_TRUE(back->passthrough);
  EXPECT_EQ(back->scene, s.scene);
  // A newline in the scene's path would end the reply there: it shows as '?'.
  s.scene = "/tmp/new\nline.toml";
  const std::string one_line = format_status(s);
  EXPECT_EQ(one_line.find('\n'), std::string::npos);
  EXPECT_EQ(parse_status(parse_reply(one_line)->text)->scene, "/tmp/new?line.toml");
  EXPECT_FALSE(parse_status("mode=absolute mice=1").has_value());  // incomplete
  EXPECT_FALSE(parse_status("mode=sideways mice=1 regions=0 desktop=0,0,1,1 cursor=0,0 helper=no scene=x"));
  // A daemon of before held_elsewhere: none held.
  const std::optional<Status> older =
      parse_status("mode=absolute mice=1 regions=0 desktop=0,0,1,1 cursor=0,0 helper=no scene=x");
  ASSERT_TRUE(older.has_value());
  EXPECT_EQ(older->held_elsewhere, 0);
  EXPECT_FALSE(
      parse_status("mode=absolute mice=1 held_elsewhere=x regions=0 desktop=0,0,1,1 cursor=0,0 helper=no "
                   "scene=x"));
  // What a daemon never says is no status: a field given twice (standing in for a missing one), an optional field
  // of another value, a count below 0, a desktop that is none.
  const std::string rest = " regions=0 desktop=0,0,1,1 cursor=0,0 helper=no scene=x";
  EXPECT_FALSE(parse_status("mode=absolute mode=absolute mice=1 regions=0 desktop=0,0,1,1 cursor=0,0 scene=x"));
  EXPECT_FALSE(parse_status("mode=absolute mice=1 passthrough=maybe" + rest));
  EXPECT_FALSE(parse_status("mode=absolute mice=-7" + rest));
  EXPECT_FALSE(parse_status("mode=absolute mice=1 held_elsewhere=-1" + rest));
  EXPECT_FALSE(parse_status("mode=absolute mice=1 regions=0 desktop=0,0,-5,0 cursor=0,0 helper=no scene=x"));
  EXPECT_TRUE(parse_status("mode=absolute mice=1 passthrough=on" + rest));
  // A scene path too long for one line (PATH_MAX is 4096) keeps its end, after "...": the line stays readable.
  s.scene = "/" + std::string(3000, 'd') + "/the scene.toml";
  const std::string long_path = format_status(s);
  EXPECT_EQ(long_path.size(), kMaxLine);
  const std::optional<Status> shortened = parse_status(parse_reply(long_path)->text);
  ASSERT_TRUE(shortened.has_value());
  EXPECT_TRUE(shortened->scene.starts_with("...ddd")) << shortened->scene;
  EXPECT_TRUE(shortened->scene.ends_with("d/the scene.toml")) << shortened->scene;

  const std::optional<Reply> cursor = parse_reply(format_cursor({0.25, 3}));
  ASSERT_TRUE(cursor && cursor->ok);
  EXPECT_EQ(parse_cursor(cursor->text), (Vec2{0.25, 3}));
  const std::optional<Reply> error = parse_reply(format_error("no\nnewlines"));
  ASSERT_TRUE(error.has_value());
  EXPECT_FALSE(error->ok);
  EXPECT_EQ(error->text, "no newlines");
  EXPECT_FALSE(parse_reply("query").has_value());  // the daemon's question to a helper is not a reply
}

TEST(ControlProtocol, ASocketPathIsNotEmptyAndFitsASocketAddress) {
  EXPECT_EQ(socket_path_problem(kDefaultSocket), "");
  EXPECT_EQ(socket_path_problem(std::string(kMaxSocketPath, 'a')), "");
  EXPECT_NE(socket_path_problem("").find("empty"), std::string::npos);
  EXPECT_NE(socket_path_problem(std::string(kMaxSocketPath + 1, 'a')).find("at most 107"), std::string::npos);
}

TEST(ControlProtocol, LinesAreSplitAndBounded) {
  LineBuffer lines;
  EXPECT_TRUE(lines.append("sta"));
  EXPECT_FALSE(lines.next_line().has_value());
  EXPECT_TRUE(lines.append("tus\ncursor\npos"));
  EXPECT_EQ(lines.next_line(), "status");
  EXPECT_EQ(lines.next_line(), "cursor");
  EXPECT_FALSE(lines.next_line().has_value());
  EXPECT_TRUE(lines.append(std::string(kMaxLine - 3, '1')));  // "pos" + that = the longest line allowed
  EXPECT_FALSE(lines.append("1"));                            // one byte more without a newline
  // A line too long that comes whole in one read, its newline and more after it, is caught too.
  LineBuffer whole;
  EXPECT_TRUE(whole.append("ok\n" + std::string(kMaxLine, 'x') + "\nok\n"));
  LineBuffer over;
  EXPECT_FALSE(over.append("ok\n" + std::string(kMaxLine + 1, 'x') + "\nok\n"));
  LineBuffer split;  // and one that ends in a later read
  EXPECT_TRUE(split.append(std::string(kMaxLine - 1, 'x')));
  EXPECT_FALSE(split.append("yy\nok\n"));
}

}  // namespace
}  // namespace ph::control
