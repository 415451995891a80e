// pseudohaptic-session's Wayland side: the layout made of the outputs' logical rectangles, what it makes
// of Hyprland's and Wayfire's answers, and its Hyprland and Wayfire clients against stand-in servers that
// speak as those compositors do (Hyprland: the request, then the answer and the end of the connection;
// Wayfire: length-prefixed JSON both ways).
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <ostream>
#include <string>
#include <thread>

#include "common/unique_fd.hpp"
#include "session/compositor_answers.hpp"
#include "session/compositor_cursor.hpp"
#include "tests/geometry_printers.hpp"
#include "tests/scoped_env.hpp"
#include "tests/scratch_dir.hpp"

namespace ph::session {
namespace {

using namespace std::chrono_literals;

TEST(WaylandLayout, UsesXdgOutputsLogicalRectangles) {
  WaylandOutput scaled;  // a 3200x1800 panel at scale 2 on the right of a 1920x1080 one
  scaled.logical = Rect{1920, 0, 1600, 900};
  scaled.mode_width = 3200;
  scaled.mode_height = 1800;
  scaled.scale = 2;
  scaled.x = 1920;
  WaylandOutput plain;
  plain.logical = Rect{0, 0, 1920, 1080};
  plain.mode_width = 1920;
  plain.mode_height = 1080;
  EXPECT_EQ(logical_rect(scaled), (Rect{1920, 0, 1600, 900}));
  EXPECT_EQ(wayland_layout({plain, scaled}), (Rect{0, 0, 3520, 1080}));
  // A fractional scale: only xdg-output knows the logical size (2560 / 1.25 = 2048).
  WaylandOutput fractional;
  fractional.logical = Rect{-2048, -300, 2048, 1152};
  fractional.mode_width = 2560;
  fractional.mode_height = 1440;
  fractional.scale = 2;  // wl_output rounds the scale up
  EXPECT_EQ(wayland_layout({plain, fractional}), (Rect{-2048, -300, 3968, 1380}));
}

TEST(WaylandLayout, WithoutXdgOutputDividesTheModeByTheScaleAndTurnsIt) {
  WaylandOutput o;
  o.x = 100;
  o.y = 50;
  o.mode_width = 3840;
  o.mode_height = 2160;
  o.scale = 2;
  EXPECT_EQ(logical_rect(o), (Rect{100, 50, 1920, 1080}));
  o.transform = 1;  // 90 degrees: a portrait output
  EXPECT_EQ(logical_rect(o), (Rect{100, 50, 1080, 1920}));
  o.transform = 2;  // 180 degrees
  EXPECT_EQ(logical_rect(o), (Rect{100, 50, 1920, 1080}));
  o.transform = 7;  // flipped-270
  EXPECT_EQ(logical_rect(o), (Rect{100, 50, 1080, 1920}));
  o.scale = 0;  // a compositor's nonsense is taken as 1
  EXPECT_EQ(logical_rect(o), (Rect{100, 50, 2160, 3840}));
}

TEST(WaylandLayout, IsNothingWithoutAnOutputOfSomeSize) {
  EXPECT_EQ(wayland_layout({}), std::nullopt);
  WaylandOutput no_mode;  // described before its mode arrived
  EXPECT_EQ(wayland_layout({no_mode}), std::nullopt);
  WaylandOutput real;
  real.logical = Rect{0, 0, 1280, 720};
  EXPECT_EQ(wayland_layout({no_mode, real}), (Rect{0, 0, 1280, 720}));
}

TEST(HyprlandAnswers, CursorposIsTheCentreOfThePixelItNames) {
  EXPECT_EQ(parse_hyprland_cursorpos("640, 360"), (Vec2{640.5, 360.5}));
  EXPECT_EQ(parse_hyprland_cursorpos("-1920, 0\n"), (Vec2{-1919.5, 0.5}));
  EXPECT_EQ(parse_hyprland_cursorpos("0, -5"), (Vec2{0.5, -4.5}));
  for (const char* bad : {"", "ok", "640,360", "640 360", "640, ", ", 360", "640, 360, 1", "640.5, 360",
                          "unknown request", "99999999999, 1", "{\"x\": 640, \"y\": 360}"}) {
    EXPECT_EQ(parse_hyprland_cursorpos(bad), std::nullopt) << bad;
  }
}

TEST(HyprlandAnswers, TheSocketIsUnderTheRuntimeDirectoryThenTmp) {
  EXPECT_EQ(
      hyprland_socket_candidates("/run/user/1000", "abc_123_456"),
      (std::vector<std::string>{"/run/user/1000/hypr/abc_123_456/.socket.sock", "/tmp/hypr/abc_123_456/.socket.sock"}));
  EXPECT_EQ(hyprland_socket_candidates("", "abc"), (std::vector<std::string>{"/tmp/hypr/abc/.socket.sock"}));
  EXPECT_TRUE(hyprland_socket_candidates("/run/user/1000", "").empty());
  EXPECT_TRUE(hyprland_socket_candidates("/run/user/1000", "../x").empty());
  EXPECT_TRUE(hyprland_socket_candidates("/run/user/1000", "..").empty());
}

TEST(WayfireAnswers, MessagesCarryTheirLengthFirst) {
  const std::string request = wayfire_cursor_request();
  ASSERT_GE(request.size(), kWayfireHeader);
  const std::string_view json = std::string_view(request).substr(kWayfireHeader);
  EXPECT_EQ(wayfire_message_length(std::string_view(request).substr(0, kWayfireHeader)), json.size());
  EXPECT_NE(json.find(R"("method": "window-rules/get_cursor_position")"), std::string_view::npos);
  EXPECT_EQ(wayfire_message_length(std::string_view(wayfire_message("{}")).substr(0, kWayfireHeader)), 2U);
  EXPECT_EQ(wayfire_message_length(std::string("\xff\xff\xff\x7f", 4)), std::nullopt);  // over Wayfire's 1 MiB
  EXPECT_EQ(wayfire_message_length("abc"), std::nullopt);
}

TEST(WayfireAnswers, TheCursorPositionReplyGivesLogicalPixels) {
  EXPECT_EQ(parse_wayfire_cursor_position(R"({"result": "ok", "pos": {"x": 640.0, "y": 360.0}})"), (Vec2{640, 360}));
  EXPECT_EQ(parse_wayfire_cursor_position(R"({"pos":{"y":-12.25,"x":1919.75},"result":"ok"})"),
            (Vec2{1919.75, -12.25}));
  EXPECT_EQ(parse_wayfire_cursor_position(R"({"pos": {"x": 3, "y": 4}})"), (Vec2{3, 4}));
  for (const char* bad :
       {R"({"error": "No such method found!"})", R"({"result": "ok", "pos": {"x": 1}})",
        R"({"result": "ok", "pos": [1, 2]})", R"({"result": "ok", "pos": {"x": "left", "y": 2}})",
        R"({"result": "ok", "pos": {"x": {"a": 1}, "y": 2}})", R"({"result": "ok", "pos": {"x": .inf, "y": 2}})",
        R"({"result": "ok", "pos": {"x": 1, "y": 2})",  // cut short
        "[]", "", "null", "\x01\x02"}) {
    EXPECT_EQ(parse_wayfire_cursor_position(bad), std::nullopt) << bad;
  }
}

// A one-connection server on a unix socket: `serve` gets the accepted connection, on its own thread.
class FakeServer {
 public:
  FakeServer(const std::string& path, std::function<void(int)> serve) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    listener_ = UniqueFd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
    if (!listener_ || ::bind(listener_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0 ||
        ::listen(listener_.get(), 4) < 0) {
      throw std::runtime_error("fake server at " + path + ": " + std::strerror(errno));
    }
    thread_ = std::thread([this, serve = std::move(serve)] {
      pollfd p{listener_.get(), POLLIN, 0};
      if (::poll(&p, 1, 5000) <= 0) return;
      const UniqueFd client(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC));
      if (client) serve(client.get());
    });
  }
  ~FakeServer() { thread_.join(); }
  FakeServer(const FakeServer&) = delete;
  FakeServer& operator=(const FakeServer&) = delete;

