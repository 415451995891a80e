// The daemon's control socket over a real Unix socket: requests reach the handler, the helper gets its
// queries, a refused peer gets a clear error, and a client that misbehaves is dropped.
#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "control/client.hpp"
#include "daemon/control_server.hpp"
#include "tests/as_nobody.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

using namespace std::chrono_literals;

class FakeSessions final : public SessionDirectory {
 public:
  explicit FakeSessions(uid_t active) : active_(active) {}
  bool has_active_local_session(uid_t uid) const override { return uid == active_; }

 private:
  uid_t active_;
};

class RecordingHandler final : public ControlHandler {
 public:
  control::Status status() const override {
    control::Status s;
    s.mice = 1;
    s.regions = 3;
    s.desktop = {0, 0, 1920, 1080};
    s.cursor = at_;
    s.scene = "default";
    return s;
  }
  Vec2 cursor() const override { return at_; }
  void position(Vec2 p, bool from_helper) override {
    std::lock_guard lock(mutex_);
    at_ = p;
    helper_positions_ += from_helper;
  }
  void layout(Rect d, const std::vector<Rect>& outputs) override {
    std::lock_guard lock(mutex_);
    desktop_ = d;
    outputs_ = outputs;
    ++layouts_;
  }
  void layout_source_gone() override { layout_sources_gone_ += 1; }
  void helper_changed(bool present) override { helper_present_ = present; }
  void passthrough(bool on) override { passthrough_ = on; }
  std::atomic<bool> passthrough_{false};

  Vec2 at() {
    std::lock_guard lock(mutex_);
    return at_;
  }
  Rect desktop() {
    std::lock_guard lock(mutex_);
    return desktop_;
  }
  std::vector<Rect> outputs() {
    std::lock_guard lock(mutex_);
    return outputs_;
  }
  int helper_positions() {
    std::lock_guard lock(mutex_);
    return helper_positions_;
  }
  int layouts() {
    std::lock_guard lock(mutex_);
    return layouts_;
  }
  std::atomic<bool> helper_present_{false};
  std::atomic<int> layout_sources_gone_{0};

 private:
  std::mutex mutex_;
  Vec2 at_{960.5, 540.5};
  Rect desktop_;
  std::vector<Rect> outputs_;
  int helper_positions_ = 0;
  int layouts_ = 0;
};

// The server on its own event loop, as the daemon runs it.
class ServerLoop {
 public:
  ServerLoop(const std::string& path, const SessionDirectory& sessions, std::FILE* log = nullptr_file())
      : epoll_(::epoll_create1(EPOLL_CLOEXEC)), log_(false, false, log) {
    server_ = std::make_unique<ControlServer>(path, epoll_.get(), sessions, log_);
    thread_ = std::thread([this] { loop(); });
  }
  ~ServerLoop() {
    stop_ = true;
    thread_.join();
  }
  void query_helper() { queries_ += 1; }
  RecordingHandler handler;

 private:
  static std::FILE* nullptr_file() {
    static std::FILE* sink = std::fopen("/dev/null", "w");
    return sink;
  }
  void loop() {
    epoll_event events[8];
    while (!stop_) {
      const int n = ::epoll_wait(epoll_.get(), events, 8, 20);
      for (int i = 0; i < n; ++i) server_->on_readable(events[i].data.fd, handler);
      if (queries_ > 0) {
        server_->query_helper();
        queries_ -= 1;
      }
    }
  }
  UniqueFd epoll_;
  Logger log_;
  std::unique_ptr<ControlServer> server_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> queries_{0};
};

