// A progress line on standard error for the commands that write many files: rewritten in place on a terminal;
// where standard error is a file or a pipe (a log, CI, `2>log`), one line per step, so that the log reads line by
// line instead of as one line of carriage returns.
#pragma once

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

namespace ph::tools {

class ProgressLine {
 public:
  ProgressLine() : in_place_(::isatty(STDERR_FILENO) == 1) {}

  bool in_place() const { return in_place_; }

  void show(const std::string& text) {
    if (in_place_) {
      fmt::print(stderr, "\r{:<{}}", text, width_);
      width_ = std::max(width_, text.size());
    } else {
      fmt::print(stderr, "{}\n", text);
    }
    std::fflush(stderr);
  }

  // Ends the line in place (a terminal), erasing it where `erase`; nothing to do where each step had its line.
  void finish(bool erase = false) {
    if (!in_place_ || width_ == 0) return;
    if (erase) {
      fmt::print(stderr, "\r{:<{}}\r", "", width_);
    } else {
      fmt::print(stderr, "\n");
    }
    width_ = 0;
  }

 private:
  bool in_place_;
  std::size_t width_ = 0;
};

}  // namespace ph::tools
