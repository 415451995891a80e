// A text file a command writes, line by line: a CSV file, a table, or standard output ("-").
#pragma once

#include <fmt/core.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "config/staged_write.hpp"

namespace ph::tools {

// Any failure (cannot open, a full disk) is an error that names the file and the reason. A regular file (or a new
// one) is written to a temporary file beside it, which close() renames over it: a run that fails or is interrupted
// leaves the file as it was (an interrupted one, its temporary `.NAME.PID.partial` beside it), never half written.
// Standard output, a FIFO, a device or a link is written through. close() says whether everything reached it;
// dropped on an error, the file is closed quietly and the temporary one removed.
class CsvFile {
 public:
  // `staged` false: written in place, for a file that is itself a temporary one (tools/output_folder.hpp, OutputSet).
  explicit CsvFile(std::filesystem::path path, bool staged = true) : path_(std::move(path)) {
    struct stat st {};
    const bool exists = path_ != "-" && ::lstat(path_.c_str(), &st) == 0;
    if (staged && path_ != "-" && (!exists || S_ISREG(st.st_mode))) {
      // A file the user may not write is not replaced either (a rename needs only the folder's permission).
      if (exists && ::access(path_.c_str(), W_OK) != 0) fail("cannot open for writing");
      staged_ = staged_path(path_);
      if (exists) mode_ = st.st_mode & 07777;
    }
    const std::filesystem::path& opened = staged_.empty() ? path_ : staged_;
    file_ = path_ == "-" ? stdout : std::fopen(opened.c_str(), "w");
    if (file_ == nullptr) fail("cannot open for writing");
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  ~CsvFile() {
    if (file_ != nullptr && file_ != stdout) std::fclose(file_);
    if (!staged_.empty()) ::unlink(staged_.c_str());
  }

  void write(std::string_view text) {
    if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) fail("write failed");
  }

  template <typename... Args>
  void print(fmt::format_string<Args...> format, Args&&... args) {
    write(fmt::format(format, std::forward<Args>(args)...));
  }

  // Whether the file is written beside its name and renamed over it (false: written through, or standard output).
  bool staged() const { return !staged_.empty(); }

  void close() {
    if (mode_ != 0 && file_ != nullptr && file_ != stdout) ::fchmod(::fileno(file_), mode_);  // the file's own mode
    const bool failed = std::fflush(file_) != 0 || std::ferror(file_) != 0;
    const int closed = file_ == stdout ? 0 : std::fclose(file_);
    file_ = nullptr;
    if (failed || closed != 0) fail("write failed");
    if (!staged_.empty()) {
      if (::rename(staged_.c_str(), path_.c_str()) != 0) fail("cannot replace it");
      staged_.clear();
    }
  }

 private:
  [[noreturn]] void fail(std::string_view what) const {
    throw std::runtime_error(
        fmt::format("{}: {}: {}", path_ == "-" ? std::string("<stdout>") : path_.string(), what, std::strerror(errno)));
  }

  std::filesystem::path path_;
  std::filesystem::path staged_;  // the temporary file, "" once renamed (or when written through)
  mode_t mode_ = 0;               // the replaced file's mode, 0 for a new file
  std::FILE* file_ = nullptr;
};

}  // namespace ph::tools
