// What the measuring commands (accuracy, stability) share: the methods they measure and their CSV files.
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
#include <vector>

#include "core/engine/methods.hpp"

namespace ph::tools {

// Every method of the registry (core/engine/methods.hpp) that is not C/D 1 throughout, with its default
// parameters, in the registry's order.
inline std::vector<MethodPtr> measured_methods() {
  std::vector<MethodPtr> out;
  const MethodRegistry registry = builtin_methods();
  for (const auto& entry : registry.entries()) {
    MethodPtr method = entry->make(entry->defaults());
    if (method->cd_lower_bound() != 1.0 || method->cd_upper_bound() != 1.0) out.push_back(std::move(method));
  }
  return out;
}

// A CSV file the command writes: each line as it comes, and any failure (cannot open, a full disk) an error that
// names the file. Closed by close(), which says whether everything reached it; dropped on an error, it is closed
// quietly.
class CsvFile {
 public:
  explicit CsvFile(std::filesystem::path path) : path_(std::move(path)), file_(std::fopen(path_.c_str(), "w")) {
    if (file_ == nullptr) fail("cannot open for writing");
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  ~CsvFile() {
    if (file_ != nullptr) std::fclose(file_);
  }

  template <typename... Args>
  void print(fmt::format_string<Args...> format, Args&&... args) {
    const std::string line = fmt::format(format, std::forward<Args>(args)...);
    if (std::fwrite(line.data(), 1, line.size(), file_) != line.size()) fail("write failed");
  }

  void close() {
    const bool failed = std::ferror(file_) != 0;
    const int closed = std::fclose(file_);
    file_ = nullptr;
    if (failed || closed != 0) fail("write failed");
  }

 private:
  [[noreturn]] void fail(std::string_view what) const {
    throw std::runtime_error(fmt::format("{}: {}: {}", path_.string(), what, std::strerror(errno)));
  }

  std::filesystem::path path_;
  std::FILE* file_;
};

}  // namespace ph::tools
