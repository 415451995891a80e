#include "config/image_child.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>
#include <vector>

namespace ph {
namespace {

namespace fs = std::filesystem;

std::string describe_exit(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::sigabbrev_np(sig);
    return "killed by signal " + std::to_string(sig) + (name != nullptr ? std::string(" (SIG") + name + ")" : "");
  }
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "stopped";
}

// Waits until `fd` is readable or the deadline passes.
bool wait_readable(int fd, std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, POLLIN, 0};
    const int n = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, 60'000)));
    if (n > 0) return true;
    if (n < 0 && errno != EINTR) return false;
  }
}

// Writing to a child that has died raises SIGPIPE, whose default kills the writer: held back while this
// thread writes, and a SIGPIPE that came meanwhile is taken off so that it is never delivered.
class SigpipeHeld {
 public:
  SigpipeHeld() {
    sigemptyset(&pipe_);
    sigaddset(&pipe_, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_, &old_);
  }
  ~SigpipeHeld() {
    const timespec none{};
    while (::sigtimedwait(&pipe_, nullptr, &none) == SIGPIPE) {
    }
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  SigpipeHeld(const SigpipeHeld&) = delete;
  SigpipeHeld& operator=(const SigpipeHeld&) = delete;

 private:
  sigset_t pipe_, old_;
};

}  // namespace

fs::path ImageChild::reader_program() {
  const char* env = std::getenv("PH_IMAGE_READER");
  if (env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = (self.parent_path() / PH_IMAGE_READER_INSTALLED).lexically_normal();
    if (fs::exists(installed, ec)) return installed;
  }
  return PH_IMAGE_READER_BUILT;
}

ImageChild::ImageChild(fs::path reader, std::chrono::milliseconds timeout)
    : program_(std::move(reader)), timeout_(timeout) {}

ImageChild::~ImageChild() { stop(); }

void ImageChild::start() {
  int ends[2];  // daemon -> child (its stdin), child -> daemon (its stdout): each end closes itself
  if (::pipe2(ends, O_CLOEXEC) < 0) throw FieldError(std::string("cannot make a pipe: ") + std::strerror(errno));
  UniqueFd down_read(ends[0]), down_write(ends[1]);
  if (::pipe2(ends, O_CLOEXEC) < 0) throw FieldError(std::string("cannot make a pipe: ") + std::strerror(errno));
  UniqueFd up_read(ends[0]), up_write(ends[1]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, down_read.get(), 0);
  posix_spawn_file_actions_adddup2(&actions, up_write.get(), 1);
  // Nothing else of the daemon's (mice, /dev/uinput, sockets) reaches the child, CLOEXEC or not.
  posix_spawn_file_actions_addclosefrom_np(&actions, 3);
  // The child starts with no signal blocked or ignored (the daemon blocks SIGTERM, SIGINT and SIGHUP).
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &all);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  const std::string program = program_.string();
  char* argv[] = {const_cast<char*>(program.c_str()), nullptr};
  char* envp[] = {nullptr};  // no environment: nothing like LD_PRELOAD comes along
  pid_t pid = -1;
  const int error = ::posix_spawn(&pid, program.c_str(), &actions, &attributes, argv, envp);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (error != 0) throw FieldError("cannot start the image reader " + program + ": " + std::strerror(error));
  pid_ = pid;
  to_child_ = std::move(down_write);  // (the child's ends close here, at the end of the scope)
  from_child_ = std::move(up_read);
}

void ImageChild::stop() {
  if (pid_ < 0) return;
  to_child_.reset();  // the child exits at end of input
  from_child_.reset();
  int status = 0;
  for (int i = 0; i < 200; ++i) {  // 2 s, then it is killed
    const pid_t done = ::waitpid(pid_, &status, WNOHANG);
    if (done == pid_ || (done < 0 && errno != EINTR)) {
      pid_ = -1;
      return;
    }
    ::usleep(10'000);
  }
  ::kill(pid_, SIGKILL);
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

void ImageChild::fail(const std::string& files, const std::string& what, bool kill_now) {
  // The child is of no further use: end it (and learn how it ended, if it ended by itself).
  std::string how;
  if (pid_ >= 0) {
    if (kill_now) ::kill(pid_, SIGKILL);
    to_child_.reset();
    from_child_.reset();
    // A crash is reported a moment after the pipe closes: a process with the image library's mappings
    // takes a while to go, under emulation more so.
    int status = 0;
    pid_t done = 0;
    for (int i = 0; i < 200 && done == 0; ++i) {
      done = ::waitpid(pid_, &status, WNOHANG);
      if (done == 0) ::usleep(10'000);
    }
    if (done == 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
    } else if (done == pid_ && !kill_now) {
      how = " (" + describe_exit(status) + ")";
    }
    pid_ = -1;
  }
  throw FieldError(files + ": the image reader (a child process) " + what + how + "; nothing of it was used");
}

image_wire::Answer ImageChild::ask(const image_wire::Request& request, const std::string& files) {
  if (pid_ < 0) start();
  std::vector<std::byte> bytes;
  try {
    try {
      const SigpipeHeld held;
      image_wire::write_message(to_child_.get(), image_wire::encode(request));
    } catch (const image_wire::WireError&) {
      fail(files, "ended before it took the request", false);  // a broken pipe: the child is gone
    }
    const auto deadline = std::chrono::steady_clock::now() + timeout_;
    if (!wait_readable(from_child_.get(), deadline))
      fail(files, "gave no answer within " + std::to_string(timeout_.count() / 1000) + " s", true);
    if (!image_wire::read_message(from_child_.get(), bytes, deadline))
      fail(files, "ended without an answer while reading it", false);
    image_wire::Answer answer = image_wire::decode_answer(bytes, request);
    if (const auto* failure = std::get_if<image_wire::Failure>(&answer)) throw FieldError(failure->message);
    return answer;
  } catch (const image_wire::WireError& e) {
    fail(files, std::string("sent a wrong answer: ") + e.what(), true);
  }
}

RegionFields ImageChild::load_fields(const FieldSources& sources, std::int32_t width, std::int32_t height,
                                     FieldNeeds needs, FieldLoadReport& report) {
  std::string files;
  for (const auto& path : {sources.normal_map, sources.depth_map}) {
    if (path) files += (files.empty() ? "" : ", ") + path->string();
  }
  image_wire::Answer answer = ask(image_wire::FieldsRequest{sources, width, height, needs}, files);
  auto& fields = std::get<image_wire::FieldsAnswer>(answer);
  report = fields.report;
  return std::move(fields.fields);
}

ImageSize ImageChild::image_size(const fs::path& path) {
  return std::get<ImageSize>(ask(image_wire::SizeRequest{path}, path.string()));
}

}  // namespace ph