TEST(ControlServer, AnswersEveryRequestAndQueriesTheHelper) {
  const ScratchDir dir("control");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::others_write,
            std::filesystem::perms::others_write);  // anyone may connect; the credentials decide

  control::Client tool(path);
  control::Reply status = tool.request("status");
  ASSERT_TRUE(status.ok) << status.text;
  const auto parsed = control::parse_status(status.text);
  ASSERT_TRUE(parsed.has_value());
  EXPECT_EQ(parsed->regions, 3);
  EXPECT_FALSE(parsed->helper);

  EXPECT_TRUE(tool.request("position 100.25 200.5").ok);
  EXPECT_EQ(server.handler.at(), (Vec2{100.25, 200.5}));
  EXPECT_EQ(server.handler.helper_positions(), 0);  // a user's --set, not a helper's report
  EXPECT_EQ(control::parse_cursor(tool.request("cursor").text), (Vec2{100.25, 200.5}));
  const control::Reply bad = tool.request("position x y");
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.text.find("finite"), std::string::npos);
  EXPECT_TRUE(tool.request("status").ok);  // a malformed line does not close the connection

  {
    control::Client helper(path);
    ASSERT_TRUE(helper.request("helper test").ok);
    EXPECT_TRUE(server.handler.helper_present_);
    ASSERT_TRUE(helper.request("layout -1920 0 3840 1440 -1920 0 1920 1080 0 0 1920 1440").ok);
    EXPECT_EQ(server.handler.desktop(), (Rect{-1920, 0, 3840, 1440}));
    EXPECT_EQ(server.handler.outputs(), (std::vector<Rect>{{-1920, 0, 1920, 1080}, {0, 0, 1920, 1440}}));
    ASSERT_TRUE(helper.request("layout -1920 0 3840 1080").ok);
    EXPECT_EQ(server.handler.desktop(), (Rect{-1920, 0, 3840, 1080}));
    EXPECT_TRUE(server.handler.outputs().empty());
    EXPECT_TRUE(control::parse_status(tool.request("status").text)->helper);
    server.query_helper();
    EXPECT_EQ(helper.read_line(2s), "query");
    ASSERT_TRUE(helper.request("position 5 6").ok);
    EXPECT_EQ(server.handler.helper_positions(), 1);
    ASSERT_TRUE(helper.request("passthrough on").ok);
    EXPECT_TRUE(server.handler.passthrough_);
    ASSERT_TRUE(helper.request("passthrough off").ok);
    EXPECT_FALSE(server.handler.passthrough_);
  }
  for (int i = 0; i < 100 && server.handler.helper_present_; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_FALSE(server.handler.helper_present_);  // the helper's connection closed
}

// The daemon keeps a session helper's layout over the connected displays only while the connection that sent it
// is open: when the connection whose layout is the latest closes, it is given the layout of the latest one still
// open, and told that the layout's source has gone where none is.
TEST(ControlServer, SaysWhenTheConnectionThatGaveTheLayoutCloses) {
  const ScratchDir dir("control");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  auto wait_for_gone = [&](int count) {
    for (int i = 0; i < 200 && server.handler.layout_sources_gone_ < count; ++i) std::this_thread::sleep_for(10ms);
    return server.handler.layout_sources_gone_.load();
  };
  {
    control::Client tool(path);  // a client that sends no layout
    EXPECT_TRUE(tool.request("status").ok);
  }
  {
    control::Client layout_only(path);  // as the helper on a Wayland desktop that gives no pointer
    ASSERT_TRUE(layout_only.request("layout 0 0 1600 900").ok);
    control::Client tool(path);
    EXPECT_TRUE(tool.request("status").ok);
  }
  EXPECT_EQ(wait_for_gone(1), 1);
  {
    control::Client first(path);
    ASSERT_TRUE(first.request("helper test").ok);
    ASSERT_TRUE(first.request("layout 0 0 1280 800").ok);
    {
      control::Client second(path);  // another session's helper: its layout is the latest
      ASSERT_TRUE(second.request("layout 0 0 1920 1080").ok);
      EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 1920, 1080}));
    }
    // The older layout's connection is still open: its layout is the one again, and nothing is gone.
    for (int i = 0; i < 200 && server.handler.desktop() != Rect{0, 0, 1280, 800}; ++i)
      std::this_thread::sleep_for(10ms);
    EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 1280, 800}));
    EXPECT_EQ(server.handler.layout_sources_gone_, 1);
  }
  EXPECT_EQ(wait_for_gone(2), 2);
}

