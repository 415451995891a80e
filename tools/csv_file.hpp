// A text file a command writes, line by line: a CSV file, a table, or standard output ("-").
#pragma once

#include <fmt/core.h>
#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace ph::tools {

// Any failure (cannot open, a full disk) is an error that names the file and the reason. close() says whether
// everything reached it; dropped on an error, the file is closed quietly.
class CsvFile {
 public:
  explicit CsvFile(std::filesystem::path path)
      : path_(std::move(path)), file_(path_ == "-" ? stdout : std::fopen(path_.c_str(), "w")) {
    if (file_ == nullptr) fail("cannot open for writing");
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  ~CsvFile() {
    if (file_ != nullptr && file_ != stdout) std::fclose(file_);
  }

  void write(std::string_view text) {
    if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) fail("write failed");
  }

  template <typename... Args>
  void print(fmt::format_string<Args...> format, Args&&... args) {
    write(fmt::format(format, std::forward<Args>(args)...));
  }

  void close() {
    const bool failed = std::fflush(file_) != 0 || std::ferror(file_) != 0;
    const int closed = file_ == stdout ? 0 : std::fclose(file_);
    file_ = nullptr;
    if (failed || closed != 0) fail("write failed");
  }

 private:
  [[noreturn]] void fail(std::string_view what) const {
    throw std::runtime_error(
        fmt::format("{}: {}: {}", path_ == "-" ? std::string("<stdout>") : path_.string(), what, std::strerror(errno)));
  }

  std::filesystem::path path_;
  std::FILE* file_;
};

}  // namespace ph::tools
