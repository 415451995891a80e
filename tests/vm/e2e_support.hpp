// What the daemon's end-to-end check (daemon_e2e.cpp) needs around the daemon it drives, inside the VM:
// owned file descriptors, a kernel uevent listener to wait on, the input nodes in sysfs, a reader of an
// evdev node, the sd_notify socket the daemon reports to, the daemon as a child process, and test mice.
#pragma once

#include <fcntl.h>
#include <linux/input.h>
#include <linux/netlink.h>
#include <poll.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "common/unique_fd.hpp"
#include "control/client.hpp"
#include "control/protocol.hpp"
#include "core/engine/event.hpp"
#include "tests/vm/vm_check.hpp"
#include "uinput/uinput_sink.hpp"

namespace ph::e2e {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

// A precondition of the checks that follow failed: the rest of that daemon's checks cannot run.
class Fatal : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline std::string errno_text(int err) { return std::strerror(err); }

// A scratch folder of this run's own, $TMPDIR/PREFIX-XXXXXX (or under /tmp): a second run, or another user's,
// never meets this one's files. It stays after the run for its logs; the programs print where it is. Mode
// 0755, not mkdtemp's 0700: the checks run clients as another user (uid 65534) against sockets inside it.
inline std::filesystem::path own_scratch(const std::string& prefix) {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern =
      (std::filesystem::path(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") / (prefix + "-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr)
    throw Fatal("cannot create a scratch folder " + pattern + ": " + errno_text(errno));
  std::filesystem::permissions(pattern, std::filesystem::perms::owner_all | std::filesystem::perms::group_read |
                                            std::filesystem::perms::group_exec | std::filesystem::perms::others_read |
                                            std::filesystem::perms::others_exec);
  return pattern;
}

// The command line of the session checks: SESSION [--daemon PSEUDOHAPTICD] [--COMPOSITOR PATH] [--scratch DIR].
struct SessionCheckOptions {
  std::string session;     // pseudohaptic-session
  std::string daemon;      // pseudohapticd, for the cases that drive the helper through the daemon
  std::string compositor;  // the compositor's binary; its default is set before parsing
  std::filesystem::path scratch;
};

// Parses `argv` into `options`; `compositor_flag` names the compositor's option ("--weston"). False on anything
// else, for the usage line.
inline bool parse_session_check_options(int argc, char** argv, const std::string& compositor_flag,
                                        SessionCheckOptions& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == compositor_flag && i + 1 < argc) {
      options.compositor = argv[++i];
    } else if (arg == "--daemon" && i + 1 < argc) {
      options.daemon = argv[++i];
    } else if (arg == "--scratch" && i + 1 < argc) {
      options.scratch = argv[++i];
    } else if (options.session.empty() && arg.rfind("-", 0) != 0) {
      options.session = arg;
    } else {
      return false;
    }
  }
  return !options.session.empty();
}

// The scratch folder given, emptied, or a new one of this run's own (own_scratch).
inline std::filesystem::path fresh_scratch(const std::filesystem::path& given, const std::string& prefix) {
  if (given.empty()) return own_scratch(prefix);
  std::filesystem::remove_all(given);
  return given;
}

// Milliseconds from now until `deadline`, rounded up, at least 0 and at most `cap`: a poll(2) timeout.
inline int ms_until(Clock::time_point deadline, std::chrono::milliseconds cap = std::chrono::hours(1)) {
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::clamp(left, 0ms, cap).count());
}

using Fd = UniqueFd;  // common/unique_fd.hpp