// Pass-through lasts while the connection that asked for it is open: a session that ends with a game in focus
// must not leave every later session without textures. Where another open connection asked before, its wish holds.
TEST(ControlServer, PassThroughEndsWithTheConnectionThatAskedForIt) {
  const ScratchDir dir("control");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  const auto wait_for = [&](bool on) {
    for (int i = 0; i < 200 && server.handler.passthrough_ != on; ++i) std::this_thread::sleep_for(10ms);
    return server.handler.passthrough_.load();
  };
  {
    control::Client helper(path);
    ASSERT_TRUE(helper.request("helper test").ok);
    ASSERT_TRUE(helper.request("passthrough on").ok);
    EXPECT_TRUE(server.handler.passthrough_);
  }
  EXPECT_FALSE(wait_for(false));  // the session ended with the game in focus
  control::Client first(path);
  ASSERT_TRUE(first.request("passthrough on").ok);
  {
    control::Client second(path);
    ASSERT_TRUE(second.request("passthrough off").ok);
    EXPECT_FALSE(server.handler.passthrough_);
  }
  EXPECT_TRUE(wait_for(true));  // the first connection, still open, asked for it
  {
    control::Client tool(path);  // a connection that never asked changes nothing when it closes
    EXPECT_TRUE(tool.request("status").ok);
  }
  std::this_thread::sleep_for(50ms);
  ASSERT_TRUE(first.request("status").ok);  // the server has gone round its loop since the close
  EXPECT_TRUE(server.handler.passthrough_);
}

// With two sessions' helpers connected (a fast user switch), the latest is the helper; when it goes, the one before
// it is the helper again, with its layout, and is asked where the cursor is.
TEST(ControlServer, AnEarlierHelperTakesOverWhenTheLatestGoes) {
  const ScratchDir dir("control");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  control::Client first(path);
  ASSERT_TRUE(first.request("helper x11").ok);
  ASSERT_TRUE(first.request("layout 0 0 1280 800").ok);
  {
    control::Client second(path);
    ASSERT_TRUE(second.request("helper x11").ok);
    ASSERT_TRUE(second.request("layout 0 0 3840 1080").ok);
    EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 3840, 1080}));
    ASSERT_TRUE(second.request("position 7 8").ok);
    EXPECT_EQ(server.handler.helper_positions(), 1);
    ASSERT_TRUE(first.request("position 9 10").ok);  // no longer the helper: a user's --set
    EXPECT_EQ(server.handler.helper_positions(), 1);
  }
  EXPECT_EQ(first.read_line(2s), "query");  // the helper again: where is the cursor on its desktop?
  for (int i = 0; i < 200 && server.handler.desktop() != Rect{0, 0, 1280, 800}; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 1280, 800}));
  EXPECT_TRUE(server.handler.helper_present_);
  EXPECT_EQ(server.handler.layout_sources_gone_, 0);
  control::Client tool(path);
  EXPECT_TRUE(control::parse_status(tool.request("status").text)->helper);
  ASSERT_TRUE(first.request("position 11 12").ok);
  EXPECT_EQ(server.handler.helper_positions(), 2);
}

