// A file written whole or not at all: under a temporary name beside it (`.NAME.PID.partial`, as the tools' CSV files
// and output sets are), renamed over it once complete. A run that fails (a full disk) or is cut short leaves the file
// as it was, not one cut short under its own name that the next reader takes for whole.
#pragma once

#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace ph {

// The temporary name beside `path` that a file is written under before it is renamed over it: `.NAME.PID.partial`
// (the tools' CSV files and output sets use it too).
inline std::filesystem::path staged_path(const std::filesystem::path& path) {
  return path.parent_path() / fmt::format(".{}.{}.partial", path.filename().string(), ::getpid());
}

// Calls write(temporary) and renames the temporary over `path`; on any failure removes the temporary and throws
// std::runtime_error naming `path` (a message that named the temporary names `path` instead).
template <typename Write>
void write_staged(const std::filesystem::path& path, Write&& write) {
  const std::filesystem::path staged = staged_path(path);
  try {
    write(staged);
  } catch (const std::exception& e) {
    ::unlink(staged.c_str());
    std::string message = e.what();
    for (std::size_t at = message.find(staged.string()); at != std::string::npos;
         at = message.find(staged.string(), at + path.string().size())) {
      message.replace(at, staged.string().size(), path.string());
    }
    throw std::runtime_error(message);
  }
  if (std::rename(staged.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(staged.c_str());
    throw std::runtime_error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(error)));
  }
}

}  // namespace ph
