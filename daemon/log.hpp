// The daemon's log: one line per message on stderr. When stderr is connected to the journal
// (JOURNAL_STREAM names it), lines carry the syslog priority as "<N>" so journald keeps the level;
// otherwise they read "pseudohapticd: LEVEL: message". Debug lines only with --verbose.
#pragma once

#include <fmt/format.h>

#include <cstdio>
#include <string_view>

namespace ph {

// syslog priorities, as sd-daemon(3) prefixes use them.
enum class LogLevel { error = 3, warning = 4, notice = 5, info = 6, debug = 7 };

class Logger {
 public:
  Logger(bool verbose, bool journal, std::FILE* out = stderr) : verbose_(verbose), journal_(journal), out_(out) {}

  // True when JOURNAL_STREAM (set by systemd) names the device and inode of our stderr.
  static bool stderr_is_journal();

  // Never throws: a line that cannot be written (a full disk, a stalled journal's interrupted write) is lost, and
  // the mouse reader or loop that logged it goes on. fmt's print throws there, and out of a reader thread that
  // was std::terminate.
  void log(LogLevel level, std::string_view message) const noexcept;
  bool verbose() const { return verbose_; }

  template <typename... Args>
  void error(fmt::format_string<Args...> f, Args&&... args) const {
    log(LogLevel::error, fmt::format(f, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void warning(fmt::format_string<Args...> f, Args&&... args) const {
    log(LogLevel::warning, fmt::format(f, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void notice(fmt::format_string<Args...> f, Args&&... args) const {
    log(LogLevel::notice, fmt::format(f, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void info(fmt::format_string<Args...> f, Args&&... args) const {
    log(LogLevel::info, fmt::format(f, std::forward<Args>(args)...));
  }
  template <typename... Args>
  void debug(fmt::format_string<Args...> f, Args&&... args) const {
    if (verbose_) log(LogLevel::debug, fmt::format(f, std::forward<Args>(args)...));
  }

 private:
  bool verbose_;
  bool journal_;
  std::FILE* out_;
};

}  // namespace ph