// The kernel's uevents (NETLINK_KOBJECT_UEVENT): something to wait on while input devices come and go.
class UeventMonitor {
 public:
  UeventMonitor() : fd_(::socket(AF_NETLINK, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, NETLINK_KOBJECT_UEVENT)) {
    if (!fd_) throw Fatal("uevent socket: " + errno_text(errno));
    sockaddr_nl addr{};
    addr.nl_family = AF_NETLINK;
    addr.nl_groups = 1;  // the kernel's broadcast group
    if (::bind(fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) {
      throw Fatal("uevent bind: " + errno_text(errno));
    }
  }

  // Returns when a uevent arrives, at `deadline`, or after `cap`, whichever comes first; drops what arrived.
  void wait(Clock::time_point deadline, std::chrono::milliseconds cap) const {
    pollfd p{fd_.get(), POLLIN, 0};
    if (::poll(&p, 1, ms_until(deadline, cap)) <= 0) return;
    char buffer[4096];
    while (::recv(fd_.get(), buffer, sizeof buffer, 0) > 0) {
    }
  }

 private:
  Fd fd_;
};

// True once `condition()` holds, checked again at every uevent (when `uevents` is given) and at least
// every `recheck`; false when `timeout` ran out first.
template <class Condition>
bool wait_until(Condition condition, Clock::duration timeout, const UeventMonitor* uevents = nullptr,
                std::chrono::milliseconds recheck = 10ms) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (condition()) return true;
    if (Clock::now() >= deadline) return false;
    if (uevents != nullptr) {
      uevents->wait(deadline, recheck);
    } else {
      ::poll(nullptr, 0, ms_until(deadline, recheck));
    }
  }
}

inline std::string read_text_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The /dev/input/eventN node of the input device called `name` (from sysfs), "" when there is none.
inline std::string find_input_node(const std::string& name) {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/sys/class/input", error)) {
    const std::string node = entry.path().filename().string();
    if (node.rfind("event", 0) != 0) continue;
    std::string device_name = read_text_file(entry.path() / "device" / "name");
    while (!device_name.empty() && device_name.back() == '\n') device_name.pop_back();
    if (device_name == name) return "/dev/input/" + node;
  }
  return "";
}

// Names of the input devices (with an event node) whose name starts with `prefix`.
inline std::vector<std::string> input_devices_named(std::string_view prefix) {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/sys/class/input", error)) {
    if (entry.path().filename().string().rfind("event", 0) != 0) continue;
    std::string device_name = read_text_file(entry.path() / "device" / "name");
    while (!device_name.empty() && device_name.back() == '\n') device_name.pop_back();
    if (device_name.rfind(prefix, 0) == 0) names.push_back(device_name);
  }
  return names;
}

inline bool openable(const std::string& node) { return Fd(::open(node.c_str(), O_RDONLY | O_CLOEXEC)).get() >= 0; }

// Waits until the input device `name` exists and its node opens; returns the node ("" on timeout).
inline std::string wait_for_device(const std::string& name, Clock::duration timeout, const UeventMonitor& uevents) {
  std::string node;
  wait_until(
      [&] {
        node = find_input_node(name);
        return !node.empty() && openable(node);
      },
      timeout, &uevents, 50ms);
  return openable(node) ? node : "";
}

inline bool wait_for_device_gone(const std::string& name, Clock::duration timeout, const UeventMonitor& uevents) {
  return wait_until([&] { return find_input_node(name).empty(); }, timeout, &uevents, 50ms);
}

inline std::string event_name(const InputEvent& e) {
  const char* code = libevdev_event_code_get_name(e.type, e.code);
  if (code != nullptr) return code;
  const char* type = libevdev_event_type_get_name(e.type);
  return std::string(type != nullptr ? type : "?") + "/" + std::to_string(e.code);
}

// "REL_X 5, BTN_LEFT 1, SYN_REPORT": a frame in words (no times).
inline std::string describe(const Frame& frame) {
  std::string text;
  for (const InputEvent& e : frame.events) {
    if (!text.empty()) text += ", ";
    text += event_name(e);
    if (e.type != ev::kSyn) text += " " + std::to_string(e.value);
  }
  return text.empty() ? "(nothing)" : text;
}

