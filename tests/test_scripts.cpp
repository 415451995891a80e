// The scripts under scripts/, and the Python tools under tools/, as a user first meets them: `--help` says what
// each does and does nothing else (no package install, no build), and an argument one does not know is refused
// before it installs, builds or reads anything.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/tool_runner.hpp"

#ifndef PH_SCRIPTS_DIR
#error "PH_SCRIPTS_DIR must name the project's scripts folder (tests/CMakeLists.txt)"
#endif
#ifndef PH_PYTHON_TOOLS_DIR
#error "PH_PYTHON_TOOLS_DIR must name the folder of the Python tools (tests/CMakeLists.txt)"
#endif

namespace ph {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> scripts() {
  std::vector<fs::path> found;
  for (const fs::directory_entry& entry : fs::directory_iterator(PH_SCRIPTS_DIR)) {
    if (entry.is_regular_file() && (entry.status().permissions() & fs::perms::owner_exec) != fs::perms::none)
      found.push_back(entry.path());
  }
  return found;
}

// Runs `script` with `args` under a 20 s limit: a script that went on to install, build or boot a VM would
// fail the test (status 124) instead of holding it up.
ToolResult run_script(const fs::path& script, const std::string& args, const ScratchDir& dir) {
  return run_program("timeout", "20 " + quote(script) + " " + args, dir);
}

// The script's header: the comment lines after the #! line, without their "# ".
std::string header_of(const fs::path& script) {
  std::istringstream lines(read_file_text(script));
  std::string line, header;
  std::getline(lines, line);  // #!/usr/bin/env bash
  while (std::getline(lines, line) && line.rfind('#', 0) == 0) {
    line.erase(0, line.rfind("# ", 0) == 0 ? 2 : 1);
    header += line + "\n";
  }
  return header;
}

TEST(Scripts, HelpPrintsTheHeaderAndDoesNothingElse) {
  const std::vector<fs::path> all = scripts();
  ASSERT_GE(all.size(), 10u) << PH_SCRIPTS_DIR;
  for (const fs::path& script : all) {
    SCOPED_TRACE(script.filename().string());
    const ScratchDir dir("scripts");
    const ToolResult r = run_script(script, "--help", dir);
    EXPECT_EQ(r.rc, 0) << r.err;
    const std::string header = header_of(script);
    ASSERT_FALSE(header.empty());
    EXPECT_EQ(r.out.substr(0, header.size()), header);
    EXPECT_EQ(r.err, "");  // no install-deps, no cmake
  }
}

// `scripts/demo` hands its arguments to `pseudohaptic demo`, which refuses unknown ones itself after the build.
TEST(Scripts, UnknownArgumentIsRefusedBeforeAnything) {
  for (const fs::path& script : scripts()) {
    if (script.filename() == "demo") continue;
    SCOPED_TRACE(script.filename().string());
    const ScratchDir dir("scripts");
    const ToolResult r = run_script(script, "--no-such-argument", dir);
    EXPECT_EQ(r.rc, 2) << r.err;
    EXPECT_EQ(r.err.rfind(script.filename().string() + ": unknown argument '--no-such-argument'", 0), 0u) << r.err;
    EXPECT_EQ(r.out, "");
  }
}

// The Python tools (charts, tables, the recording generator) answer --help with a usage line and their purpose,
// and refuse an argument they do not take, rather than reading it as a folder or ignoring it.
TEST(Scripts, PythonToolsAnswerHelpAndRefuseUnknownArguments) {
  std::vector<fs::path> tools;
  for (const fs::directory_entry& entry : fs::directory_iterator(PH_PYTHON_TOOLS_DIR)) {
    if (entry.path().extension() == ".py") tools.push_back(entry.path());
  }
  ASSERT_GE(tools.size(), 5u) << PH_PYTHON_TOOLS_DIR;
  for (const fs::path& tool : tools) {
    SCOPED_TRACE(tool.filename().string());
    const ScratchDir dir("python-tools");
    // Debian's python3-matplotlib is /usr/bin/python3's (scripts/test says why).
    const ToolResult help = run_program("timeout", "60 /usr/bin/python3 " + quote(tool) + " --help", dir);
    EXPECT_EQ(help.rc, 0) << help.err;
    EXPECT_EQ(help.out.rfind("usage: " + tool.filename().string(), 0), 0u) << help.out;
    const ToolResult unknown =
        run_program("timeout", "60 /usr/bin/python3 " + quote(tool) + " --no-such-option a b c", dir);
    EXPECT_EQ(unknown.rc, 2) << unknown.err;
    EXPECT_NE(unknown.err.find("unrecognized arguments"), std::string::npos) << unknown.err;
  }
}

}  // namespace
}  // namespace ph
