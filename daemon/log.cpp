#include "daemon/log.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace ph {

namespace {

std::string_view level_name(LogLevel level) {
  switch (level) {
    case LogLevel::error:
      return "error";
    case LogLevel::warning:
      return "warning";
    case LogLevel::notice:
      return "notice";
    case LogLevel::info:
      return "info";
    case LogLevel::debug:
      return "debug";
  }
  return "info";
}

}  // namespace

bool Logger::stderr_is_journal() {
  const char* stream = std::getenv("JOURNAL_STREAM");  // "DEVICE:INODE"
  if (stream == nullptr) return false;
  struct stat st {};
  if (::fstat(STDERR_FILENO, &st) != 0) return false;
  unsigned long long device = 0, inode = 0;
  if (std::sscanf(stream, "%llu:%llu", &device, &inode) != 2) return false;
  return device == st.st_dev && inode == st.st_ino;
}

void Logger::log(LogLevel level, std::string_view message) const noexcept {
  if (level == LogLevel::debug && !verbose_) return;
  try {
    // A message never spans lines: a journal entry or a grep hit is one line.
    std::string line(message);
    for (char& c : line) {
      if (c == '\n') c = ' ';
    }
    if (journal_) {
      fmt::print(out_, "<{}>{}\n", static_cast<int>(level), line);
    } else {
      fmt::print(out_, "pseudohapticd: {}: {}\n", level_name(level), line);
    }
    std::fflush(out_);
  } catch (...) {  // (nowhere left to say it)
  }
}

}  // namespace ph