// The frame without its times: what a reader compares (the kernel stamps the events it delivers).
inline Frame untimed(Frame frame) {
  for (InputEvent& e : frame.events) e.time = 0;
  return frame;
}

inline bool same_events(const Frame& a, const Frame& b) { return untimed(a).events == untimed(b).events; }

// Whether the kernel delivers the frame at all: it drops a SYN_REPORT that ends an empty frame.
inline bool delivers_something(const Frame& frame) {
  return std::any_of(frame.events.begin(), frame.events.end(), [](const InputEvent& e) { return e.type != ev::kSyn; });
}

inline bool is_pointer_motion(const InputEvent& e) {
  return (e.type == ev::kRel && (e.code == ev::kRelX || e.code == ev::kRelY)) ||
         (e.type == ev::kAbs && (e.code == ev::kAbsX || e.code == ev::kAbsY));
}

// The frame's events other than the pointer's motion (REL_X/REL_Y, ABS_X/ABS_Y), in order.
inline Frame without_motion(const Frame& frame) {
  Frame out;
  for (const InputEvent& e : frame.events) {
    if (!is_pointer_motion(e)) out.events.push_back(e);
  }
  return out;
}

// Whether the frame moves the pointer (a REL_X or REL_Y that is not 0).
inline bool has_motion(const Frame& frame) {
  return std::any_of(frame.events.begin(), frame.events.end(),
                     [](const InputEvent& e) { return e.type == ev::kRel && is_pointer_motion(e) && e.value != 0; });
}

// The value of an event of the frame, nullopt when the frame has none.
inline std::optional<std::int32_t> value_in(const Frame& frame, std::uint16_t type, std::uint16_t code) {
  for (const InputEvent& e : frame.events) {
    if (e.type == type && e.code == code) return e.value;
  }
  return std::nullopt;
}

// The clock of the events the daemon reads: it asks the kernel for CLOCK_MONOTONIC (EVIOCSCLOCKID), and
// the kernel stamps a frame when its SYN_REPORT is written. In microseconds, as InputEvent::time.
inline TimeUs monotonic_us() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeUs>(ts.tv_sec) * 1000000 + static_cast<TimeUs>(ts.tv_nsec / 1000);
}

// The frame with every event at `time`.
inline Frame stamped(Frame frame, TimeUs time) {
  for (InputEvent& e : frame.events) e.time = time;
  return frame;
}

inline InputEvent rel(std::uint16_t code, std::int32_t value) { return {0, ev::kRel, code, value}; }
inline InputEvent abs_event(std::uint16_t code, std::int32_t value) { return {0, ev::kAbs, code, value}; }
inline InputEvent key(std::uint16_t code, std::int32_t value) { return {0, ev::kKey, code, value}; }

// A frame of these events, ended by SYN_REPORT.
inline Frame make_frame(std::vector<InputEvent> events) {
  events.push_back({0, ev::kSyn, ev::kSynReport, 0});
  return Frame{std::move(events)};
}

// Reads an evdev node (non-blocking, not grabbed) and splits what it reads into frames.
class EventReader {
 public:
  explicit EventReader(std::string node)
      : node_(std::move(node)), fd_(::open(node_.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)) {
    if (!fd_) throw Fatal("cannot open " + node_ + ": " + errno_text(errno));
  }

  const std::string& node() const { return node_; }
  int fd() const { return fd_.get(); }
  bool gone() const { return gone_; }

