// Whether two paths of a command line name one file, so that a command refuses to write its output over one of
// its inputs (`replay`, `trace`).
#pragma once

#include <sys/stat.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace ph::tools {

inline bool same_file(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

// Whether two paths of the command name one file: an existing one by its inode (through links and other
// spellings), a new one by its path made absolute. "-" is a stream, never a file here.
inline bool same_path(const std::string& a, const std::string& b) {
  if (a == "-" || b == "-") return false;
  struct stat sa {};
  struct stat sb {};
  const bool a_exists = ::stat(a.c_str(), &sa) == 0, b_exists = ::stat(b.c_str(), &sb) == 0;
  if (a_exists || b_exists) return a_exists && b_exists && same_file(sa, sb);
  std::error_code ignored;
  return std::filesystem::weakly_canonical(a, ignored) == std::filesystem::weakly_canonical(b, ignored);
}

// Whether two outputs of the command are one: "-" is standard output, which another output may name as well
// (/dev/stdout, /proc/self/fd/1, or the file standard output is redirected to).
inline bool same_output(const std::string& a, const std::string& b) {
  if (a == "-" && b == "-") return true;
  if (a != "-" && b != "-") return same_path(a, b);
  const std::string& other = a == "-" ? b : a;
  struct stat out {};
  struct stat at {};
  // A device (/dev/null) takes two outputs alike; a file, a FIFO or a socket would get them mixed.
  return ::fstat(1, &out) == 0 && ::stat(other.c_str(), &at) == 0 && same_file(out, at) && !S_ISCHR(at.st_mode);
}

// Whether standard input is the file at `path` (a recording redirected in with `< FILE`): writing `path` would
// replace what is being read.
inline bool is_standard_input(const std::string& path) {
  if (path == "-") return false;
  struct stat in {};
  struct stat at {};
  return ::fstat(0, &in) == 0 && S_ISREG(in.st_mode) && ::stat(path.c_str(), &at) == 0 && same_file(in, at);
}

}  // namespace ph::tools
