// The manual pages against the programs' own --help: every long option a program lists is named in its page, so
// that neither can gain an option the other does not show.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/unique_fd.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"

namespace {

// What `command` writes to standard output.
std::string output_of(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  std::array<char, 4096> buffer{};
  while (const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  EXPECT_EQ(::pclose(pipe), 0) << command;
  return out;
}

// The long options of CLI11's help: each option line starts with spaces, then "-x," or not, then "--name".
std::vector<std::string> long_options(const std::string& help) {
  std::vector<std::string> options;
  std::size_t at = 0;
  while (at < help.size()) {
    const std::size_t end = std::min(help.find('\n', at), help.size());
    const std::string line = help.substr(at, end - at);
    at = end + 1;
    const std::size_t start = line.find_first_not_of(' ');
    if (start == 0 || start == std::string::npos) continue;
    std::size_t dashes =
        line.compare(start, 1, "-") == 0 && line.compare(start, 2, "--") != 0 ? line.find(',', start) : start;
    if (dashes == std::string::npos) continue;
    if (line[dashes] == ',') ++dashes;
    if (line.compare(dashes, 2, "--") != 0) continue;
    const std::size_t name_end = line.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-", dashes + 2);
    options.push_back(line.substr(dashes, name_end - dashes));
  }
  return options;
}

// As a manual page writes it: roff takes a plain '-' for a hyphen, so options write "\-".
std::string roff(const std::string& option) {
  std::string out;
  for (char c : option) out += c == '-' ? std::string("\\-") : std::string(1, c);
  return out;
}

void expect_page_names_every_option(const char* program, const char* page) {
  const std::vector<std::string> options = long_options(output_of(fmt::format("'{}' --help", program)));
  EXPECT_GE(options.size(), 4u) << program;
  const std::string manual = ph::read_file_text(page);
  for (const std::string& option : options) {
    EXPECT_NE(manual.find(roff(option)), std::string::npos) << page << " does not name " << option;
  }
}

// The commands `pseudohaptic --help` lists under "Subcommands:", one per line, indented by two spaces.
std::vector<std::string> listed_commands(const std::string& help) {
  std::vector<std::string> commands;
  std::size_t at = help.find("Subcommands:");
  while (at < help.size()) {
    const std::size_t end = std::min(help.find('\n', at), help.size());
    const std::string line = help.substr(at, end - at);
    at = end + 1;
    if (line.size() > 2 && line.starts_with("  ") && line[2] != ' ')
      commands.push_back(line.substr(2, line.find(' ', 2) - 2));
  }
  return commands;
}

// Whether a manual names `word` (roff-escaped) between `before` and `after`. The texts are formatted, not added:
// GCC 12 warns of an out-of-bounds copy in `"literal" + std::string + "literal"` at -O2, wrongly.
bool names(const std::string& manual, const char* before, const std::string& word, const char* after) {
  return manual.find(fmt::format("{}{}{}", before, roff(word), after)) != std::string::npos;
}

// Every command has its line in the synopsis and an entry under COMMANDS, and every option of each is named.
TEST(ManPages, TheToolsPageNamesEveryCommandAndItsOptions) {
  const std::string manual = ph::read_file_text(PH_TOOL_MAN_PAGE);
  const std::vector<std::string> commands = listed_commands(output_of(fmt::format("'{}' --help", PH_TOOL_PATH)));
  EXPECT_GE(commands.size(), 10u);
  for (const std::string& command : commands) {
    EXPECT_TRUE(names(manual, "\n.B pseudohaptic ", command, "\n")) << command << ": not in pseudohaptic.1's synopsis";
    // Each entry a tagged paragraph of its own: without its .TP it runs on in the paragraph before.
    EXPECT_TRUE(names(manual, "\n.TP\n.BI \"", command, " ") || names(manual, "\n.TP\n.B ", command, "\n"))
        << command << ": no entry of its own (.TP) in pseudohaptic.1's COMMANDS";
    for (const std::string& option : long_options(output_of(fmt::format("'{}' {} --help", PH_TOOL_PATH, command)))) {
      EXPECT_TRUE(names(manual, "", option, "")) << "pseudohaptic.1 does not name " << command << " " << option;
    }
  }
}

// One version everywhere: the project's (CMakeLists.txt) in each program's --version and in each page's title line.
TEST(ManPages, EveryProgramAndPageCarriesTheProjectsVersion) {
  std::vector<std::pair<std::string, std::string>> programs = {{"pseudohapticd", PH_DAEMON_PATH},
                                                               {"pseudohaptic", PH_TOOL_PATH}};
  std::vector<std::string> pages = {PH_DAEMON_MAN_PAGE, PH_TOOL_MAN_PAGE};
#ifdef PH_SESSION_PATH
  programs.emplace_back("pseudohaptic-session", PH_SESSION_PATH);
  pages.emplace_back(PH_SESSION_MAN_PAGE);
#endif
  for (const auto& [name, path] : programs) {
    EXPECT_EQ(output_of(fmt::format("'{}' --version", path)), fmt::format("{} {}\n", name, PH_PROJECT_VERSION));
  }
  for (const std::string& page : pages) {
    const std::string manual = ph::read_file_text(page);
    const std::string title = manual.substr(0, manual.find('\n'));
    EXPECT_TRUE(title.starts_with(".TH ") &&
                title.find(fmt::format("\"pseudohaptic {}\"", PH_PROJECT_VERSION)) != std::string::npos)
        << page << ": " << title;
  }
}

// pseudohapticd(8): a command-line error exits with 100 to 127 before anything starts. `-c ""` (a drop-in whose
// variable is unset) is one: it used to run the default scene file or the embedded scene without a word.
// Runs `command` (standard error with standard output) under a time limit, since a program that took what it should
// refuse would run until a signal, and expects it to exit as a command-line error does (100 to 127); its output.
std::string expect_command_line_error(const std::string& command) {
  FILE* pipe = ::popen(fmt::format("timeout -s KILL 10 {} </dev/null 2>&1", command).c_str(), "r");
  if (pipe == nullptr) {
    ADD_FAILURE() << "popen failed: " << command;
    return "";
  }
  std::string out;
  std::array<char, 4096> buffer{};
  while (const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) >= 100 && WEXITSTATUS(status) <= 127)
      << command << ": exit status " << status << "\n"
      << out;
  return out;
}

TEST(ManPages, TheDaemonRefusesAnEmptySceneFilePathAsTheCommandLineErrorItIs) {
  // (A daemon that took the empty path would, as root, take the mice.)
  const std::string out = expect_command_line_error(fmt::format("'{}' -c '' --control ''", PH_DAEMON_PATH));
  EXPECT_NE(out.find("--config: an empty path"), std::string::npos) << out;
  EXPECT_EQ(out.find("default scene"), std::string::npos) << out;
}

// pseudohapticd(8): SIGTERM and SIGINT end the daemon, also while its scene loads: it waited for the load (seconds
// for a large image, for ever for a pipe given as the scene file that no one writes), as systemd's stop timeout ran
// out. Also when the
// signal was ignored where the daemon was started (a shell's background job ignores SIGINT): Linux keeps a blocked
// signal pending even when it is ignored, which the daemon's signalfd relies on.
TEST(ManPages, TheDaemonStopsOnSigtermWhileItsSceneLoads) {
  const ph::ScratchDir dir("daemon-pipe");
  const std::string log = (dir / "daemon.log").string();
  for (const int signal : {SIGTERM, SIGINT}) {
    for (const bool ignored_at_start : {false, true}) {
      SCOPED_TRACE(fmt::format("{}{}", ::strsignal(signal), ignored_at_start ? ", ignored where it was started" : ""));
      // A pipe whose writer (this test) never writes nor closes it: the daemon's load reads it as /dev/fd/N and waits.
      int ends[2];
      ASSERT_EQ(::pipe(ends), 0);
      const std::string scene = "/dev/fd/" + std::to_string(ends[0]);
      struct stat pipe_stat {};
      ASSERT_EQ(::fstat(ends[0], &pipe_stat), 0);
      const pid_t daemon = ::fork();
      ASSERT_GE(daemon, 0);
      if (daemon == 0) {
        const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
        ::dup2(out, 1);
        ::dup2(out, 2);
        if (ignored_at_start) ::signal(signal, SIG_IGN);
        ::close(ends[1]);
        ::execl(PH_DAEMON_PATH, PH_DAEMON_PATH, "-c", scene.c_str(), "--control", "", static_cast<char*>(nullptr));
        ::_exit(127);
      }
      ::close(ends[0]);
      // The daemon's load has opened the pipe (past the blocking of its signals, which comes first) once a second
      // descriptor of the daemon's leads to it (the one it was started with is the first; before the exec, the fork's
      // copy of the writer's end, of the same inode, would count); the load then waits for lines that never come.
      const auto opened_twice = [&] {
        int found = 0;
        std::error_code ignored;
        if (!std::filesystem::equivalent(fmt::format("/proc/{}/exe", daemon), PH_DAEMON_PATH, ignored)) return false;
        for (const auto& fd : std::filesystem::directory_iterator(fmt::format("/proc/{}/fd", daemon), ignored)) {
          struct stat st {};
          found +=
              ::stat(fd.path().c_str(), &st) == 0 && st.st_ino == pipe_stat.st_ino && st.st_dev == pipe_stat.st_dev;
        }
        return found >= 2;
      };
      bool opened = false;
      for (int i = 0; i < 1000 && !(opened = opened_twice()); ++i) ::usleep(10'000);
      ASSERT_TRUE(opened) << "the daemon did not open its scene file within 10 s";
      const int writer = ends[1];
      const auto sent = std::chrono::steady_clock::now();
      ::kill(daemon, signal);
      int status = 0;
      pid_t ended = 0;
      while ((ended = ::waitpid(daemon, &status, WNOHANG)) == 0 &&
             std::chrono::steady_clock::now() - sent < std::chrono::seconds(5))
        ::usleep(10'000);
      if (ended == 0) {  // still loading: what the test is for
        ::kill(daemon, SIGKILL);
        ::waitpid(daemon, &status, 0);
      }
      ::close(writer);
      const std::string said = ph::read_file_text(log);
      EXPECT_NE(ended, 0) << "still running 5 s after the signal; it said: " << said;
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "; it said: " << said;
      EXPECT_NE(
          said.find(fmt::format("SIG{} received while the scene loads; stopping", signal == SIGTERM ? "TERM" : "INT")),
          std::string::npos)
          << said;
    }
  }
}

TEST(ManPages, TheDaemonsPageNamesEveryOption) { expect_page_names_every_option(PH_DAEMON_PATH, PH_DAEMON_MAN_PAGE); }

#ifdef PH_SESSION_PATH
// pseudohaptic-session(1): a --control that can never be a socket's path (empty, as an unset variable in the unit
// leaves it, or longer than a socket's path may be) is a command-line error, not a daemon to wait for for ever.
TEST(ManPages, TheSessionHelperRefusesASocketPathThatCannotBeAsTheCommandLineErrorItIs) {
  for (const std::string& path : {std::string(), "/tmp/" + std::string(110, 'a')}) {
    const std::string out = expect_command_line_error(fmt::format("'{}' --control '{}'", PH_SESSION_PATH, path));
    EXPECT_NE(out.find("--control: is "), std::string::npos) << out;
  }
}

// pseudohaptic-session(1): SIGTERM, SIGINT and SIGHUP stop the helper with status 0, also while a display server
// that took the connection never answers (a hung X server, a stale compositor socket): Xlib and libwayland wait for
// it without a time limit, and the helper ended only with SIGKILL. A socket that is listened on but never accepted
// from stands in for such a Wayland compositor (its connect succeeds; the first roundtrip never returns).
TEST(ManPages, TheSessionHelperStopsOnASignalWhileTheDisplayDoesNotAnswer) {
  const ph::ScratchDir dir("mute-display");
  const std::string mute = (dir / "wayland-mute").string(), log = (dir / "helper.log").string();
  const ph::UniqueFd listener(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(mute.size(), sizeof(address.sun_path));
  std::memcpy(address.sun_path, mute.c_str(), mute.size() + 1);
  ASSERT_EQ(::bind(listener.get(), reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  ASSERT_EQ(::listen(listener.get(), 8), 0);
  for (const int signal : {SIGTERM, SIGINT, SIGHUP}) {
    SCOPED_TRACE(::strsignal(signal));
    const pid_t helper = ::fork();
    ASSERT_GE(helper, 0);
    if (helper == 0) {
      const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      ::dup2(out, 1);
      ::dup2(out, 2);
      ::unsetenv("JOURNAL_STREAM");
      ::execl(PH_SESSION_PATH, PH_SESSION_PATH, "--backend", "wayland", "--wayland-display", mute.c_str(), "--control",
              (dir / "no-daemon").c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::usleep(300'000);  // connected by then, and waiting for the compositor's first answer
    ::kill(helper, signal);
    const auto sent = std::chrono::steady_clock::now();
    int status = 0;
    pid_t ended = 0;
    while ((ended = ::waitpid(helper, &status, WNOHANG)) == 0 &&
           std::chrono::steady_clock::now() - sent < std::chrono::seconds(5))
      ::usleep(10'000);
    if (ended == 0) {  // still waiting for the display: what the test is for
      ::kill(helper, SIGKILL);
      ::waitpid(helper, &status, 0);
    }
    const std::string said = ph::read_file_text(log);
    if (said.find("backend is not built") != std::string::npos) GTEST_SKIP() << said;
    EXPECT_NE(ended, 0) << "still running 5 s after the signal; it said: " << said;
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "; it said: " << said;
    EXPECT_NE(said.find(fmt::format("SIG{} while opening the desktop: stopping", ::sigabbrev_np(signal))),
              std::string::npos)
        << said;
  }
}

// A child process of the test, with standard output and error into `log` (or /dev/null) and `env` added to its
// environment; killed at the end of the scope where it is still running.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const std::vector<std::string>& env, const std::string& log = "") {
    pid_ = ::fork();
    if (pid_ != 0) return;
    const int out = ::open(log.empty() ? "/dev/null" : log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(out, 1);
    ::dup2(out, 2);
    for (const std::string& e : env) ::putenv(const_cast<char*>(e.c_str()));
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  ~Child() {
    if (pid_ > 0 && !ended_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  pid_t pid() const { return pid_; }
  // Its wait status once it ends within `limit`; nullopt if it is still running then.
  std::optional<int> wait_for(std::chrono::milliseconds limit) {
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    while (std::chrono::steady_clock::now() - start < limit) {
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        ended_ = true;
        return status;
      }
      ::usleep(10'000);
    }
    return std::nullopt;
  }

 private:
  pid_t pid_ = -1;
  bool ended_ = false;
};

bool program_on_path(const std::string& name) {
  return std::system(("command -v " + name + " >/dev/null 2>&1").c_str()) == 0;
}

// pseudohaptic-session(1): when the X server goes away the helper exits with status 1 and says so in its own log
// (an error, with the journal's priority), not in Xlib's words ("X connection to :N broken"), which carried no
// priority and no name. A real X server: Xwayland on a headless weston.
TEST(ManPages, TheSessionHelperSaysTheXServerWentAway) {
  if (!program_on_path("weston") || !program_on_path("Xwayland")) GTEST_SKIP() << "no weston or Xwayland here";
  const ph::ScratchDir runtime("runtime");
  std::filesystem::permissions(runtime.path(), std::filesystem::perms::owner_all);
  const std::string runtime_env = "XDG_RUNTIME_DIR=" + runtime.path().string();
  Child weston({"weston", "--backend=headless-backend.so", "--socket=ph-wl", "--width=640", "--height=480",
                "--no-config", "--idle-time=0"},
               {runtime_env});
  for (int i = 0; i < 1000 && !std::filesystem::exists(runtime / "ph-wl"); ++i) ::usleep(10'000);
  ASSERT_TRUE(std::filesystem::exists(runtime / "ph-wl")) << "weston did not start";
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const ph::UniqueFd display_read(fds[0]), display_write(fds[1]);
  Child xwayland({"Xwayland", "-noreset", "-displayfd", std::to_string(display_write.get())},
                 {runtime_env, "WAYLAND_DISPLAY=ph-wl"});
  char number[16] = {};
  pollfd wait{display_read.get(), POLLIN, 0};
  ASSERT_EQ(::poll(&wait, 1, 10'000), 1) << "Xwayland gave no display number within 10 s";
  ASSERT_GT(::read(display_read.get(), number, sizeof(number) - 1), 0);
  const std::string display = ":" + std::string(number, std::strcspn(number, "\n"));
  const std::string log = (runtime / "helper.log").string(), stopping_log = (runtime / "stopping.log").string();
  Child helper(
      {PH_SESSION_PATH, "--backend", "x11", "--display", display, "--control", (runtime / "no-daemon").string()},
      {runtime_env}, log);
  // A second helper is told to stop as the server goes (logout): it stops as it was told, status 0, without an
  // error of the server's going when it closes the display.
  Child stopping(
      {PH_SESSION_PATH, "--backend", "x11", "--display", display, "--control", (runtime / "no-daemon").string()},
      {runtime_env}, stopping_log);
  // Connected once it looks for the daemon (after the desktop is open).
  for (const std::string& l : {log, stopping_log}) {
    for (int i = 0; i < 500 && ph::read_file_text(l).find("no pseudohapticd") == std::string::npos; ++i)
      ::usleep(10'000);
  }
  ::kill(stopping.pid(), SIGSTOP);
  ::kill(xwayland.pid(), SIGKILL);
  ::usleep(200'000);
  ::kill(stopping.pid(), SIGTERM);
  ::kill(stopping.pid(), SIGCONT);
  const std::optional<int> stopped = stopping.wait_for(std::chrono::seconds(5));
  const std::string stopping_said = ph::read_file_text(stopping_log);
  ASSERT_TRUE(stopped.has_value()) << stopping_said;
  EXPECT_TRUE(WIFEXITED(*stopped) && WEXITSTATUS(*stopped) == 0) << "status " << *stopped << ": " << stopping_said;
  EXPECT_NE(stopping_said.find("info: stopping"), std::string::npos) << stopping_said;
  EXPECT_EQ(stopping_said.find("went away"), std::string::npos) << stopping_said;
  const std::optional<int> status = helper.wait_for(std::chrono::seconds(5));
  const std::string said = ph::read_file_text(log);
  if (said.find("backend is not built") != std::string::npos) GTEST_SKIP() << said;
  ASSERT_TRUE(status.has_value()) << "still running 5 s after the X server went away; it said: " << said;
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 1) << "status " << *status << "; it said: " << said;
  EXPECT_NE(
      said.find("pseudohaptic-session: error: the X server went away (the connection to " + display + " is broken)"),
      std::string::npos)
      << said;
  EXPECT_EQ(said.find("X connection to"), std::string::npos) << said;
}

TEST(ManPages, TheSessionHelpersPageNamesEveryOption) {
  expect_page_names_every_option(PH_SESSION_PATH, PH_SESSION_MAN_PAGE);
}
#endif

}  // namespace