 private:
  UniqueFd listener_;
  std::thread thread_;
};

// Reads until `want` bytes have come, the peer closes or a second passes.
std::string read_bytes(int fd, std::size_t want) {
  std::string data;
  char buffer[512];
  while (data.size() < want) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 1000) <= 0) break;
    const ssize_t n = ::recv(fd, buffer, std::min(sizeof buffer, want - data.size()), 0);
    if (n <= 0) break;
    data.append(buffer, static_cast<std::size_t>(n));
  }
  return data;
}

void write_all(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n <= 0) return;
    data.remove_prefix(static_cast<std::size_t>(n));
  }
}

TEST(HyprlandCursor, AsksCursorposAndReadsTheAnswerUntilTheConnectionEnds) {
  ScratchDir dir("hypr");
  const std::string path = (dir / ".socket.sock").string();
  std::string asked;
  {
    FakeServer hyprland(path, [&](int fd) {
      asked = read_bytes(fd, std::strlen("cursorpos"));
      write_all(fd, "1024, ");  // in two pieces, as a socket may deliver it
      std::this_thread::sleep_for(20ms);
      write_all(fd, "-37");
    });
    HyprlandCursor cursor(path, 2s);
    EXPECT_EQ(cursor.position(), (Vec2{1024.5, -36.5}));
  }
  EXPECT_EQ(asked, "cursorpos");
}

TEST(HyprlandCursor, GivesNothingForAnErrorASilentServerOrNoServer) {
  ScratchDir dir("hypr");
  const std::string path = (dir / ".socket.sock").string();
  {
    FakeServer hyprland(path, [](int fd) {
      read_bytes(fd, std::strlen("cursorpos"));
      write_all(fd, "unknown request");
    });
    EXPECT_EQ(HyprlandCursor(path, 2s).position(), std::nullopt);
  }
  std::filesystem::remove(path);
  {
    FakeServer silent(path, [](int fd) { read_bytes(fd, 1000); });  // reads and waits: never answers
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(HyprlandCursor(path, 100ms).position(), std::nullopt);
    EXPECT_LT(std::chrono::steady_clock::now() - start, 900ms);  // gave up at its deadline, not the server's
  }
  std::filesystem::remove(path);
  EXPECT_EQ(HyprlandCursor(path, 100ms).position(), std::nullopt);
}

