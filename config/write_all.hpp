// Writes every byte, through short writes and EINTR: what each file or pipe the project writes with write(2) needs.
#pragma once

#include <unistd.h>

#include <cerrno>
#include <cstddef>

namespace ph {

// All `size` bytes of `data` to `fd`; false with errno set (EIO for a write that took nothing) on a failure.
inline bool write_all(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace ph
