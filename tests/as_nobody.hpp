// Runs a check as a user without privileges: as nobody (uid and gid 65534) in a child process when the test runs as
// root, who passes every permission check, else in the test's own process. The check returns a small number, which
// comes back through a pipe.
#pragma once

#include <grp.h>
#include <sys/wait.h>
#include <unistd.h>

#include <functional>

namespace ph {

inline int as_nobody(const std::function<int()>& check) {
  if (::getuid() != 0) return check();
  int ends[2];
  if (::pipe(ends) != 0) return -1;
  const pid_t child = ::fork();
  if (child < 0) return -1;
  if (child == 0) {
    ::close(ends[0]);
    int result = -1;
    // Without root's supplementary groups (gid 0 among them): nobody's own only.
    if (::setgroups(0, nullptr) == 0 && ::setgid(65534) == 0 && ::setuid(65534) == 0) {
      try {
        result = check();
      } catch (...) {
      }
    }
    (void)!::write(ends[1], &result, sizeof result);
    ::_exit(0);
  }
  ::close(ends[1]);
  int result = -1;
  (void)!::read(ends[0], &result, sizeof result);
  ::close(ends[0]);
  ::waitpid(child, nullptr, 0);
  return result;
}

}  // namespace ph
