// The control socket under a flood: the time one wake-up of the daemon's event loop spends on a connection that
// sends requests as fast as it can. The event loop holds the state lock that the mice's readers wait for meanwhile,
// so this is how long a local client can hold up the cursor at a time. docs/SERVICE.md, "The control socket".
#include <benchmark/benchmark.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/unique_fd.hpp"
#include "daemon/control_access.hpp"
#include "daemon/control_server.hpp"
#include "daemon/log.hpp"

namespace ph {
namespace {

class EveryoneLocal final : public SessionDirectory {
 public:
  bool has_active_local_session(uid_t) const override { return true; }
};

// What the daemon answers with, at a fixed cost: the flood's own handling is what is timed.
class FixedHandler final : public ControlHandler {
 public:
  control::Status status() const override {
    control::Status s;
    s.mice = 1;
    s.regions = 3;
    s.desktop = {0, 0, 1920, 1080};
    s.cursor = {960.5, 540.5};
    s.scene = "/etc/pseudohaptic/scene.toml";
    return s;
  }
  Vec2 cursor() const override { return {960.5, 540.5}; }
  void position(Vec2, bool) override {}
  void layout(Rect, const std::vector<Rect>&) override {}
  void layout_source_gone() override {}
  void helper_changed(bool) override {}
  void passthrough(bool) override {}
};

// A server on its own epoll, with one client connected and accepted.
class Flooded {
 public:
  Flooded() {
    char folder[] = "/tmp/ph-bench-control-XXXXXX";
    if (::mkdtemp(folder) == nullptr) throw std::runtime_error("mkdtemp failed");
    folder_ = folder;
    server_ = std::make_unique<ControlServer>(socket_path(), epoll_.get(), sessions_, log_);
    client_ = UniqueFd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, socket_path().c_str(), sizeof address.sun_path - 1);
    if (::connect(client_.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) < 0)
      throw std::runtime_error("connect failed");
    serve();  // the accept
  }
  ~Flooded() {
    server_.reset();
    std::error_code ignored;
    std::filesystem::remove_all(folder_, ignored);
  }
  Flooded(const Flooded&) = delete;
  Flooded& operator=(const Flooded&) = delete;

  void send(const std::string& text) {
    if (::send(client_.get(), text.data(), text.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(text.size()))
      throw std::runtime_error("send failed");
  }
  // Reads what the server answered, so that its answers never fill the socket.
  void discard_answers() {
    std::array<char, 65536> sink{};
    while (::recv(client_.get(), sink.data(), sink.size(), MSG_DONTWAIT) > 0) {
    }
  }
  // The descriptors that woke the loop, as the daemon's epoll_wait gives them.
  int wait(std::array<epoll_event, 4>& events, int timeout_ms = 1000) {
    return ::epoll_wait(epoll_.get(), events.data(), static_cast<int>(events.size()), timeout_ms);
  }
  void handle(const std::array<epoll_event, 4>& events, int n) {
    for (int i = 0; i < n; ++i) server_->on_readable(events[static_cast<std::size_t>(i)].data.fd, handler_);
  }
  void serve() {
    std::array<epoll_event, 4> events{};
    handle(events, wait(events));
  }

 private:
  std::string socket_path() const { return folder_ + "/control"; }

  std::string folder_;
  UniqueFd epoll_{::epoll_create1(EPOLL_CLOEXEC)};
  EveryoneLocal sessions_;
  Logger log_{false, false, std::fopen("/dev/null", "w")};
  FixedHandler handler_;
  std::unique_ptr<ControlServer> server_;
  UniqueFd client_;
};

// One wake-up of the loop on a connection that has sent 4 KiB of `line`s at once: the daemon reads what it reads
// at a time, answers it, and goes back to the loop (and the mice) with the rest waiting.
void flood(benchmark::State& state, const std::string& line) {
  Flooded f;
  std::string text;
  while (text.size() + line.size() <= 4096) text += line;
  std::array<epoll_event, 4> events{};
  for (auto _ : state) {
    state.PauseTiming();
    f.discard_answers();
    f.send(text);
    const int n = f.wait(events);
    state.ResumeTiming();
    f.handle(events, n);
    state.PauseTiming();
    for (int n_left = f.wait(events, 0); n_left > 0; n_left = f.wait(events, 0)) {  // the rest, untimed
      f.discard_answers();
      f.handle(events, n_left);
    }
    state.ResumeTiming();
  }
}

BENCHMARK_CAPTURE(flood, empty_lines, std::string("\n"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(flood, status, std::string("status\n"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(flood, cursor, std::string("cursor\n"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(flood, layouts, std::string("layout 0 0 1920 1080\n"))->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace ph

BENCHMARK_MAIN();