// A daemon started by hand has no RuntimeDirectory= to make /run/pseudohaptic: the server makes the socket's own
// folder, and only that one (a path with a missing folder above it still fails, naming the path). 0755 under any
// umask (077 here): every user's helper must reach the socket.
TEST(ControlServer, MakesTheSocketsOwnFolder) {
  const ScratchDir dir("control");
  const std::string path = (dir.path() / "pseudohaptic" / "control").string();
  const FakeSessions sessions(::getuid());
  {
    const mode_t umask_before = ::umask(077);
    ServerLoop server(path, sessions);
    ::umask(umask_before);
    EXPECT_EQ(std::filesystem::status(dir.path() / "pseudohaptic").permissions(),
              std::filesystem::perms::owner_all | std::filesystem::perms::group_read |
                  std::filesystem::perms::group_exec | std::filesystem::perms::others_read |
                  std::filesystem::perms::others_exec);
    control::Client tool(path);
    EXPECT_TRUE(tool.request("status").ok);
  }
  const std::string deeper = (dir.path() / "a" / "b" / "control").string();
  const UniqueFd epoll(::epoll_create1(EPOLL_CLOEXEC));
  const Logger log(false, false, std::fopen("/dev/null", "w"));
  try {
    ControlServer server(deeper, epoll.get(), sessions, log);
    ADD_FAILURE() << "bound under a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(deeper + ": cannot bind: No such file or directory"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "a"));
}

// A file or a folder at the path is not taken for another daemon's socket ("Address already in use").
TEST(ControlServer, AFileAtThePathIsSaidToBeNoSocket) {
  const ScratchDir dir("control-file");
  const std::string path = (dir.path() / "control").string();
  std::ofstream(path) << "not a socket\n";
  const FakeSessions sessions(::getuid());
  const UniqueFd epoll(::epoll_create1(EPOLL_CLOEXEC));
  const Logger log(false, false, std::fopen("/dev/null", "w"));
  try {
    ControlServer server(path, epoll.get(), sessions, log);
    ADD_FAILURE() << "a server on a file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("a file is there, not a socket"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_file_text(path), "not a socket\n");  // left as it was
}

// A second daemon started beside a running one (`sudo pseudohapticd` while the service runs) must not take the
// running one's socket: it used to unlink it as stale, bind its own, and remove that when it ended, leaving the
// running daemon unreachable. A socket file whose daemon is gone is still replaced.
TEST(ControlServer, LeavesALiveSocketAloneAndReplacesAStaleOne) {
  const ScratchDir dir("control");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  {
    ServerLoop running(path, sessions);
    const UniqueFd epoll(::epoll_create1(EPOLL_CLOEXEC));
    const Logger log(false, false, std::fopen("/dev/null", "w"));
    try {
      ControlServer second(path, epoll.get(), sessions, log);
      ADD_FAILURE() << "a second server took the running one's socket";
    } catch (const ControlSocketInUse& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("another pseudohapticd"), std::string::npos) << e.what();
    }
    control::Client tool(path);  // the running one still answers on its own socket
    EXPECT_TRUE(tool.request("status").ok);
  }
  // A socket file left behind: bound, never unlinked, its listener closed.
  {
    const UniqueFd gone(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
    ASSERT_EQ(::bind(gone.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
    ASSERT_EQ(::listen(gone.get(), 1), 0);
  }
  ASSERT_TRUE(std::filesystem::is_socket(path));
  ServerLoop next(path, sessions);
  control::Client tool(path);
  EXPECT_TRUE(tool.request("status").ok);
}

// Out of file descriptors, a waiting connection kept the listener readable and accept failing (EMFILE): the loop
// spun, and the client waited for ever. It is now closed at once, and once descriptors are free again, served.
TEST(ControlServer, OutOfDescriptorsAConnectionIsClosedNotLeftWaiting) {
  const ScratchDir dir("control-emfile");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  rlimit before{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &before), 0);
  // The limit put back however the block below ends (after the filler is closed: declared first, destroyed last).
  struct RestoreLimit {
    rlimit limit;
    ~RestoreLimit() { ::setrlimit(RLIMIT_NOFILE, &limit); }
  } restore{before};
  // Under UndefinedBehaviorSanitizer the first check of a virtual call's type reads memory through a pipe, which fails
  // out of descriptors and is reported as a call on an invalid object: the server's warning below is logged out of
  // descriptors, so the logger's types are checked here first, while descriptors are free.
  if (std::FILE* devnull = std::fopen("/dev/null", "w")) {
    Logger(false, false, devnull).warning("control socket: out of file descriptors (the test's warm-up)");
    std::fclose(devnull);
  }
  std::vector<UniqueFd> filler;
  UniqueFd client;
  {
    // A limit a few above what is open, then every descriptor but one taken: the client's socket gets it.
    rlimit low = before;
    low.rlim_cur = 0;
    for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
      low.rlim_cur = std::max<rlim_t>(low.rlim_cur, std::stoul(entry.path().filename().string()) + 1);
    }
    low.rlim_cur += 8;
    ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
    while (true) {
      UniqueFd fd(::open("/dev/null", O_RDONLY | O_CLOEXEC));
      if (!fd) break;
      filler.push_back(std::move(fd));
    }
    filler.pop_back();
    client = UniqueFd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
    ASSERT_TRUE(client);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
    ASSERT_EQ(::connect(client.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
    pollfd p{client.get(), POLLIN, 0};
    const int ready = ::poll(&p, 1, 2000);
    char byte = 0;
    const ssize_t n = ready == 1 ? ::recv(client.get(), &byte, 1, MSG_DONTWAIT) : -1;
    // Still out of descriptors, with nothing waiting: the server idles, not spins (accept says EMFILE then too). The
    // process's CPU time over 200 ms of this thread's sleep is the server's: a spinning loop takes most of it.
    const auto cpu_ms = [] {
      rusage usage{};
      ::getrusage(RUSAGE_SELF, &usage);
      return (usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) * 1000.0 +
             (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1000.0;
    };
    const double cpu_before = cpu_ms();
    std::this_thread::sleep_for(200ms);
    const double busy_ms = cpu_ms() - cpu_before;
    filler.clear();
    client = UniqueFd();
    ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &before), 0);
    EXPECT_EQ(ready, 1) << "the connection was left waiting";
    EXPECT_EQ(n, 0) << "the connection was not closed";
    EXPECT_LT(busy_ms, 50.0) << "the server spun while out of descriptors";
  }
  control::Client tool(path);
  EXPECT_TRUE(tool.request("status").ok);
}

TEST(ControlServer, DropsAClientWhoseLineNeverEnds) {
  const ScratchDir dir("control-flood");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  control::Client flood(path);
  const std::string endless(3 * control::kMaxLine, 'x');  // no newline
  ASSERT_EQ(::send(flood.fd(), endless.data(), endless.size(), MSG_NOSIGNAL), static_cast<ssize_t>(endless.size()));
  const auto line = flood.read_line(2s);
  ASSERT_TRUE(line.has_value());
  EXPECT_EQ(*line, "error line too long");
  EXPECT_THROW(flood.read_line(2s), control::ControlError);  // and the daemon hung up
  control::Client next(path);                                // others are still served
  EXPECT_TRUE(next.request("cursor").ok);
}

// The requests read whole before a line too long are answered and applied before the connection is closed on it.
TEST(ControlServer, RequestsBeforeALineTooLongAreStillAnswered) {
  const ScratchDir dir("control-long-line");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  control::Client client(path);
  const std::string text = "position 3 4\ncursor\n" + std::string(control::kMaxLine + 100, 'x') + "\nposition 1 2\n";
  ASSERT_EQ(::send(client.fd(), text.data(), text.size(), MSG_NOSIGNAL), static_cast<ssize_t>(text.size()));
  std::vector<std::string> replies;
  try {
    while (auto line = client.read_line(2s)) replies.push_back(*line);
  } catch (const control::ControlError&) {  // the daemon hung up
  }
  ASSERT_EQ(replies.size(), 3U) << fmt::format("{}", fmt::join(replies, " | "));
  EXPECT_EQ(replies[0], "ok");
  EXPECT_TRUE(replies[1].starts_with("ok ")) << replies[1];  // the cursor
  EXPECT_EQ(replies[2], "error line too long");
  EXPECT_EQ(server.handler.at(), (Vec2{3, 4}));  // the one before the long line applied, the one after it not
}

// A connection that says `helper` again and again is one helper, logged once: a loop of them must not fill the journal.
TEST(ControlServer, AHelperSaidAgainIsLoggedOnce) {
  const ScratchDir dir("control-helper-again");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  const std::string log_path = (dir.path() / "log").string();
  std::FILE* log = std::fopen(log_path.c_str(), "w");
  ASSERT_NE(log, nullptr);
  {
    ServerLoop server(path, sessions, log);
    control::Client helper(path);
    for (int i = 0; i < 20; ++i) ASSERT_TRUE(helper.request("helper x11").ok);
    control::Client other(path);  // another connection saying it: a new helper, said
    ASSERT_TRUE(other.request("helper wayland").ok);
  }
  std::fclose(log);
  const std::string said = read_file_text(log_path);
  std::size_t count = 0;
  for (std::size_t at = said.find("session helper '"); at != std::string::npos;
       at = said.find("session helper '", at + 1))
    ++count;
  EXPECT_EQ(count, 2U) << said;
}

// A burst of layouts (a helper's, or anyone's the access rule lets in) would lay the scene out again for each on the
// event loop: of a run sent at once only the last is applied, though the daemon reads it in several pieces, and what
// follows a layout sees it applied.
TEST(ControlServer, OfARunOfLayoutsOnlyTheLastIsApplied) {
  const ScratchDir dir("control-layouts");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  control::Client client(path);
  std::string burst;
  for (int i = 0; i < 200; ++i) burst += fmt::format("layout 0 0 {} 1080\n", 1920 + (i % 2) * 700);
  burst += "cursor\nlayout 0 0 1234 567\n";
  ASSERT_GT(burst.size(), 4096U);  // more than any one read
  ASSERT_EQ(::send(client.fd(), burst.data(), burst.size(), MSG_NOSIGNAL), static_cast<ssize_t>(burst.size()));
  for (int i = 0; i < 202; ++i) {
    const std::optional<std::string> reply = client.read_line(2s);
    ASSERT_TRUE(reply.has_value()) << "reply " << i;
    EXPECT_TRUE(reply->starts_with("ok")) << *reply;
  }
  EXPECT_EQ(server.handler.layouts(), 2);  // the run's last, before `cursor`; then the one after it
  EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 1234, 567}));
  // One at a time, each is applied before its answer.
  ASSERT_TRUE(client.request("layout 0 0 800 600").ok);
  EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 800, 600}));
  // A run ending a read is applied before the request that follows it in the next one.
  std::string run;
  while (run.size() < 3000) run += "layout 0 0 640 480\n";
  run += "position 5 5\nstatus\n";
  ASSERT_EQ(::send(client.fd(), run.data(), run.size(), MSG_NOSIGNAL), static_cast<ssize_t>(run.size()));
  bool status_read = false;  // the answers up to the status, which is the last
  for (int i = 0; i < 1000 && !status_read; ++i)
    status_read = client.read_line(2s).value_or("").starts_with("ok mode=");
  ASSERT_TRUE(status_read);
  EXPECT_EQ(server.handler.desktop(), (Rect{0, 0, 640, 480}));
  EXPECT_EQ(server.handler.layouts(), 4);
}