  // The next complete frame (up to and including SYN_REPORT), times in microseconds of the kernel's
  // clock; nullopt on timeout or once the device is gone.
  std::optional<Frame> next_frame(Clock::duration timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      const auto end = std::find_if(pending_.begin(), pending_.end(),
                                    [](const InputEvent& e) { return e.type == ev::kSyn && e.code == ev::kSynReport; });
      if (end != pending_.end()) {
        Frame frame{std::vector<InputEvent>(pending_.begin(), end + 1)};
        pending_.erase(pending_.begin(), end + 1);
        return frame;
      }
      if (gone_) return std::nullopt;
      if (!fill(ms_until(deadline)) && Clock::now() >= deadline) return std::nullopt;
    }
  }

  // Everything that can be read now, partial frames included.
  std::vector<InputEvent> read_now() {
    fill(0);
    std::vector<InputEvent> events(pending_.begin(), pending_.end());
    pending_.clear();
    return events;
  }

  // The keys and buttons down now, as the kernel says (EVIOCGKEY).
  std::vector<std::uint16_t> keys_down() const {
    unsigned long bits[KEY_MAX / (8 * sizeof(unsigned long)) + 1] = {};
    if (::ioctl(fd_.get(), EVIOCGKEY(sizeof bits), bits) < 0) throw Fatal("EVIOCGKEY on " + node_ + " failed");
    std::vector<std::uint16_t> down;
    for (unsigned code = 0; code <= KEY_MAX; ++code) {
      if ((bits[code / (8 * sizeof(unsigned long))] >> (code % (8 * sizeof(unsigned long)))) & 1UL) {
        down.push_back(static_cast<std::uint16_t>(code));
      }
    }
    return down;
  }

 private:
  // Waits up to timeout_ms for something to read, then reads all of it. True when something was read.
  bool fill(int timeout_ms) {
    pollfd p{fd_.get(), POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    bool any = false;
    input_event buffer[64];
    for (;;) {
      const ssize_t n = ::read(fd_.get(), buffer, sizeof buffer);
      if (n < 0) {
        if (errno == EINTR) continue;
        if (errno != EAGAIN) gone_ = true;  // ENODEV: the device went away
        return any;
      }
      if (n == 0) {
        gone_ = true;
        return any;
      }
      for (std::size_t i = 0; i < static_cast<std::size_t>(n) / sizeof(input_event); ++i) {
        const input_event& e = buffer[i];
        const TimeUs time = static_cast<TimeUs>(e.input_event_sec) * 1000000 + static_cast<TimeUs>(e.input_event_usec);
        pending_.push_back({time, e.type, e.code, e.value});
      }
      any = true;
    }
  }

  std::string node_;
  Fd fd_;
  std::deque<InputEvent> pending_;
  bool gone_ = false;
};

