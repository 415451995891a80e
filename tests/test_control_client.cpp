// The control socket's client, as `pseudohaptic status` and `cursor` use it, against sockets that misbehave: a
// daemon that takes no connection, a socket that is not a pseudohapticd's, a folder the file system shuts, and the
// daemon's own question to a helper among the replies (docs/SERVICE.md, "The control socket").
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>

#include "common/unique_fd.hpp"
#include "control/client.hpp"
#include "tests/as_nobody.hpp"
#include "tests/scratch_dir.hpp"

namespace ph::control {
namespace {

sockaddr_un address_of(const std::string& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  return address;
}

// A socket listened on at `path` with room for `backlog` waiting connections, none of them accepted.
UniqueFd listening(const std::string& path, int backlog) {
  UniqueFd fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
  const sockaddr_un address = address_of(path);
  EXPECT_EQ(::bind(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address), 0) << path;
  EXPECT_EQ(::listen(fd.get(), backlog), 0);
  return fd;
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const ControlError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ControlError";
  return "";
}

// A daemon that has stopped accepting (hung): once its queue is full a blocking connect waited for ever. The client
// gives up after its time-out and says so.
TEST(ControlClient, ADaemonThatTakesNoConnectionIsGivenUpOn) {
  const ScratchDir dir("control-client");
  const std::string path = (dir / "control").string();
  const UniqueFd daemon = listening(path, 0);
  // Fills the queue (a backlog of 0 leaves room for one).
  const UniqueFd waiting(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  const sockaddr_un address = address_of(path);
  ASSERT_EQ(::connect(waiting.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  const auto start = std::chrono::steady_clock::now();
  const std::string said = error_of([&] { Client client(path, std::chrono::milliseconds(300)); });
  const auto took = std::chrono::steady_clock::now() - start;
  EXPECT_NE(said.find("pseudohapticd at " + path + " takes no connection (its queue is full): is it hung?"),
            std::string::npos)
      << said;
  EXPECT_GE(took, std::chrono::milliseconds(300));
  EXPECT_LT(took, std::chrono::seconds(3));
}

// A socket that answers something else (another program's): said so at once, not waited on as a daemon that does
// not answer. The daemon's `query` to a helper is skipped; the reply after it is the answer.
TEST(ControlClient, AnAnswerThatIsNoReplyIsSaidToBeSo) {
  const ScratchDir dir("control-client");
  const std::string path = (dir / "control").string();
  const UniqueFd server = listening(path, 4);
  std::thread answer([&] {
    for (const char* said : {"hello there\n", "query\nok 1 2\n"}) {
      const UniqueFd peer(::accept(server.get(), nullptr, nullptr));
      char request[64];
      (void)!::read(peer.get(), request, sizeof request);
      (void)!::write(peer.get(), said, std::strlen(said));
    }
  });
  const auto start = std::chrono::steady_clock::now();
  const std::string said = error_of([&] { Client(path).request("status"); });
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
  EXPECT_NE(said.find(path + " answered \"hello there\", which is no reply of pseudohapticd's"), std::string::npos)
      << said;
  Client client(path);
  const Reply reply = client.request("cursor");
  EXPECT_TRUE(reply.ok);
  EXPECT_EQ(reply.text, "1 2");
  answer.join();
}

// The daemon's own rule (root and the active local session's user) is its answer once connected, so a connection
// the file system refuses is a folder's or the socket's mode, and the advice says that.
TEST(ControlClient, PermissionDeniedIsTheFileSystems) {
  const ScratchDir dir("control-client");
  std::filesystem::create_directories(dir / "shut");
  const std::string path = (dir / "shut" / "control").string();
  const UniqueFd server = listening(path, 4);
  std::filesystem::permissions(dir / "shut", std::filesystem::perms::owner_all);
  const int advised = as_nobody([&] {
    try {
      Client client(path);
    } catch (const ControlError& e) {
      const std::string said = e.what();
      return said.find(
                 "Permission denied (the file system's permissions: a folder on the path, or the socket's "
                 "mode") != std::string::npos
                 ? 1
                 : 0;
    }
    return 2;
  });
  EXPECT_EQ(advised, 1);
}

}  // namespace
}  // namespace ph::control
