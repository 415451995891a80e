// A stand-in KWin on a private session bus, for tests/test_session_kwin.cpp and
// tests/vm/wayland_session_check.cpp: PrivateBus runs a dbus-daemon of the test's own; StandInKWin owns
// org.kde.KWin there, offers /Scripting's loadScript, unloadScript and start and the loaded script's run
// (at /Scripting/Script<id> as KWin 6 does, or /<id> as KWin 5 does), and when the script runs it reads
// the file it was given and calls what the script's callDBus names with positions the test chooses: what
// a KWin running that script would do. Not a real KWin: no JavaScript runs. What it does was checked against
// a real KWin 5.27 (tests/vm/kwin_session_check.cpp): loadScript numbers the first script 0, `run` on
// /Scripting/Script0 fails with UnknownObject and on /0 runs it, and the script's calls carry two int32.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <systemd/sd-bus.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace ph::kwin_stand_in {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct BusCloser {
  void operator()(sd_bus* bus) const { sd_bus_flush_close_unref(bus); }
};
struct MessageCloser {
  void operator()(sd_bus_message* m) const { sd_bus_message_unref(m); }
};
using BusPtr = std::unique_ptr<sd_bus, BusCloser>;
using MessagePtr = std::unique_ptr<sd_bus_message, MessageCloser>;

BusPtr connect_bus(const std::string& address) {
  sd_bus* raw = nullptr;
  if (sd_bus_new(&raw) < 0) return nullptr;
  BusPtr bus(raw);
  if (sd_bus_set_address(raw, address.c_str()) < 0 || sd_bus_set_bus_client(raw, 1) < 0 || sd_bus_start(raw) < 0) {
    return nullptr;
  }
  return bus;
}

std::optional<std::string> find_dbus_daemon() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::filesystem::path candidate = std::filesystem::path(dir) / "dbus-daemon";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return std::nullopt;
}

// A session bus of the test's own: dbus-daemon listening in a scratch directory, stopped at the end.
class PrivateBus {
 public:
  PrivateBus(const std::string& program, const std::filesystem::path& dir) {
    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC) < 0) return;
    const std::string listen = "--address=unix:path=" + (dir / "bus").string();
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(pipe_fds[1], STDOUT_FILENO);
      ::execl(program.c_str(), program.c_str(), "--session", listen.c_str(), "--print-address", "--nofork",
              "--nopidfile", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(pipe_fds[1]);
    // The first line it prints is the address it listens on.
    std::string out;
    char c = 0;
    const auto deadline = Clock::now() + 10s;
    while (Clock::now() < deadline) {
      pollfd p{pipe_fds[0], POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      if (::read(pipe_fds[0], &c, 1) != 1 || c == '\n') break;
      out += c;
    }
    ::close(pipe_fds[0]);
    address_ = out;
  }
  ~PrivateBus() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    ::waitpid(pid_, nullptr, 0);
  }
  PrivateBus(const PrivateBus&) = delete;
  PrivateBus& operator=(const PrivateBus&) = delete;
  const std::string& address() const { return address_; }

 private:
  pid_t pid_ = -1;
  std::string address_;
};

// A position as KWin's engine hands it to the bus: "ii" when whole, "dd" otherwise (and mixed).
struct Sent {
  double x, y;
  std::string types;
};

enum class KWinVersion { five, six };

struct StandInOptions {
  KWinVersion version = KWinVersion::six;
  bool refuse = false;        // loadScript answers with an error, as a KWin that does not take scripts
  std::optional<Sent> first;  // what the script sends as it starts; none: it stays silent
};

// What the stand-in saw.
struct Seen {
  std::vector<std::pair<std::string, std::string>> loaded;  // (file, plugin name)
  std::vector<std::string> unloaded;                        // plugin names, in order
  std::vector<std::string> runs;                            // the object paths `run` was called on
  std::string script;                                       // the file's text when it ran
  std::vector<std::string> calls;                           // "loadScript", "unloadScript", "run", in order
  int replies_ok = 0, replies_error = 0;                    // to the script's calls
  std::string last_error;
};