// A layout that ended one read of a connection, more of its burst waiting, is applied before what follows it in the
// next read: unless another connection's layout came between, which is then the latest and stays.
TEST(ControlServer, ALayoutLeftForTheNextReadGivesWayToALaterOne) {
  const ScratchDir dir("control-deferred-layout");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  const UniqueFd epoll(::epoll_create1(EPOLL_CLOEXEC));
  std::FILE* null = std::fopen("/dev/null", "w");
  ASSERT_NE(null, nullptr);
  const Logger log(false, false, null);
  RecordingHandler handler;
  {
    ControlServer server(path, epoll.get(), sessions, log);
    std::array<epoll_event, 8> events{};
    const auto wait = [&] { return ::epoll_wait(epoll.get(), events.data(), static_cast<int>(events.size()), 1000); };
    control::Client a(path);
    ASSERT_EQ(wait(), 1);
    server.on_readable(events[0].data.fd, handler);  // A accepted
    control::Client b(path);
    ASSERT_EQ(wait(), 1);
    server.on_readable(events[0].data.fd, handler);  // B accepted
    // Exactly one read's worth of layouts (8 lines of 22 bytes, 16 of 21: 512), then a request.
    std::string burst;
    for (int i = 0; i < 8; ++i) burst += "layout 0 0 1111 11111\n";
    for (int i = 0; i < 16; ++i) burst += "layout 0 0 1111 1111\n";
    ASSERT_EQ(burst.size(), 512U);
    burst += "cursor\n";
    ASSERT_EQ(::send(a.fd(), burst.data(), burst.size(), MSG_NOSIGNAL), static_cast<ssize_t>(burst.size()));
    ASSERT_EQ(wait(), 1);
    const int a_fd = events[0].data.fd;
    server.on_readable(a_fd, handler);  // the layouts: the last one waits for what follows
    EXPECT_EQ(handler.layouts(), 0);
    const std::string later = "layout 0 0 2222 2222\n";
    ASSERT_EQ(::send(b.fd(), later.data(), later.size(), MSG_NOSIGNAL), static_cast<ssize_t>(later.size()));
    std::this_thread::sleep_for(50ms);
    const int n = wait();
    ASSERT_EQ(n, 2);
    const int b_fd = events[0].data.fd == a_fd ? events[1].data.fd : events[0].data.fd;
    server.on_readable(b_fd, handler);  // B's layout, sent after A's
    EXPECT_EQ(handler.desktop(), (Rect{0, 0, 2222, 2222}));
    server.on_readable(a_fd, handler);  // A's `cursor`
    EXPECT_EQ(handler.desktop(), (Rect{0, 0, 2222, 2222})) << "A's earlier layout was applied over B's";
    EXPECT_EQ(handler.layouts(), 1);
  }
  std::fclose(null);
}