TEST(WayfireCursor, SendsAFramedRequestAndReadsTheFramedReply) {
  ScratchDir dir("wayfire");
  const std::string path = (dir / "wayfire-ipc.sock").string();
  std::string method_line;
  {
    FakeServer wayfire(path, [&](int fd) {
      const std::string header = read_bytes(fd, kWayfireHeader);
      const std::optional<std::size_t> length = wayfire_message_length(header);
      if (!length) return;
      method_line = read_bytes(fd, *length);
      const std::string reply = wayfire_message(R"({"pos": {"x": 812.4, "y": 95.0}, "result": "ok"})");
      write_all(fd, std::string_view(reply).substr(0, 2));  // the header in two pieces
      std::this_thread::sleep_for(20ms);
      write_all(fd, std::string_view(reply).substr(2));
    });
    WayfireCursor cursor(path, 2s);
    EXPECT_EQ(cursor.position(), (Vec2{812.4, 95.0}));
  }
  EXPECT_NE(method_line.find("window-rules/get_cursor_position"), std::string::npos) << method_line;
}

TEST(WayfireCursor, GivesNothingWhenTheMethodIsMissingOrTheReplyIsCut) {
  ScratchDir dir("wayfire");
  const std::string path = (dir / "wayfire-ipc.sock").string();
  const auto serve = [](std::string reply) {
    return [reply](int fd) {
      const std::optional<std::size_t> length = wayfire_message_length(read_bytes(fd, kWayfireHeader));
      if (length) read_bytes(fd, *length);
      write_all(fd, reply);
    };
  };
  {  // Wayfire without the ipc-rules plugin
    FakeServer wayfire(path, serve(wayfire_message(R"({"error": "No such method found!"})")));
    EXPECT_EQ(WayfireCursor(path, 2s).position(), std::nullopt);
  }
  std::filesystem::remove(path);
  {  // the connection ends in the middle of the reply
    FakeServer wayfire(path, serve(wayfire_message(R"({"result": "ok", "pos": {"x": 1, "y": 2}})").substr(0, 20)));
    EXPECT_EQ(WayfireCursor(path, 2s).position(), std::nullopt);
  }
}

TEST(CursorSourceFromEnvironment, FindsHyprlandsSocketOrWayfiresOrNone) {
  ScratchDir dir("runtime");
  ScopedEnv runtime("XDG_RUNTIME_DIR", dir.path().string());
  ScopedEnv wayfire("WAYFIRE_SOCKET", "");
  {
    ScopedEnv signature("HYPRLAND_INSTANCE_SIGNATURE", "sig_1");
    std::string unmet;
    EXPECT_EQ(cursor_source_from_environment(&unmet), nullptr);  // no socket there: not Hyprland after all
    EXPECT_EQ(unmet, "HYPRLAND_INSTANCE_SIGNATURE is set, but no Hyprland socket is there (" +
                         (dir / "hypr/sig_1/.socket.sock").string() + ", /tmp/hypr/sig_1/.socket.sock)");
    std::filesystem::create_directories(dir / "hypr/sig_1");
    const std::string path = (dir / "hypr/sig_1/.socket.sock").string();
    FakeServer hyprland(path, [](int fd) {
      read_bytes(fd, std::strlen("cursorpos"));
      write_all(fd, "5, 6");
    });
    const std::unique_ptr<CursorSource> source = cursor_source_from_environment();
    ASSERT_NE(source, nullptr);
    EXPECT_EQ(source->name(), "hyprland");
    EXPECT_EQ(source->socket(), path);
    EXPECT_EQ(source->position(), (Vec2{5.5, 6.5}));
  }
  ScopedEnv signature("HYPRLAND_INSTANCE_SIGNATURE", "");
  std::string unmet = "left over";
  EXPECT_EQ(cursor_source_from_environment(&unmet), nullptr);
  EXPECT_EQ(unmet, "");  // nothing named: nothing to say
  // A variable that names no socket (left in the user manager by a Wayfire session that has ended): none, so that
  // another source (KWin) is tried.
  const std::string wayfire_path = (dir / "wayfire-wayland-1-.socket").string();
  ScopedEnv wayfire_set("WAYFIRE_SOCKET", wayfire_path);
  EXPECT_EQ(cursor_source_from_environment(&unmet), nullptr);
  EXPECT_EQ(unmet, "WAYFIRE_SOCKET names no socket (" + wayfire_path + ")");
  FakeServer wayfire_server(wayfire_path, [](int) {});  // says nothing: position() has no answer
  const std::unique_ptr<CursorSource> source = cursor_source_from_environment();
  ASSERT_NE(source, nullptr);
  EXPECT_EQ(source->name(), "wayfire");
  EXPECT_EQ(source->socket(), wayfire_path);
  EXPECT_EQ(source->position(), std::nullopt);
}

}  // namespace
}  // namespace ph::session
