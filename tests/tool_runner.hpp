// Runs the pseudohaptic tool as a user would, through the shell, for the tool tests. PH_TOOL_PATH names
// the binary (tests/CMakeLists.txt).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

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

// Runs the tool with `args` (already quoted where needed), standard output and error into files of `dir`.
inline ToolResult run_tool(const std::string& args, const ScratchDir& dir) {
  const std::filesystem::path out = dir / "stdout.txt";
  const std::filesystem::path err = dir / "stderr.txt";
  const std::string command = quote(std::string(PH_TOOL_PATH)) + " " + args + " >" + quote(out) + " 2>" + quote(err);
  const int status = std::system(command.c_str());
  ToolResult result;
  if (status != -1) result.rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = read_text(out);
  result.err = read_text(err);
  return result;
}

}  // namespace ph