// A burst longer than the daemon reads at once (it reads a little at a time, so that a flood does not hold up the
// mice) is answered whole and in order.
TEST(ControlServer, ABurstLongerThanOneReadIsAnsweredWholeAndInOrder) {
  const ScratchDir dir("control-burst");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  control::Client client(path);
  std::string burst;
  constexpr int kPairs = 1000;
  for (int i = 0; i < kPairs; ++i) burst += fmt::format("position {} 0.5\ncursor\n\n", i);
  ASSERT_GT(burst.size(), 16000U);
  ASSERT_EQ(::send(client.fd(), burst.data(), burst.size(), MSG_NOSIGNAL), static_cast<ssize_t>(burst.size()));
  for (int i = 0; i < kPairs; ++i) {
    ASSERT_EQ(client.read_line(2s), "ok") << i;
    const std::optional<control::Reply> at = control::parse_reply(client.read_line(2s).value_or(""));
    ASSERT_TRUE(at && at->ok) << i;
    ASSERT_EQ(control::parse_cursor(at->text), (Vec2{double(i), 0.5})) << i;
    ASSERT_TRUE(client.read_line(2s).value_or("").starts_with("error")) << i;  // the empty line
  }
  EXPECT_TRUE(client.request("cursor").ok);
}

// `pseudohaptic passthrough` holds pass-through on for as long as it runs, and turns it off when a signal ends it.
TEST(ControlServer, ThePassthroughCommandHoldsItOnWhileItRuns) {
  const ScratchDir dir("control-passthrough-command");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid());
  ServerLoop server(path, sessions);
  const std::string err = (dir.path() / "stderr").string();
  const pid_t tool = ::fork();
  ASSERT_GE(tool, 0);
  if (tool == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(fd, 2);
    ::execl(PH_TOOL_PATH, PH_TOOL_PATH, "passthrough", "--socket", path.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const bool on = [&] {
    for (int i = 0; i < 200 && !server.handler.passthrough_; ++i) std::this_thread::sleep_for(10ms);
    return server.handler.passthrough_.load();
  }();
  EXPECT_TRUE(on) << read_file_text(err);
  std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(server.handler.passthrough_) << "it did not stay on";
  ::kill(tool, SIGTERM);
  int status = -1;
  ::waitpid(tool, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status << ": " << read_file_text(err);
  for (int i = 0; i < 200 && server.handler.passthrough_; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_FALSE(server.handler.passthrough_);
  const std::string said = read_file_text(err);
  EXPECT_NE(said.find("pass-through on"), std::string::npos) << said;
  EXPECT_NE(said.find("pass-through off"), std::string::npos) << said;
}

// Connects `count` times as a refused peer and reads each refusal; returns how many were refused with a reason.
int refused_connections(const std::string& path, int count) {
  return as_nobody([&] {
    int refused = 0;
    for (int i = 0; i < count; ++i) {
      try {
        control::Client client(path);
        refused += client.read_line(2s).value_or("").starts_with("error permission denied");
      } catch (const std::exception&) {
      }
    }
    return refused;
  });
}

// Anyone may connect: a loop of refused connections must not fill the journal.
TEST(ControlServer, AUidsRefusalsAreLoggedOnceInTenSeconds) {
  const ScratchDir dir("control-refusals");
  const std::string path = (dir.path() / "control").string();
  const bool root = ::getuid() == 0;
  const FakeSessions sessions(root ? 12345 : ::getuid() + 1);
  std::FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  {
    ServerLoop server(path, sessions, log);
    EXPECT_EQ(refused_connections(path, 30), 30);  // each one still told why
  }
  std::fflush(log);
  std::rewind(log);
  std::string text(1 << 16, '\0');
  text.resize(std::fread(text.data(), 1, text.size(), log));
  std::fclose(log);
  std::size_t lines = 0;
  for (std::size_t at = text.find("refused pid"); at != std::string::npos; at = text.find("refused pid", at + 1))
    ++lines;
  EXPECT_EQ(lines, 1u) << text;
}

// The server answers a refused peer and closes before it reads the request: the client's send then fails, and what
// it says must still be the daemon's reason, not "Broken pipe".
TEST(ControlServer, ARefusedClientIsToldWhyEvenWhenItsRequestCannotBeSent) {
  const ScratchDir dir("control-refused-request");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(::getuid() == 0 ? 12345 : ::getuid() + 1);
  ServerLoop server(path, sessions);
  const int told = as_nobody([&] {
    try {
      control::Client client(path);
      pollfd hung_up{client.fd(), POLLRDHUP, 0};  // the server has answered and closed
      if (::poll(&hung_up, 1, 2000) != 1) return 2;
      const control::Reply reply = client.request("status");
      return !reply.ok && reply.text.starts_with("permission denied") ? 1 : 3;
    } catch (const std::exception&) {
      return 0;
    }
  });
  EXPECT_EQ(told, 1) << "0: the request threw; 2: the server did not close; 3: another reply";
}

// Sixteen connections that sit idle fill the server; root is still let in, to ask what the daemon does.
TEST(ControlServer, IdleConnectionsDoNotLockOutRoot) {
  if (::getuid() != 0) GTEST_SKIP() << "needs root: the idle connections are another user's";
  const ScratchDir dir("control-full");
  const std::string path = (dir.path() / "control").string();
  const FakeSessions sessions(65534);  // nobody has the active session
  ServerLoop server(path, sessions);
  int ends[2];
  ASSERT_EQ(::pipe(ends), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // nobody, holding 16 connections and then one too many
    ::close(ends[0]);
    char verdict = 'n';
    if (::setgroups(0, nullptr) == 0 && ::setgid(65534) == 0 && ::setuid(65534) == 0) {
      try {
        std::vector<std::unique_ptr<control::Client>> idle;
        for (int i = 0; i < 16; ++i) {
          idle.push_back(std::make_unique<control::Client>(path));
          if (!idle.back()->request("cursor").ok) throw std::runtime_error("not served");
        }
        control::Client extra(path);
        const control::Reply reply = extra.request("cursor");
        verdict = !reply.ok && reply.text == "too many connections" ? 'y' : 'x';
        (void)!::write(ends[1], &verdict, 1);
        ::pause();  // keeps the connections until killed
      } catch (const std::exception&) {
      }
    }
    (void)!::write(ends[1], &verdict, 1);
    ::_exit(0);
  }
  ::close(ends[1]);
  char verdict = '?';
  (void)!::read(ends[0], &verdict, 1);
  EXPECT_EQ(verdict, 'y') << "y: the 17th connection of a user was refused; n: no connections; x: another reply";
  control::Client root(path);
  EXPECT_TRUE(root.request("status").ok);
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  ::close(ends[0]);
}

// A peer that is neither root nor the active local user is told why and disconnected. As root the test
// connects from a child that drops to nobody; as anyone else, the fake logind knows no session for it.
TEST(ControlServer, RefusesAPeerWithoutAnActiveLocalSession) {
  const ScratchDir dir("control-refuse");
  const std::string path = (dir.path() / "control").string();
  const bool root = ::getuid() == 0;
  const FakeSessions sessions(root ? 12345 : ::getuid() + 1);
  ServerLoop server(path, sessions);
  auto try_connect = [&]() -> std::string {
    control::Client client(path);
    const auto line = client.read_line(2s);
    return line.value_or("nothing");
  };
  if (!root) {
    EXPECT_NE(try_connect().find("error permission denied"), std::string::npos);
    return;
  }
  EXPECT_EQ(as_nobody([&] { return try_connect().starts_with("error permission denied: uid 65534") ? 1 : 0; }), 1);
  // Root itself is always let in.
  control::Client root_client(path);
  EXPECT_TRUE(root_client.request("cursor").ok);
}

TEST(ControlAccess, RootAndTheActiveLocalUserOnly) {
  const FakeSessions sessions(1000);
  EXPECT_FALSE(control_refusal(0, sessions).has_value());
  EXPECT_FALSE(control_refusal(1000, sessions).has_value());
  const auto refused = control_refusal(1001, sessions);
  ASSERT_TRUE(refused.has_value());
  EXPECT_NE(refused->find("uid 1001"), std::string::npos);
}

}  // namespace
}  // namespace ph