class StandInKWin {
 public:
  StandInKWin(std::string address, StandInOptions options) : address_(std::move(address)), options_(options) {
    std::promise<bool> ready;
    std::future<bool> started = ready.get_future();
    thread_ = std::thread([this, &ready] { serve(ready); });
    started_ = started.get();
  }
  ~StandInKWin() {
    stop_ = true;
    thread_.join();
  }
  StandInKWin(const StandInKWin&) = delete;
  StandInKWin& operator=(const StandInKWin&) = delete;

  bool started() const { return started_; }
  // Has the running script report `s`, as KWin does on cursorPosChanged.
  void send(Sent s) {
    const std::lock_guard lock(mutex_);
    queue_.push_back(std::move(s));
  }
  Seen seen() const {
    const std::lock_guard lock(mutex_);
    return seen_;
  }

 private:
  // KWin 5.27 numbers the first script it loads 0 (its object: /0); KWin 6 is given another number here.
  int script_id() const { return options_.version == KWinVersion::six ? 7 : 0; }

  void serve(std::promise<bool>& ready) {
    BusPtr bus = connect_bus(address_);
    bus_ = bus.get();
    const std::string script_object = options_.version == KWinVersion::six
                                          ? "/Scripting/Script" + std::to_string(script_id())
                                          : "/" + std::to_string(script_id());
    if (!bus || sd_bus_request_name(bus_, "org.kde.KWin", 0) < 0 ||
        sd_bus_add_object(bus_, nullptr, "/Scripting", &StandInKWin::on_scripting, this) < 0 ||
        sd_bus_add_object(bus_, nullptr, script_object.c_str(), &StandInKWin::on_script, this) < 0) {
      ready.set_value(false);
      return;
    }
    ready.set_value(true);
    while (!stop_) {
      while (sd_bus_process(bus_, nullptr) > 0) {
      }
      std::vector<Sent> queued;
      {
        const std::lock_guard lock(mutex_);
        queued.swap(queue_);
      }
      for (const Sent& s : queued) call_back(s);
      sd_bus_wait(bus_, 5000);
    }
    bus_ = nullptr;
  }  // closing the connection gives org.kde.KWin up

  void note(const char* call) {
    const std::lock_guard lock(mutex_);
    seen_.calls.emplace_back(call);
  }

  static int on_scripting(sd_bus_message* m, void* data, sd_bus_error*) {
    auto& self = *static_cast<StandInKWin*>(data);
    const char* interface = "org.kde.kwin.Scripting";
    if (sd_bus_message_is_method_call(m, interface, "loadScript") > 0) {
      self.note("loadScript");
      const char *file = nullptr, *plugin = nullptr;
      if (sd_bus_message_read(m, "ss", &file, &plugin) < 0) return -EINVAL;
      if (self.options_.refuse) {
        return sd_bus_reply_method_errorf(m, SD_BUS_ERROR_ACCESS_DENIED, "scripting is disabled here");
      }
      if (self.loaded_) return sd_bus_reply_method_return(m, "i", -1);  // KWin: that name is loaded already
      self.loaded_ = true;
      self.running_ = false;
      self.file_ = file;
      const std::lock_guard lock(self.mutex_);
      self.seen_.loaded.emplace_back(file, plugin);
      return sd_bus_reply_method_return(m, "i", self.script_id());
    }
    if (sd_bus_message_is_method_call(m, interface, "unloadScript") > 0) {
      self.note("unloadScript");
      const char* plugin = nullptr;
      if (sd_bus_message_read(m, "s", &plugin) < 0) return -EINVAL;
      const bool was = self.loaded_;
      self.loaded_ = self.running_ = false;
      {
        const std::lock_guard lock(self.mutex_);
        self.seen_.unloaded.emplace_back(plugin);
      }
      return sd_bus_reply_method_return(m, "b", static_cast<int>(was));
    }
    if (sd_bus_message_is_method_call(m, interface, "start") > 0) {
      self.note("start");
      self.run(sd_bus_message_get_path(m));
      return sd_bus_reply_method_return(m, nullptr);
    }
    return 0;
  }

