// UniqueFd (common/unique_fd.hpp): closes what it owns once, keeps errno when it closes on an error path, and
// returns close(2)'s result where a file's close may fail.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <utility>

#include "common/unique_fd.hpp"

namespace ph {
namespace {

bool is_open(int fd) { return ::fcntl(fd, F_GETFD) != -1; }

TEST(UniqueFd, ClosesWhatItOwnsOnceAndKeepsErrno) {
  int fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  {
    UniqueFd owner(fd);
    UniqueFd moved(std::move(owner));
    EXPECT_FALSE(owner);
    EXPECT_EQ(moved.get(), fd);
  }
  EXPECT_FALSE(is_open(fd));
  // A close that fails (here EBADF: the number no longer open, nothing opened since in this thread) leaves errno as
  // it was, the reason of the error being reported.
  fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  ASSERT_EQ(::close(fd), 0);
  {
    UniqueFd stale(fd);
    errno = ENOSPC;  // as after a failed write, about to be reported
  }
  EXPECT_EQ(errno, ENOSPC);
  UniqueFd stale(fd);
  EXPECT_EQ(stale.close(), -1);  // close() says so
  EXPECT_EQ(errno, EBADF);

  fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  UniqueFd closing(fd);
  EXPECT_EQ(closing.close(), 0);
  EXPECT_FALSE(closing);
  EXPECT_FALSE(is_open(fd));
  EXPECT_EQ(closing.close(), 0);  // nothing left to close
}

}  // namespace
}  // namespace ph
