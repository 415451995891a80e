// pseudohaptic: the command-line tool for researchers and for checking scenes.
#include <fmt/core.h>
#include <poll.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <system_error>

#include "tools/commands.hpp"

namespace {

// An error for the user, on standard error. Never throws: where standard error cannot be written either (a full
// disk), the exit status still says it.
void say_error(const std::string& text) {
  std::fputs(("pseudohaptic: " + text + "\n").c_str(), stderr);
  std::fflush(stderr);
}

// Whether standard output is a pipe whose reader has gone (`| head` that has read enough): its writes fail with EPIPE.
bool stdout_reader_gone() {
  pollfd out{1, 0, 0};
  return ::poll(&out, 1, 0) == 1 && (out.revents & POLLERR) != 0;
}

// Ends the process as SIGPIPE would (status 141, no message), once a command has cleaned up after the failed write:
// the tool ignores SIGPIPE so that it may (replay's temporary files), and `| head` must stay quiet all the same.
[[noreturn]] void end_as_sigpipe() {
  std::fflush(stderr);
  std::signal(SIGPIPE, SIG_DFL);
  std::raise(SIGPIPE);
  std::_Exit(141);  // (not reached)
}

// What a command wrote to standard output is buffered: a disk that filled or a reader that went away shows only
// when it is flushed, so the exit status must wait for that.
int with_stdout_flushed(int status) {
  errno = 0;
  if (std::fflush(stdout) == 0 && !std::ferror(stdout)) return status;
  if (stdout_reader_gone()) end_as_sigpipe();
  say_error(std::string("<stdout>: write failed") + (errno != 0 ? std::string(": ") + std::strerror(errno) : ""));
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // A reader that goes away (`| head`) makes a write fail with EPIPE, which the commands clean up after (replay's
  // temporary files) before the process ends as SIGPIPE would have ended it (end_as_sigpipe).
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{
      "pseudohaptic: pseudo-haptic textures for an ordinary mouse.\n"
      "Tools to make test targets, trace the cursor across a texture and compare the methods."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "pseudohaptic 0.1.0");

  std::map<CLI::App*, ph::tools::Run> runs;
  auto add = [&](const char* name, const char* help, ph::tools::Run (*setup)(CLI::App&)) {
    CLI::App* sub = app.add_subcommand(name, help);
    runs[sub] = setup(*sub);
  };
  add("targets", "Write the 24 targets of the curvature paper (normal maps, depth maps, scene files)",
      ph::tools::add_targets_command);
  add("surfaces", "Write the analytic test surfaces of the second paper (normal maps, depth maps, exact K, scenes)",
      ph::tools::add_surfaces_command);
  add("inspect", "Write curvature, curvature classes, isophotes and contours of a texture as false-colour PNGs",
      ph::tools::add_inspect_command);
  add("trace", "Move the cursor along a straight stroke across a texture and write one CSV row per texel step",
      ph::tools::add_trace_command);
  add("replay", "Push a recorded mouse stream through the daemon's pipeline and write what it would emit",
      ph::tools::add_replay_command);
  add("demo", "Print the C/D-ratio range of both methods on each of the 24 targets (the paper's Fig. 5 in numbers)",
      ph::tools::add_demo_command);
  add("accuracy", "Measure speed and accuracy of every engine variant against the exact ground truth (CSV for charts)",
      ph::tools::add_accuracy_command);
  add("study", "Run the curvature paper's user study in silico through the daemon's pipeline (CSV, summary tables)",
      ph::tools::add_study_command);
  add("stability", "Run the failure-mode suite: where each method breaks and how badly (CSV for charts)",
      ph::tools::add_stability_command);
  add("check-config", "Check a scene file (the daemon's config): its [daemon] table, regions and images",
      ph::tools::add_check_config_command);
  add("status", "Ask the running daemon what it does (output, mice, scene, desktop, cursor model, session helper)",
      ph::tools::add_status_command);
  add("cursor", "Print the running daemon's cursor model, or move it with --set X,Y", ph::tools::add_cursor_command);
  add("passthrough", "Hold the daemon's pass-through on while it runs (a game that locks the pointer; Wayland)",
      ph::tools::add_passthrough_command);

  // CLI11 answers a misspelt command, no command, or an option before the command with only "A subcommand is
  // required": say which, and list the commands.
  std::string names;
  bool known = false;
  for (const CLI::App* sub : app.get_subcommands({})) {
    known = known || (argc > 1 && sub->get_name() == argv[1]);
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  const std::string_view first = argc > 1 ? argv[1] : "";
  if (!known && first != "-h" && first != "--help" && first != "--version") {
    if (first.empty()) {
      fmt::print(stderr, "pseudohaptic: give a command: {} (--help explains each)\n", names);
    } else if (first.front() == '-') {
      fmt::print(stderr, "pseudohaptic: unknown option '{}' before the command (commands: {}; --help explains each)\n",
                 first, names);
    } else {
      fmt::print(stderr, "pseudohaptic: unknown command '{}' (commands: {}; --help explains each)\n", first, names);
    }
    return 2;
  }
  try {
    // "--method=" (a variable left empty in a script): CLI11 takes the next argument as its value, or says a value
    // is missing. An empty value is no option's: said as the command line's error, naming the option.
    for (int i = 1; i < argc; ++i) {
      const std::string_view arg = argv[i];
      if (arg == "--") break;
      if (arg.size() > 3 && arg.starts_with("--") && arg.ends_with("=")) {
        throw CLI::ValidationError(std::string(arg.substr(0, arg.size() - 1)),
                                   "an empty value: give one, or leave the option out");
      }
    }
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    for (const auto& [sub, run] : runs) {
      if (sub->parsed()) return with_stdout_flushed(run());
    }
  } catch (const CLI::ParseError& e) {
    // The command line, refused by a command's own check of what CLI11 cannot say (an argument required unless
    // another option is given): exits as CLI11's own refusals do.
    return app.exit(e);
  } catch (const std::filesystem::filesystem_error& e) {
    // libstdc++ says "filesystem error: cannot create directories: Not a directory [out]": the path first, as the
    // tool's other errors name their file.
    std::string what = e.what();
    if (const std::string_view prefix = "filesystem error: "; what.starts_with(prefix)) what.erase(0, prefix.size());
    if (const std::size_t at = what.rfind(" ["); at != std::string::npos && !e.path1().empty()) what.erase(at);
    // An output folder given as a link to nowhere: "File exists" names neither the link nor where it leads.
    std::error_code ignored;
    if (e.code() == std::errc::file_exists && std::filesystem::is_symlink(e.path1(), ignored) &&
        !std::filesystem::exists(e.path1(), ignored)) {
      what = "is a link to " + std::filesystem::read_symlink(e.path1(), ignored).string() + ", which does not exist";
    }
    say_error((e.path1().empty() ? "" : e.path1().string() + ": ") + what);
    return 1;
  } catch (const std::exception& e) {
    // A failed write to standard output whose reader has gone ends as SIGPIPE would: the commands name standard
    // output "<stdout>" in their errors, and fmt's print throws a system_error. Any other error is said, whether or
    // not the reader is still there (`status | head` with no daemon to ask, or a failed send to the daemon).
    const auto* system = dynamic_cast<const std::system_error*>(&e);
    const bool a_write_to_stdout = std::string_view(e.what()).starts_with("<stdout>") ||
                                   (system != nullptr && system->code() == std::errc::broken_pipe);
    if (a_write_to_stdout && stdout_reader_gone()) end_as_sigpipe();
    say_error(e.what());
    return 1;
  }
  return 1;
}