// Tries EVIOCGRAB on the node through a descriptor of its own and lets go at once. Returns 0 when the
// grab succeeded, else the errno (EBUSY: someone else holds the grab).
inline int try_grab(const std::string& node) {
  const Fd fd(::open(node.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (!fd) return errno;
  if (::ioctl(fd.get(), EVIOCGRAB, 1) < 0) return errno;
  ::ioctl(fd.get(), EVIOCGRAB, 0);
  return 0;
}

// A unix datagram socket at a path, for NOTIFY_SOCKET: the daemon's sd_notify lines ("READY=1", ...). A
// thread of its own reads it all the time: the kernel queues only a few datagrams (net.unix.max_dgram_qlen,
// 10) and then blocks the sender, so a socket read only now and then would stall the daemon.
class NotifySocket {
 public:
  explicit NotifySocket(std::string path)
      : path_(std::move(path)),
        fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0)),
        stop_(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
    if (!fd_ || !stop_) throw Fatal("notify socket: " + errno_text(errno));
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    if (path_.size() >= sizeof addr.sun_path) throw Fatal("notify socket path too long: " + path_);
    std::memcpy(addr.sun_path, path_.c_str(), path_.size() + 1);
    ::unlink(path_.c_str());
    if (::bind(fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) {
      throw Fatal("bind " + path_ + ": " + errno_text(errno));
    }
    reader_ = std::thread([this] { read_until_stopped(); });
  }
  ~NotifySocket() {
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(stop_.get(), &one, sizeof one);
    reader_.join();
    ::unlink(path_.c_str());
  }
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  const std::string& path() const { return path_; }

  // Waits for the line (e.g. "READY=1"), skipping the lines before it; false on timeout.
  bool expect(std::string_view line, Clock::duration timeout) {
    const auto deadline = Clock::now() + timeout;
    std::unique_lock lock(mutex_);
    for (;;) {
      while (!unread_.empty()) {
        const std::string next = std::move(unread_.front());
        unread_.pop_front();
        if (next == line) return true;
      }
      if (arrived_.wait_until(lock, deadline) == std::cv_status::timeout && unread_.empty()) return false;
    }
  }

  // Forgets what arrived and was not expected yet.
  void clear() {
    const std::lock_guard lock(mutex_);
    unread_.clear();
  }

  // Every line received, in order.
  std::vector<std::string> history() const {
    const std::lock_guard lock(mutex_);
    return history_;
  }

 private:
  void read_until_stopped() {
    for (;;) {
      pollfd p[2] = {{fd_.get(), POLLIN, 0}, {stop_.get(), POLLIN, 0}};
      if (::poll(p, 2, -1) < 0 && errno != EINTR) return;
      if (p[1].revents != 0) return;
      char buffer[4096];
      ssize_t n;
      while ((n = ::recv(fd_.get(), buffer, sizeof buffer, 0)) > 0) {
        std::istringstream lines(std::string(buffer, static_cast<std::size_t>(n)));
        const std::lock_guard lock(mutex_);
        for (std::string line; std::getline(lines, line);) {
          if (line.empty()) continue;
          unread_.push_back(line);
          history_.push_back(line);
        }
        arrived_.notify_all();
      }
    }
  }

  std::string path_;
  Fd fd_, stop_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<std::string> unread_;
  std::vector<std::string> history_;
  std::thread reader_;  // last: started once everything it uses exists
};

// The daemon as a child process: stdout and stderr into a log file, NOTIFY_SOCKET set, no other
// descriptor of ours inherited. Killed (SIGKILL) and reaped if still running when destroyed.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const std::vector<std::string>& env, std::string log_path)
      : log_path_(std::move(log_path)) {
    std::vector<char*> args, envp;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
    const Fd log(::open(log_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644));
    if (!log) throw Fatal("cannot create " + log_path_ + ": " + errno_text(errno));
    pid_ = ::fork();
    if (pid_ < 0) throw Fatal("fork: " + errno_text(errno));
    if (pid_ == 0) {  // only async-signal-safe calls from here
      ::dup2(log.get(), STDOUT_FILENO);
      ::dup2(log.get(), STDERR_FILENO);
      ::syscall(SYS_close_range, 3U, UINT_MAX, 0U);
      ::execve(args[0], args.data(), envp.data());
      ::_exit(127);
    }
    pidfd_ = Fd(static_cast<int>(::syscall(SYS_pidfd_open, pid_, 0U)));
    if (!pidfd_) throw Fatal("pidfd_open: " + errno_text(errno));
  }
  ~ChildProcess() {
    if (running()) ::kill(pid_, SIGKILL);
    wait_exit(10s);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  bool signal(int sig) const { return ::kill(pid_, sig) == 0; }

  bool running() {
    if (status_) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) status_ = status;
    return !status_;
  }

  // The wait status once it has exited, nullopt if it is still running after `timeout`.
  std::optional<int> wait_exit(Clock::duration timeout) {
    if (!running()) return status_;
    pollfd p{pidfd_.get(), POLLIN, 0};
    ::poll(&p, 1, ms_until(Clock::now() + timeout));
    running();
    return status_;
  }

  // Blocks until the child is stopped (after SIGSTOP); false if it exited instead.
  bool wait_stopped() {
    int status = 0;
    if (::waitpid(pid_, &status, WUNTRACED) != pid_) return false;
    if (WIFSTOPPED(status)) return true;
    status_ = status;
    return false;
  }

  // What it wrote so far.
  std::string log() const { return read_text_file(log_path_); }
  const std::string& log_path() const { return log_path_; }

 private:
  std::string log_path_;
  pid_t pid_ = -1;
  Fd pidfd_;
  std::optional<int> status_;
};