  static int on_script(sd_bus_message* m, void* data, sd_bus_error*) {
    auto& self = *static_cast<StandInKWin*>(data);
    if (sd_bus_message_is_method_call(m, "org.kde.kwin.Script", "run") <= 0) return 0;
    self.note("run");
    self.run(sd_bus_message_get_path(m));
    return sd_bus_reply_method_return(m, nullptr);
  }

  // The four strings of the script's `callDBus("SERVICE", "PATH", "INTERFACE", "METHOD", at.x, at.y)`
  // (std::regex would do, but GCC 12 warns inside it under -O1 and the sanitizers).
  static std::optional<std::vector<std::string>> call_target(const std::string& script) {
    const std::size_t call = script.find("callDBus(");
    if (call == std::string::npos) return std::nullopt;
    std::vector<std::string> strings;
    std::size_t at = call + std::strlen("callDBus(");
    for (int i = 0; i < 4; ++i) {
      const std::string separator = i == 0 ? "\"" : ", \"";
      if (script.compare(at, separator.size(), separator) != 0) return std::nullopt;
      at += separator.size();
      const std::size_t end = script.find('"', at);
      if (end == std::string::npos || end == at) return std::nullopt;
      strings.push_back(script.substr(at, end - at));
      at = end + 1;
    }
    if (script.compare(at, std::strlen(", at.x, at.y)"), ", at.x, at.y)") != 0) return std::nullopt;
    return strings;
  }

  // Runs the loaded script as far as a stand-in can: reads it and takes callDBus's target from it.
  void run(const char* object) {
    if (!loaded_ || running_) return;
    std::ifstream in(file_);
    std::stringstream text;
    text << in.rdbuf();
    {
      const std::lock_guard lock(mutex_);
      seen_.runs.emplace_back(object);
      seen_.script = in ? text.str() : "";
    }
    const std::optional<std::vector<std::string>> target = call_target(text.str());
    if (!in || !target) return;
    running_ = true;
    service_ = (*target)[0];
    path_ = (*target)[1];
    interface_ = (*target)[2];
    method_ = (*target)[3];
    if (options_.first) call_back(*options_.first);
  }

  void call_back(const Sent& s) {
    if (!running_) return;
    sd_bus_message* raw = nullptr;
    if (sd_bus_message_new_method_call(bus_, &raw, service_.c_str(), path_.c_str(), interface_.c_str(),
                                       method_.c_str()) < 0) {
      return;
    }
    const MessagePtr m(raw);
    for (std::size_t i = 0; i < 2; ++i) {
      const double value = i == 0 ? s.x : s.y;
      if (s.types[i] == 'i') {
        const std::int32_t whole = static_cast<std::int32_t>(value);
        sd_bus_message_append_basic(m.get(), 'i', &whole);
      } else {
        sd_bus_message_append_basic(m.get(), 'd', &value);
      }
    }
    sd_bus_call_async(bus_, nullptr, m.get(), &StandInKWin::on_reply, this, 0);
  }

  static int on_reply(sd_bus_message* reply, void* data, sd_bus_error*) {
    auto& self = *static_cast<StandInKWin*>(data);
    const std::lock_guard lock(self.mutex_);
    if (sd_bus_message_is_method_error(reply, nullptr) > 0) {
      ++self.seen_.replies_error;
      self.seen_.last_error = sd_bus_message_get_error(reply)->name;
    } else {
      ++self.seen_.replies_ok;
    }
    return 0;
  }

  std::string address_;
  StandInOptions options_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  bool started_ = false;
  // The stand-in's thread only:
  sd_bus* bus_ = nullptr;
  bool loaded_ = false, running_ = false;
  std::string file_, service_, path_, interface_, method_;
  // Shared with the test:
  mutable std::mutex mutex_;
  std::vector<Sent> queue_;
  Seen seen_;
};

// Waits until `done` or two seconds have passed.
template <typename Done>
bool wait_for_stand_in(Done done) {
  const auto deadline = Clock::now() + 2s;
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return false;
}

}  // namespace ph::kwin_stand_in
