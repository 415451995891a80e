// Runs the pseudohaptic tool as a user would, through the shell, for the tool tests. PH_TOOL_PATH names
// the binary (tests/CMakeLists.txt).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"

#ifndef PH_TOOL_PATH
#error "PH_TOOL_PATH must name the pseudohaptic binary (tests/CMakeLists.txt)"
#endif

namespace ph {

inline std::string read_text(const std::filesystem::path& path) { return read_file_text(path); }

// A word for the shell, single-quoted.
inline std::string quote(const std::string& word) {
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}
inline std::string quote(const std::filesystem::path& path) { return quote(path.string()); }

struct ToolResult {
  int rc = -1;  // exit status; 128 + N when killed by signal N
  std::string out;
  std::string err;
};

// Runs `program` with `args` (already quoted where needed), standard output and error into files of `dir`.
// `in_dir`: run from the scratch folder, where relative paths among `args` then lie (and can be looked for).
inline ToolResult run_program(const std::filesystem::path& program, const std::string& args, const ScratchDir& dir,
                              bool in_dir = false) {
  const std::filesystem::path out = dir / "stdout.txt";
  const std::filesystem::path err = dir / "stderr.txt";
  const std::string command = (in_dir ? "cd " + quote(dir.path()) + " && " : std::string()) + quote(program) + " " +
                              args + " >" + quote(out) + " 2>" + quote(err);
  const int status = std::system(command.c_str());
  ToolResult result;
  if (status != -1) result.rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = read_text(out);
  result.err = read_text(err);
  return result;
}

// Runs the tool with `args`, as run_program.
inline ToolResult run_tool(const std::string& args, const ScratchDir& dir) {
  return run_program(std::string(PH_TOOL_PATH), args, dir);
}

// run_tool from the scratch folder: relative paths among `args` lie in it.
inline ToolResult run_tool_in_dir(const std::string& args, const ScratchDir& dir) {
  return run_program(std::string(PH_TOOL_PATH), args, dir, true);
}

// A failure as a user should meet it: each of `parts` on standard error, no sign of a crash, and exit status 1
// (the tool's own errors), or where CLI11 turned the command line down ("Run with --help ..."), its own status.
inline void expect_clean_failure(const ToolResult& r, std::initializer_list<std::string_view> parts) {
  const auto said = [&r](std::string_view part) { return r.err.find(part) != std::string::npos; };
  if (said("Run with --help")) {
    EXPECT_TRUE(r.rc > 0 && r.rc < 128) << "exit status " << r.rc << ": " << r.err;
  } else {
    EXPECT_EQ(r.rc, 1) << r.err;
  }
  for (std::string_view part : parts) EXPECT_TRUE(said(part)) << "expected '" << part << "' in: " << r.err;
  for (std::string_view crash : {"terminate called", "what():", "Aborted", "Segmentation", "Sanitizer", "#0 ", "#1 "}) {
    EXPECT_FALSE(said(crash)) << r.err;
  }
}

}  // namespace ph