inline std::string describe_wait_status(int status) {
  if (WIFEXITED(status)) return "exit status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("killed by ") + ::strsignal(WTERMSIG(status));
  return "wait status " + std::to_string(status);
}

// Open descriptors of a process (entries of /proc/PID/fd).
inline int open_fd_count(pid_t pid) {
  int count = 0;
  std::error_code error;
  for (auto it = std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd", error);
       !error && it != std::filesystem::directory_iterator(); it.increment(error)) {
    ++count;
  }
  return count;
}

// VmRSS of a process in KiB (/proc/PID/status), -1 when it cannot be read.
inline long rss_kib(pid_t pid) {
  std::istringstream status(read_text_file("/proc/" + std::to_string(pid) + "/status"));
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

// Each mapping of a process (/proc/PID/smaps), keyed by its start address, permissions and path ("[heap]", a file,
// or nothing for an anonymous one): its size and resident KiB.
struct MappingKib {
  long size = 0, rss = 0, huge = 0;  // huge: AnonHugePages, what transparent huge pages hold
};
inline std::map<std::string, MappingKib> mappings_kib(pid_t pid) {
  std::map<std::string, MappingKib> out;
  std::istringstream smaps(read_text_file("/proc/" + std::to_string(pid) + "/smaps"));
  MappingKib* current = nullptr;
  for (std::string line; std::getline(smaps, line);) {
    std::istringstream words(line);
    std::string first, perms, offset, device, inode, path;
    words >> first;
    if (first.empty()) continue;
    if (first.back() != ':') {  // a mapping's header: start-end perms offset dev inode [path]
      words >> perms >> offset >> device >> inode >> path;
      current = &out[first.substr(0, first.find('-')) + " " + perms + " " + path];
    } else if (current != nullptr && (first == "Size:" || first == "Rss:" || first == "AnonHugePages:")) {
      long kib = 0;
      words >> kib;
      (first == "Size:" ? current->size : first == "Rss:" ? current->rss : current->huge) = kib;
    }
  }
  return out;
}

// The mappings whose resident KiB grew by at least `min_kib` from `before` to `after` (new ones included), as
// "KEY: RSS1 -> RSS2 KiB of SIZE1 -> SIZE2, in huge pages ...", largest growth first.
inline std::vector<std::string> grown_mappings(const std::map<std::string, MappingKib>& before,
                                               const std::map<std::string, MappingKib>& after, long min_kib) {
  std::vector<std::pair<long, std::string>> grown;
  for (const auto& [key, now] : after) {
    const auto found = before.find(key);
    const bool is_new = found == before.end();
    const MappingKib was = is_new ? MappingKib{} : found->second;
    if (now.rss - was.rss >= min_kib) {
      grown.emplace_back(now.rss - was.rss,
                         fmt::format("{}: {} -> {} KiB of {} -> {}, in huge pages {} -> {} KiB{}", key, was.rss,
                                     now.rss, was.size, now.size, was.huge, now.huge, is_new ? " (new)" : ""));
    }
  }
  std::sort(grown.begin(), grown.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::string> out;
  for (auto& g : grown) out.push_back(std::move(g.second));
  return out;
}

// The names of a process's threads (/proc/PID/task/TID/comm), in no particular order.
inline std::vector<std::string> thread_names(pid_t pid) {
  std::vector<std::string> out;
  std::error_code error;
  const std::string tasks = "/proc/" + std::to_string(pid) + "/task";
  for (auto it = std::filesystem::directory_iterator(tasks, error);
       !error && it != std::filesystem::directory_iterator(); it.increment(error)) {
    std::string name = read_text_file(it->path().string() + "/comm");
    while (!name.empty() && name.back() == '\n') name.pop_back();
    out.push_back(std::move(name));
  }
  return out;
}

// Whether a process has `path` open (a link in /proc/PID/fd).
inline bool process_has_open(pid_t pid, const std::string& path) {
  std::error_code error;
  for (auto it = std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd", error);
       !error && it != std::filesystem::directory_iterator(); it.increment(error)) {
    std::error_code link_error;
    if (std::filesystem::read_symlink(it->path(), link_error).string() == path) return true;
  }
  return false;
}

// A test mouse's device: vm_mouse's, with the horizontal and high-resolution wheels and a middle button.
inline DeviceDescription test_mouse_description(const std::string& name) {
  DeviceDescription d = vm::vm_mouse(name);
  for (std::uint16_t code : {ev::kRelHWheel, ev::kRelWheelHiRes, ev::kRelHWheelHiRes}) d.enable(ev::kRel, code);
  d.enable(ev::kKey, ev::kBtnMiddle);
  return d;
}

// A "physical" mouse through uinput: REL_X/REL_Y, wheel and horizontal wheel with their hi-res
// companions, left, right and middle buttons. Destroying it releases what it holds, then removes it.
class TestMouse {
 public:
  explicit TestMouse(const std::string& name)
      : name_(name), sink_(test_mouse_description(name)), node_(sink_.devnode()) {
    if (node_.empty()) throw Fatal("the kernel gave no device node for test mouse '" + name + "'");
  }

  const std::string& name() const { return name_; }
  const std::string& node() const { return node_; }
  void send(const Frame& frame) { sink_.write(frame); }

 private:
  std::string name_;
  UinputSink sink_;
  std::string node_;
};

// A touchpad-like pointer through uinput: ABS_X/ABS_Y (0..1000), BTN_TOUCH, BTN_TOOL_FINGER and BTN_LEFT,
// no REL_X/REL_Y. The daemon does not take it (not a mouse) but watches it to resync its cursor model.
class TestTouchpad {
 public:
  explicit TestTouchpad(const std::string& name) : sink_(description(name)), node_(sink_.devnode()) {
    if (node_.empty()) throw Fatal("the kernel gave no device node for test touchpad '" + name + "'");
  }

  const std::string& node() const { return node_; }
  void send(const Frame& frame) { sink_.write(frame); }

 private:
  static DeviceDescription description(const std::string& name) {
    DeviceDescription d;
    d.name = name;
    d.bustype = 0x18;        // BUS_I2C, as laptop touchpads
    d.properties.set(0x00);  // INPUT_PROP_POINTER
    for (std::uint16_t type : {ev::kSyn, ev::kKey, ev::kAbs}) d.enable(ev::kSyn, type);
    for (std::uint16_t code : {std::uint16_t{BTN_LEFT}, std::uint16_t{BTN_TOUCH}, std::uint16_t{BTN_TOOL_FINGER}}) {
      d.enable(ev::kKey, code);
    }
    for (std::uint16_t code : {ev::kAbsX, ev::kAbsY}) {
      d.enable(ev::kAbs, code);
      d.absinfo[code] = {0, 1000, 0, 0, 10};
    }
    return d;
  }

  UinputSink sink_;
  std::string node_;
};

// A session helper of our own on the daemon's control socket: says `helper test`, records when each
// `query` arrives, and answers it with `position X Y` of the point it is given (none: no answer). A
// thread of its own reads the socket all the time, as a real helper would.
class FakeHelper {
 public:
  explicit FakeHelper(const std::string& socket) : client_(socket) {
    if (!client_.send_line("helper test")) throw Fatal("the fake helper could not send 'helper test'");
    for (;;) {  // the reply; a query may come first
      const std::optional<std::string> line = client_.read_line(std::chrono::milliseconds(5000));
      if (!line) throw Fatal("no reply to 'helper test' within 5 s");
      if (*line == "ok") break;
      if (*line != "query") throw Fatal("'helper test' answered: " + *line);
      queries_.push_back(Clock::now());
    }
    reader_ = std::thread([this] { read_until_stopped(); });
  }
  ~FakeHelper() {
    stop_ = true;
    reader_.join();
  }
  FakeHelper(const FakeHelper&) = delete;
  FakeHelper& operator=(const FakeHelper&) = delete;

  // What to answer the next queries with (nullopt: nothing).
  void answer_with(std::optional<Vec2> point) {
    const std::lock_guard lock(mutex_);
    point_ = point;
  }

  // The first query that arrived at or after `after`, waiting at most `timeout`.
  std::optional<Clock::time_point> query_after(Clock::time_point after, Clock::duration timeout) {
    std::unique_lock lock(mutex_);
    const auto found = [&]() -> std::optional<Clock::time_point> {
      for (const Clock::time_point t : queries_) {
        if (t >= after) return t;
      }
      return std::nullopt;
    };
    arrived_.wait_for(lock, timeout, [&] { return found().has_value(); });
    return found();
  }

  // Queries that arrived in [from, to].
  int queries_between(Clock::time_point from, Clock::time_point to) const {
    const std::lock_guard lock(mutex_);
    return static_cast<int>(
        std::count_if(queries_.begin(), queries_.end(), [&](Clock::time_point t) { return t >= from && t <= to; }));
  }

  // When the last query arrived (nullopt: none yet).
  std::optional<Clock::time_point> last_query() const {
    const std::lock_guard lock(mutex_);
    return queries_.empty() ? std::nullopt : std::optional<Clock::time_point>(queries_.back());
  }

  int answers() const { return answers_; }
  // Lines other than `query` and `ok` (an error from the daemon), for the report.
  std::vector<std::string> unexpected() const {
    const std::lock_guard lock(mutex_);
    return unexpected_;
  }

 private:
  void read_until_stopped() {
    try {
      while (!stop_) {
        const std::optional<std::string> line = client_.read_line(std::chrono::milliseconds(20));
        if (!line || *line == "ok") continue;
        std::unique_lock lock(mutex_);
        if (*line != "query") {
          unexpected_.push_back(*line);
          continue;
        }
        queries_.push_back(Clock::now());
        const std::optional<Vec2> point = point_;
        lock.unlock();
        arrived_.notify_all();
        if (point && client_.send_line(control::format_request(control::PositionRequest{*point}))) ++answers_;
      }
    } catch (const control::ControlError& e) {
      const std::lock_guard lock(mutex_);
      unexpected_.push_back(std::string("connection ended: ") + e.what());
    }
  }

  control::Client client_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<Clock::time_point> queries_;
  std::vector<std::string> unexpected_;
  std::optional<Vec2> point_;
  std::atomic<int> answers_{0};
  std::atomic<bool> stop_{false};
  std::thread reader_;  // last: started once everything it uses exists
};

// The daemon creates a mouse's virtual device just before it grabs the mouse, and drops what the mouse
// queued before the grab: a frame sent in between goes to the mouse's other readers only. Sends a wheel
// notch every 200 ms until one comes out of `out`, then a horizontal one and reads up to it, so that no
// notch is left to read. The grab holds from then on. (Frames without motion leave the cursor model alone.)
template <class Mouse>  // TestMouse, or anything else that sends frames
bool wait_taken(Mouse& mouse, EventReader& out, Clock::duration timeout, Clock::duration frame_timeout = 5s) {
  const auto deadline = Clock::now() + timeout;
  bool through = false;
  while (!through && Clock::now() < deadline) {
    mouse.send(make_frame({rel(ev::kRelWheel, 1)}));
    through = out.next_frame(200ms).has_value();
  }
  if (!through) return false;
  const Frame marker = make_frame({rel(ev::kRelHWheel, 1)});
  mouse.send(marker);
  while (const std::optional<Frame> got = out.next_frame(frame_timeout)) {
    if (same_events(*got, marker)) return true;
  }
  return false;
}

}  // namespace ph::e2e
