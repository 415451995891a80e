// End-to-end tests of the `pseudohaptic` command-line tool (tools/): run the built binary, read what it writes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "config/desktop_geometry.hpp"
#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/map_storage.hpp"
#include "tests/as_nobody.hpp"
#include "tests/csv_table.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/tool_runner.hpp"
#include "tools/csv_file.hpp"
#include "tools/output_folder.hpp"

namespace ph {
namespace {

// check-config's standard error less its warnings of images the service's sandbox hides, which every scene in a
// scratch folder under /tmp gets (PrivateTmp=yes).
std::string without_sandbox_warnings(const std::string& err) {
  std::string kept;
  std::size_t begin = 0;
  while (begin < err.size()) {
    const std::size_t end = std::min(err.find('\n', begin), err.size());
    const std::string_view line(err.data() + begin, end - begin);
    if (line.find("which pseudohapticd.service cannot read") == std::string_view::npos)
      kept.append(line).push_back('\n');
    begin = end + 1;
  }
  return kept;
}

namespace fs = std::filesystem;

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

constexpr std::string_view kHeader = "frame,x,y,texel_x,texel_y,cos_alpha,delta_beta_deg,kmax,kmin,dh,cd,region";
enum Column { kFrame, kX, kY, kTexelX, kTexelY, kCosAlpha, kDeltaBeta, kKmax, kKmin, kDh, kCd, kRegion, kColumns };

struct Csv {
  std::string header;
  std::vector<std::vector<std::string>> rows;

  double number(std::size_t row, Column column) const { return std::stod(rows[row][column]); }
};

Csv parse_trace_csv(const std::string& text) {
  CsvTable table = parse_csv(text);
  return {table.header, std::move(table.rows)};
}

const std::string kBump = "bump-gaussian-h1-r200";
const std::string kHole = "hole-gaussian-h1-r200";

TargetSpec target_named(const std::string& name) {
  for (const TargetSpec& t : all_targets()) {
    if (t.name() == name) return t;
  }
  ADD_FAILURE() << "no target " << name;
  return {};
}

// Runs a trace into a CSV file and reads it back.
Csv trace(const std::string& args, const ScratchDir& dir) {
  const fs::path csv = dir / "trace.csv";
  const ToolResult r = run_tool("trace " + args + " -o " + quote(csv), dir);
  EXPECT_EQ(r.rc, 0) << args << "\n" << r.err;
  Csv parsed = parse_trace_csv(read_text(csv));
  for (const auto& row : parsed.rows) {
    for (const std::string& cell : row) EXPECT_NE(cell, "-0") << args;  // zero is written 0, whatever its sign
  }
  return parsed;
}

enum class Method { curvature, depth };

// One row per texel step across the 500 px target's middle row, with the method's columns filled.
void expect_trace_shape(const Csv& csv, Method method, const std::string& region) {
  EXPECT_EQ(csv.header, kHeader);
  ASSERT_GE(csv.rows.size(), 499u);
  ASSERT_LE(csv.rows.size(), 502u);
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    SCOPED_TRACE("row " + std::to_string(i));
    const auto& row = csv.rows[i];
    ASSERT_EQ(row.size(), static_cast<std::size_t>(kColumns));
    EXPECT_EQ(csv.number(i, kTexelX), static_cast<double>(i));
    EXPECT_EQ(csv.number(i, kTexelY), 250.0);
    EXPECT_NEAR(csv.number(i, kY), 250.0, 1e-9);
    if (i > 0) {
      EXPECT_NEAR(csv.number(i, kX) - csv.number(i - 1, kX), 1.0, 1e-5);
      EXPECT_GE(csv.number(i, kFrame), csv.number(i - 1, kFrame));  // a fast frame crosses several texels
    }
    if (i >= 500) continue;  // past the region: flat outside
    EXPECT_EQ(row[kRegion], region);
    const bool curvature = method == Method::curvature;
    for (Column c : {kCosAlpha, kDeltaBeta, kKmax, kKmin}) EXPECT_EQ(row[c].empty(), !curvature) << row[c];
    EXPECT_EQ(row[kDh].empty(), curvature) << row[kDh];
    EXPECT_FALSE(row[kCd].empty());
  }
}

// On a bump centred at x = 250 with radius 200 the cursor slows down on the way up (C/D > 1) and speeds up on the
// way down (C/D < 1); on a hole the other way round; flat (C/D = 1) around it. Never the wrong way. The depth
// method is strict on every texel of both slopes. The curvature method with Eq. 1's printed sign of delta-beta
// (the default, docs/METHODS.md) clamps kmin or kmax to 1 where the slope eases off or steepens by more than
// about 1 degree per texel, so there C/D is exactly 1: strict on `strict_share` of the texels only.
void expect_cd_profile(const Csv& csv, bool bump, double strict_share) {
  std::size_t up = 0, up_strict = 0, down = 0, down_strict = 0;
  for (std::size_t i = 0; i < std::min<std::size_t>(csv.rows.size(), 500); ++i) {
    const double texel = csv.number(i, kTexelX);
    const double cd = csv.number(i, kCd);
    const bool uphill = bump ? texel < 250 : texel > 250;
    if ((texel >= 60 && texel <= 240) || (texel >= 260 && texel <= 440)) {
      if (uphill) {
        EXPECT_GE(cd, 1.0) << "uphill at texel " << texel;
        ++up;
        up_strict += cd > 1.0;
      } else {
        EXPECT_LE(cd, 1.0) << "downhill at texel " << texel;
        ++down;
        down_strict += cd < 1.0;
      }
    } else if (texel < 45 || texel > 455) {
      // Exactly 1 on exact fields; a 16-bit normal map cannot hold 0 exactly ((0 + 1) / 2 * 65535 = 32767.5 is
      // stored as 32768, read back as 1 / 65535), so its flat texels lean by that much.
      EXPECT_NEAR(cd, 1.0, 1e-4) << "flat at texel " << texel;
    }
  }
  EXPECT_EQ(up, 181u);
  EXPECT_EQ(down, 181u);
  EXPECT_GE(static_cast<double>(up_strict), strict_share * static_cast<double>(up)) << up_strict << " of " << up;
  EXPECT_GE(static_cast<double>(down_strict), strict_share * static_cast<double>(down))
      << down_strict << " of " << down;
}

constexpr double kCurvatureStrict = 0.6;  // 120 to 181 of the 181 texels of a slope of the Gaussian targets
constexpr double kDepthStrict = 1.0;

// The cd columns of two traces of the same stroke agree within `relative` on at least `share` of the rows.
void expect_same_cd(const Csv& a, const Csv& b, double relative, double share) {
  ASSERT_EQ(a.rows.size(), b.rows.size());
  std::size_t close = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    EXPECT_EQ(a.rows[i][kTexelX], b.rows[i][kTexelX]);
    const double ca = a.number(i, kCd), cb = b.number(i, kCd);
    const double error = std::abs(ca - cb) / std::max(std::abs(ca), std::abs(cb));
    worst = std::max(worst, error);
    if (error <= relative) ++close;
  }
  EXPECT_GE(static_cast<double>(close), share * static_cast<double>(a.rows.size()))
      << close << " of " << a.rows.size() << " rows within " << relative << ", worst " << worst;
}

// ---------------------------------------------------------------------------------------------------------------

// Each run of the tool costs a quarter of a second (several under AddressSanitizer), so the tests below run it
// as few times as they can: the whole file stays well under 30 s with the sanitizer.

TEST(Tool, HelpNamesTheCommandsAndEveryTraceFlag) {
  ScratchDir dir;
  const ToolResult top = run_tool("--help", dir);
  EXPECT_EQ(top.rc, 0) << top.err;
  for (std::string_view command : {"targets", "trace", "demo"}) EXPECT_TRUE(contains(top.out, command)) << top.out;

  const ToolResult help = run_tool("trace --help", dir);
  EXPECT_EQ(help.rc, 0) << help.err;
  EXPECT_TRUE(contains(help.out, kHeader)) << help.out;
  for (std::string_view flag : {"--scene",        "--target",
                                "--normal-map",   "--depth-map",
                                "--normal-green", "--normal-encoding",
                                "--depth-zero",   "--relief-px",
                                "--method",       "--kmax-prime",
                                "--kmin-prime",   "--kmax-limits",
                                "--kmin-limits",  "--delta-beta-sign",
                                "--gain",         "--depth-kmax",
                                "--depth-kmin",   "--from",
                                "--to",           "--step",
                                "--speed",        "--rate",
                                "-o,--output"}) {
    EXPECT_TRUE(contains(help.out, std::string(flag) + " ")) << flag << " missing from:\n" << help.out;
  }

  // No command, or an option before it: said, with the list of commands.
  const ToolResult none = run_tool("", dir);
  EXPECT_EQ(none.rc, 2);
  EXPECT_TRUE(contains(none.err, "give a command: targets, surfaces")) << none.err;
  const ToolResult option = run_tool("--step 2 trace", dir);
  EXPECT_EQ(option.rc, 2);
  EXPECT_TRUE(contains(option.err, "unknown option '--step' before the command (commands: targets")) << option.err;
  EXPECT_EQ(run_tool("--version", dir).rc, 0);
  // A misspelt command is named, with the list of commands.
  const ToolResult unknown = run_tool("trcae --step 2", dir);
  EXPECT_EQ(unknown.rc, 2);
  EXPECT_TRUE(contains(unknown.err, "unknown command 'trcae'")) << unknown.err;
  EXPECT_TRUE(contains(unknown.err, "trace")) << unknown.err;
  // An output folder that cannot be made is named first, as a file the tool cannot read is.
  std::ofstream(dir / "a-file") << "not a folder\n";
  const ToolResult file = run_tool("targets " + quote(dir / "a-file"), dir);
  expect_clean_failure(file, {"pseudohaptic: " + (dir / "a-file").string() + ": cannot create directories: "});
  EXPECT_FALSE(contains(file.err, "filesystem error")) << file.err;
}

// Every number flag that no later check covers refuses NaN and infinity with its own name: CLI11's range checks
// let NaN through, and a NaN acceleration speed, Weber fraction or relief scale gave output that meant nothing.
// The check runs as the command line is read, so the files named need not exist and no OUTDIR is made.
TEST(Tool, NumberFlagsRefuseNanAndInfinity) {
  ScratchDir dir;
  const std::string out = quote(dir / "out");
  const std::string map = "--normal-map " + quote(dir / "n.png") + " ";
  struct Flag {
    std::string command, flag;
    bool pair = false;  // takes X,Y or X,Y,Z: the non-finite value comes first
  };
  const Flag flags[] = {
      {"study --small " + out, "--weber"},
      {"study --small " + out, "--bound"},
      {"study --small " + out, "--speedup-weight"},
      {"replay " + quote(dir / "in.evemu") + " " + out, "--speed"},
      {"replay " + quote(dir / "in.evemu") + " " + out, "--mouse-dpi"},
      {"inspect " + map + out, "--planar-curvedness"},
      {"inspect " + map + out, "--parabolic-ratio"},
      {"inspect " + map + out, "--cos-alpha"},
      {"inspect " + map + out, "--light", true},
      {"inspect " + map + out, "--relief-px"},
      {"trace " + map + "-o " + out, "--depth-zero"},
      {"trace " + map + "-o " + out, "--relief-px"},
      {"trace --target " + kBump + " -o " + out, "--kmax-limits", true},
      {"trace --target " + kBump + " -o " + out, "--step"},
      {"trace --target " + kBump + " -o " + out, "--speed"},
      {"trace --target " + kBump + " --speed 100 -o " + out, "--rate"},
      {"replay " + quote(dir / "in.evemu") + " " + out, "--gain"},
      {"trace --target " + kBump + " -o " + out, "--kmin-limits", true},
      {"demo --targets " + out, "--step"},
      {"cursor --socket " + quote(dir / "socket"), "--set", true},
  };
  for (const Flag& f : flags) {
    for (std::string_view value : {"nan", "inf", "-inf"}) {
      const std::string given = std::string(value) + (f.pair ? ",1" : "") + (f.flag == "--light" ? ",1" : "");
      const ToolResult r = run_tool(f.command + " " + f.flag + " " + given, dir);
      SCOPED_TRACE(f.command + " " + f.flag + " " + given);
      expect_clean_failure(r, {f.flag, "must be a finite number"});
      EXPECT_FALSE(fs::exists(dir / "out"));
    }
  }
  // Where the number must also be above 0, 0 says so, not CLI11's range up to DBL_MAX written out.
  const std::vector<std::string> at_zero = {"demo --step 0", "study --small --weber 0 " + out,
                                            "study --small --bound -2 " + out};
  for (const std::string& command : at_zero) {
    const ToolResult r = run_tool(command, dir);
    SCOPED_TRACE(command);
    expect_clean_failure(r, {"must be a finite number > 0"});
    EXPECT_FALSE(contains(r.err, "not in range")) << r.err;
  }
}

// A full disk (/dev/full) under what a command writes: its output is lost, so it must not say success. Before, trace
// to a file or to standard output and demo exited 0 with nothing written; and where standard error was full too,
// the tool aborted.
// A command's output file is whole or as it was: written beside it and renamed over it at the end, so that a run
// that fails (or is cut short) leaves no half-written CSV for the charts to read as a result. A device is written
// through (a rename would replace /dev/null itself).
TEST(Tool, ACsvFileIsReplacedWholeOrNotAtAll) {
  ScratchDir dir;
  const fs::path path = dir / "rows.csv";
  std::ofstream(path) << "old\n";
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  {
    tools::CsvFile dropped(path);
    dropped.write("new, unfinished");
  }  // an error or a failed run: never closed
  EXPECT_EQ(read_text(path), "old\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);  // no temporary file
  {
    tools::CsvFile done(path);
    done.write("new\n");
    done.close();
  }
  EXPECT_EQ(read_text(path), "new\n");
  EXPECT_EQ(fs::status(path).permissions(), fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
  tools::CsvFile null("/dev/null");
  null.write("x\n");
  null.close();
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  // A file its user may not write is not replaced (a rename would, as the folder allows it), as a shell's > would not.
  fs::permissions(dir.path(), fs::perms::all);
  EXPECT_EQ(as_nobody([&] {
              const fs::path locked = dir / "locked.csv";
              std::ofstream(locked) << "kept\n";
              fs::permissions(locked, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
              try {
                tools::CsvFile f(locked);
                return 1;
              } catch (const std::runtime_error& e) {
                const std::string message = e.what();
                if (message.find("cannot open for writing: Permission denied") == std::string::npos) return 2;
              }
              return read_text(locked) == "kept\n" ? 0 : 3;
            }),
            0);
}

// A command's files are replaced as a set: until commit() each is written beside its name, so that a run that fails or
// is cut short while any of them is written leaves all of them as they were, not some of this run's beside an older
// run's (the charts would read them as one run).
TEST(Tool, AnOutputSetIsReplacedWholeOrNotAtAll) {
  ScratchDir dir;
  std::ofstream(dir / "a.csv") << "old a\n";
  std::ofstream(dir / "b.csv") << "old b\n";
  fs::permissions(dir / "a.csv", fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  const auto files_in_dir = [&] { return std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()); };
  {
    tools::OutputSet files(dir.path());
    tools::CsvFile a(files.stage("a.csv"), false);
    a.write("new a\n");
    a.close();
    EXPECT_EQ(read_text(dir / "a.csv"), "old a\n");  // written, not yet in place
    tools::CsvFile b(files.stage("b.csv"), false);
    b.write("new b, unfinished");
  }  // an error while b was written: never committed
  EXPECT_EQ(read_text(dir / "a.csv"), "old a\n");
  EXPECT_EQ(read_text(dir / "b.csv"), "old b\n");
  EXPECT_EQ(files_in_dir(), 2);  // no temporary file
  {
    tools::OutputSet files(dir.path());
    for (const char* name : {"a.csv", "b.csv", "c.csv"}) {
      tools::CsvFile f(files.stage(name), false);
      f.print("new {}\n", name);
      f.close();
    }
    files.commit();
  }
  EXPECT_EQ(read_text(dir / "a.csv"), "new a.csv\n");
  EXPECT_EQ(read_text(dir / "b.csv"), "new b.csv\n");
  EXPECT_EQ(read_text(dir / "c.csv"), "new c.csv\n");
  EXPECT_EQ(fs::status(dir / "a.csv").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);  // the replaced file's mode
  EXPECT_EQ(files_in_dir(), 3);
  // A link is written through, as a CsvFile writes it.
  fs::create_symlink(dir / "c.csv", dir / "link.csv");
  tools::OutputSet files(dir.path());
  EXPECT_EQ(files.stage("link.csv"), dir / "link.csv");
}

TEST(Tool, AWriteThatFailsIsAnErrorNotASuccess) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  ScratchDir dir;
  const std::string tool = quote(std::string(PH_TOOL_PATH));
  auto run = [&](const std::string& args, const std::string& redirect) {
    const int status = std::system((tool + " " + args + " " + redirect).c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  };
  const std::string err = " 2>" + quote(dir / "stderr.txt");
  const std::string trace = "trace --target bump-gaussian-h1-r100";
  EXPECT_EQ(run(trace + " -o /dev/full", ">/dev/null" + err), 1);
  EXPECT_TRUE(contains(read_text(dir / "stderr.txt"), "pseudohaptic: /dev/full: write failed: No space left on device"))
      << read_text(dir / "stderr.txt");
  for (const std::string& args : {trace, std::string("demo --targets ") + quote(dir / "targets")}) {
    EXPECT_EQ(run(args, ">/dev/full" + err), 1) << args;
    EXPECT_TRUE(
        contains(read_text(dir / "stderr.txt"), "pseudohaptic: <stdout>: write failed: No space left on device"))
        << args << ": " << read_text(dir / "stderr.txt");
  }
  EXPECT_EQ(run(trace, ">/dev/full 2>/dev/full"), 1);  // nothing can be said; the status says it, no abort
  EXPECT_EQ(run(trace + " -o " + quote(dir / "no-such-folder" / "t.csv"), ">/dev/null" + err), 1);
  EXPECT_TRUE(contains(read_text(dir / "stderr.txt"), "t.csv: cannot open for writing: No such file or directory"))
      << read_text(dir / "stderr.txt");
  EXPECT_EQ(run(trace, ">/dev/null" + err), 0) << read_text(dir / "stderr.txt");
  // The CSV files of stability and accuracy name the file that could not be written.
  fs::create_directories(dir / "stability");
  fs::create_symlink("/dev/full", dir / "stability" / "stability.csv");
  EXPECT_EQ(run("stability --small --mode jump " + quote(dir / "stability"), ">/dev/null" + err), 1);
  EXPECT_TRUE(contains(read_text(dir / "stderr.txt"), "stability.csv: write failed: No space left on device"))
      << read_text(dir / "stderr.txt");
}

// The tool run with `args`, its standard output a pipe whose reader has gone before anything is written (`| head`
// that has read enough), SIGPIPE's action the default as a shell leaves it: its wait status and standard error.
std::pair<int, std::string> run_with_the_reader_gone(const ScratchDir& dir, const std::vector<std::string>& args) {
  int ends[2];
  if (::pipe(ends) != 0) return {-1, "pipe failed"};
  ::close(ends[0]);
  const std::string err = (dir / "reader-gone-err.txt").string();
  const pid_t child = ::fork();
  if (child == 0) {
    ::dup2(ends[1], 1);
    const int to_err = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(to_err, 2);
    ::signal(SIGPIPE, SIG_DFL);
    std::vector<char*> argv{const_cast<char*>(PH_TOOL_PATH)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(PH_TOOL_PATH, argv.data());
    ::_exit(127);
  }
  ::close(ends[1]);
  int status = -1;
  ::waitpid(child, &status, 0);
  return {status, read_text(err)};
}

// status and cursor take the socket as --socket or, as pseudohapticd and pseudohaptic-session name it, --control;
// without a daemon there the error names the path and says what to check.
TEST(Tool, StatusAndCursorNameTheSocketTheyCouldNotReach) {
  ScratchDir dir;
  const std::string socket = (dir / "no-daemon").string();
  for (std::string_view command : {"status --socket ", "status --control ", "cursor --control "}) {
    SCOPED_TRACE(command);
    expect_clean_failure(run_tool(std::string(command) + quote(socket), dir),
                         {"cannot connect to " + socket, "is pseudohapticd running?"});
  }
  // A path that is there but is no socket is said to be what it is, not a daemon that is down.
  fs::create_directories(dir / "a-folder");
  std::ofstream(dir / "a-file") << "not a socket\n";
  for (const auto& [name, what] : {std::pair{"a-folder", "a folder"}, std::pair{"a-file", "a file"}}) {
    const ToolResult r = run_tool("status --socket " + quote(dir / name), dir);
    expect_clean_failure(r, {"cannot connect to " + (dir / name).string() + ": " + what + ", not a socket"});
    EXPECT_FALSE(contains(r.err, "is pseudohapticd running?")) << r.err;
  }
  // A path no socket can have, and a position the daemon would refuse, are the command line's errors, naming the
  // option (they reached the daemon, or the socket call, and exited 1).
  const ToolResult long_path = run_tool("status --socket /tmp/" + std::string(110, 'a'), dir);
  expect_clean_failure(long_path, {"--socket: is 115 bytes long"});
  EXPECT_EQ(long_path.rc, 105) << long_path.err;
  const ToolResult far = run_tool("cursor --socket " + quote(socket) + " --set 2000000,0", dir);
  expect_clean_failure(far, {"--set"});
  EXPECT_EQ(far.rc, 105) << far.err;
  // Just past the bound: the bound said in full, so that the value is seen to lie outside it.
  const ToolResult just_past = run_tool("cursor --socket " + quote(socket) + " --set 1048577,0", dir);
  expect_clean_failure(just_past, {"--set", "from -1048576 to 1048576, not 1048577"});
  // With no daemon to ask and a reader of its output that has gone (`status | head`), the error is still said: only
  // a failed write to that reader ends the tool quietly, as SIGPIPE would (check-config's own write, which said
  // "<stdout>: write failed", too).
  const auto [status, err] = run_with_the_reader_gone(dir, {"status", "--socket", socket});
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << "status " << status << ": " << err;
  EXPECT_TRUE(contains(err, "cannot connect to " + socket)) << err;
  std::ofstream(dir / "flat.toml") << "[daemon]\noutput = \"relative\"\n";
  const auto [config_status, config_err] =
      run_with_the_reader_gone(dir, {"check-config", (dir / "flat.toml").string()});
  EXPECT_TRUE(WIFSIGNALED(config_status) && WTERMSIG(config_status) == SIGPIPE)
      << "status " << config_status << ": " << config_err;
  EXPECT_EQ(without_sandbox_warnings(config_err), "");
}

TEST(Tool, TraceTargetCurvature) {
  ScratchDir dir;
  const Csv csv = trace("--target " + kBump, dir);
  expect_trace_shape(csv, Method::curvature, kBump);
  expect_cd_profile(csv, true, kCurvatureStrict);
}

TEST(Tool, TraceTargetDepthToStandardOutput) {
  ScratchDir dir;
  const ToolResult r = run_tool("trace --target " + kBump + " --method depth", dir);  // -o - by default
  ASSERT_EQ(r.rc, 0) << r.err;
  const Csv csv = parse_trace_csv(r.out);
  expect_trace_shape(csv, Method::depth, kBump);
  expect_cd_profile(csv, true, kDepthStrict);
  EXPECT_TRUE(contains(r.err, "frames")) << r.err;  // the summary goes to stderr, not into the CSV
}

TEST(Tool, TraceHoleBothMethods) {
  ScratchDir dir;
  const Csv curvature = trace("--target " + kHole, dir);
  expect_trace_shape(curvature, Method::curvature, kHole);
  expect_cd_profile(curvature, false, kCurvatureStrict);
  const Csv depth = trace("--target " + kHole + " --method depth", dir);
  expect_trace_shape(depth, Method::depth, kHole);
  expect_cd_profile(depth, false, kDepthStrict);
}

// The target's files (16-bit maps) traced through a scene file or given as maps give the rows of the exact target.
TEST(Tool, TraceFilesMatchTarget) {
  ScratchDir dir;
  const TargetSpec spec = target_named(kBump);
  const std::vector<fs::path> scenes = write_target_files(dir.path(), {spec});
  ASSERT_EQ(scenes.size(), 1u);
  const TargetFilePaths paths = target_file_paths(dir.path(), spec);
  const std::string depth_options = " --depth-zero 0.5 --relief-px 200";  // as the target's scene file says
  const std::string maps = "--normal-map " + quote(paths.normal_map) + " --depth-map " + quote(paths.depth_map);

  const Csv exact_curvature = trace("--target " + kBump, dir);
  const Csv exact_depth = trace("--target " + kBump + " --method depth", dir);
  {
    SCOPED_TRACE("--scene, curvature");
    const Csv csv = trace("--scene " + quote(scenes[0]), dir);
    expect_trace_shape(csv, Method::curvature, kBump);
    expect_cd_profile(csv, true, kCurvatureStrict);
    expect_same_cd(csv, exact_curvature, 1e-2, 0.95);
  }
  {
    SCOPED_TRACE("--scene, depth");
    const Csv csv = trace("--scene " + quote(scenes[0]) + " --method depth", dir);
    expect_trace_shape(csv, Method::depth, kBump);
    expect_cd_profile(csv, true, kDepthStrict);
    expect_same_cd(csv, exact_depth, 1e-2, 0.95);
  }
  {
    SCOPED_TRACE("--scene whose region's name holds a comma and quotes: one quoted cell");
    std::string text = read_text(scenes[0]);
    const std::string name_line = "name = \"" + kBump + "\"";
    ASSERT_NE(text.find(name_line), std::string::npos) << text;
    text.replace(text.find(name_line), name_line.size(), "name = 'bump, \"big\"'");
    std::ofstream(dir / "named.toml", std::ios::binary) << text;
    const ToolResult r =
        run_tool("trace --scene " + quote(dir / "named.toml") + " -o " + quote(dir / "named.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(read_text(dir / "named.csv"), ",\"bump, \"\"big\"\"\"\n"));
    expect_trace_shape(parse_trace_csv(read_text(dir / "named.csv")), Method::curvature, "bump, \"big\"");
  }
  {
    SCOPED_TRACE("--normal-map --depth-map: curvature unless told otherwise");
    const Csv csv = trace(maps + depth_options, dir);
    expect_trace_shape(csv, Method::curvature, "trace");  // a region from maps is named "trace"
    expect_cd_profile(csv, true, kCurvatureStrict);
    expect_same_cd(csv, exact_curvature, 1e-2, 0.95);
  }
  {
    SCOPED_TRACE("--normal-map --depth-map --method depth");
    const Csv csv = trace(maps + depth_options + " --method depth", dir);
    expect_trace_shape(csv, Method::depth, "trace");
    expect_cd_profile(csv, true, kDepthStrict);
    expect_same_cd(csv, exact_depth, 1e-2, 0.95);
  }
  {
    SCOPED_TRACE("--depth-map alone: the depth method");
    const Csv csv = trace("--depth-map " + quote(paths.depth_map) + depth_options, dir);
    expect_trace_shape(csv, Method::depth, "trace");
    expect_same_cd(csv, exact_depth, 1e-2, 0.95);
  }
}

// "--option=" with nothing after the '=' (a variable left empty in a script) is the command line's error, naming the
// option: CLI11 took the next argument as its value (replay's --method took the recording) or said a value was
// missing.
TEST(Tool, AnEmptyOptionValueIsNamed) {
  ScratchDir dir;
  for (const std::string& command :
       {"replay --method= " + quote(dir / "in.evemu") + " " + quote(dir / "out.evemu"),
        "stability " + quote(dir / "out") + " --small --mode=", "trace --target= -o " + quote(dir / "x.csv")}) {
    SCOPED_TRACE(command);
    const ToolResult r = run_tool(command, dir);
    expect_clean_failure(r, {"an empty value: give one, or leave the option out"});
    EXPECT_EQ(r.rc, 105) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << r.err;
  }
}

TEST(Tool, TraceErrors) {
  ScratchDir dir;
  const std::string out = " -o " + quote(dir / "x.csv");
  {
    SCOPED_TRACE("no texture");
    expect_clean_failure(run_tool("trace" + out, dir), {"--scene", "--target", "--normal-map"});
  }
  {
    SCOPED_TRACE("two textures");
    expect_clean_failure(run_tool("trace --target " + kBump + " --depth-map " + quote(dir / "a.png") + out, dir),
                         {"exactly one"});
  }
  {
    SCOPED_TRACE("an empty target name: said of --target, not taken for no texture");
    const ToolResult r = run_tool("trace --target ''" + out, dir);
    expect_clean_failure(r, {"--target: is empty: give a target's name"});
    EXPECT_FALSE(contains(r.err, "exactly one")) << r.err;
  }
  {
    SCOPED_TRACE("missing files");
    expect_clean_failure(run_tool("trace --scene " + quote(dir / "nope.toml") + out, dir), {"nope.toml"});
    expect_clean_failure(run_tool("trace --normal-map " + quote(dir / "nope.png") + out, dir), {"nope.png"});
    expect_clean_failure(run_tool("trace --target bump-square-h1-r200" + out, dir), {"bump-square-h1-r200"});
  }
  {
    SCOPED_TRACE("bad --method");
    expect_clean_failure(run_tool("trace --target " + kBump + " --method bogus" + out, dir),
                         {"--method", "bogus", "curvature", "depth"});
  }
  {
    SCOPED_TRACE("bad --step, --speed, --rate, --from, --to: each named");
    expect_clean_failure(run_tool("trace --target " + kBump + " --step -1" + out, dir),
                         {"--step: must be a finite number > 0"});
    expect_clean_failure(run_tool("trace --target " + kBump + " --speed 0" + out, dir),
                         {"--speed: must be a finite number > 0"});
    expect_clean_failure(run_tool("trace --target " + kBump + " --speed 100 --rate 0" + out, dir),
                         {"--rate: must be a finite number > 0"});
    expect_clean_failure(run_tool("trace --target " + kBump + " --from nan,3" + out, dir),
                         {"--from: X and Y must be finite numbers"});
    expect_clean_failure(run_tool("trace --target " + kBump + " --to 3,inf" + out, dir),
                         {"--to: X and Y must be finite numbers"});
  }
  {
    SCOPED_TRACE("a map's decoding flag without a map");
    expect_clean_failure(run_tool("trace --target " + kBump + " --relief-px 50" + out, dir),
                         {"--relief-px applies to --normal-map/--depth-map only", "a target's fields are exact"});
    const fs::path scene = dir / "flat.toml";
    std::ofstream(scene) << "[[region]]\nwidth = 20\nheight = 20\nmethod = \"none\"\n";
    expect_clean_failure(
        run_tool("trace --scene " + quote(scene) + " --normal-green directx" + out, dir),
        {"--normal-green applies to --normal-map/--depth-map only", "a scene file sets it per region"});
  }
  {
    SCOPED_TRACE("bad scene file");
    const fs::path scene = dir / "bad.toml";
    std::ofstream(scene) << "[[region]]\nwidth = 20\nheight = 20\nnormal_map = \"n.png\"\nnormal_green = \"up\"\n";
    expect_clean_failure(run_tool("trace --scene " + quote(scene) + out, dir),
                         {scene.string() + ":5:", "region[0].normal_green"});
  }
}

// A region too large for the memory the process may have is said with the region and its size, as any load error,
// not as "std::bad_alloc" alone.
TEST(Tool, ARegionTooLargeForTheMemoryIsNamed) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit this test sets";
#endif
  ScratchDir dir;
  write_normal_png16(dir / "n.png", NormalImage(8, 8));
  std::ofstream(dir / "huge.toml")
      << "[[region]]\nname = \"huge\"\nwidth = 8192\nheight = 8192\nnormal_map = \"n.png\"\n";
  // 1 GB of address space: the largest region a scene may have needs more to be read.
  const std::string limited =
      "ulimit -v 1000000 && exec " + quote(std::string(PH_TOOL_PATH)) + " check-config " + quote(dir / "huge.toml");
  const ToolResult r = run_program("/bin/sh", "-c " + quote(limited), dir);
  // Said by the image reader, which check-config reads through as the daemon does, under the tighter limit it was
  // started under (its own 8 GiB would not be raised past it, nor complained about).
  expect_clean_failure(r, {(dir / "huge.toml").string() + ":1: region 'huge': not enough memory to read it",
                           "exceeds the 976 MiB the image reader may use", "make the region smaller"});
  EXPECT_FALSE(contains(r.err, "bad_alloc")) << r.err;
  EXPECT_FALSE(contains(r.err, "setrlimit")) << r.err;
}

// check-config reads the images through the daemon's image reader, not in its own process: a reader that crashes
// fails the check as it fails the service's load, naming the file.
TEST(Tool, CheckConfigReadsTheImagesAsTheDaemonDoes) {
  ScratchDir dir;
  write_normal_png16(dir / "n.png", NormalImage(8, 8));
  std::ofstream(dir / "scene.toml") << "[[region]]\nname = \"r\"\nwidth = 8\nheight = 8\nnormal_map = \"n.png\"\n";
  std::ofstream(dir / "reader") << "#!/bin/sh\nkill -SEGV $$\n";
  fs::permissions(dir / "reader", fs::perms::owner_all);
  const ToolResult r = run_program("/usr/bin/env",
                                   "PH_IMAGE_READER=" + quote(dir / "reader") + " " + quote(std::string(PH_TOOL_PATH)) +
                                       " check-config " + quote(dir / "scene.toml"),
                                   dir);
  expect_clean_failure(r, {(dir / "n.png").string(), "the image reader (a child process)", "SIGSEGV"});
  // With the real reader, the same file passes.
  const ToolResult fine = run_tool("check-config " + quote(dir / "scene.toml"), dir);
  EXPECT_EQ(fine.rc, 0) << fine.err;
}

// An option that would change nothing in the trace asked for is refused, naming it and what would use it.
TEST(Tool, TraceRefusesAnOptionNoTracedMethodReads) {
  ScratchDir dir;
  const std::string out = " -o " + quote(dir / "x.csv");
  expect_clean_failure(run_tool("trace --target " + kBump + " --gain 5" + out, dir),
                       {"--gain is an option of the depth method", "they use curvature", "--method depth"});
  expect_clean_failure(run_tool("trace --target " + kBump + " --method depth --kmax-limits 1,8" + out, dir),
                       {"--kmax-limits is an option of the curvature method", "they use depth"});
  expect_clean_failure(run_tool("trace --target " + kBump + " --method hybrid --kmax-prime 6" + out, dir),
                       {"--kmax-prime", "the hybrid method runs it with its default parameters"});
  expect_clean_failure(run_tool("trace --target " + kBump + " --rate 250" + out, dir), {"--rate applies to --speed"});
  EXPECT_FALSE(fs::exists(dir / "x.csv"));
  // Where the method traced is the option's, its options are taken.
  const ToolResult both = run_tool("trace --target " + kBump + " --method depth --gain 5 --depth-kmax 3" + out, dir);
  EXPECT_EQ(both.rc, 0) << both.err;
  // So with a map's decoding options: --relief-px with only a normal map changed nothing.
  fs::remove(dir / "x.csv");
  ASSERT_EQ(run_tool("surfaces --size 16 " + quote(dir / "m"), dir).rc, 0);
  expect_clean_failure(
      run_tool("trace --normal-map " + quote(dir / "m" / "cone.normal.png") + " --relief-px 3" + out, dir),
      {"--relief-px says how to decode a depth map: give --depth-map, or leave it out"});
  EXPECT_FALSE(fs::exists(dir / "x.csv"));
}

// A frame that ends exactly on a region's edge enters its first texel at the start of the next frame: that texel has
// its row, and the stroke is not said to cross no region. Before, the row was left out, and a 1 px region's stroke
// read "C/D range [0.8, 1]" beside "crosses no region, so its C/D is 1 throughout".
TEST(Tool, TraceHasARowForATexelEnteredAtAFrameBoundary) {
  ScratchDir dir;
  ASSERT_EQ(run_tool("surfaces --size 16 " + quote(dir / "m"), dir).rc, 0);
  std::ofstream(dir / "m" / "s.toml")
      << "[[region]]\nname = \"cone\"\nx = 10\ny = 0\nwidth = 16\nheight = 16\nnormal_map = \"cone.normal.png\"\n";
  for (const std::string from : {"0,8.5", "0.5,8.5"}) {
    SCOPED_TRACE(from);
    const ToolResult r = run_tool(
        "trace --scene " + quote(dir / "m" / "s.toml") + " --from " + from + " --to 40,8.5 -o " + quote(dir / "t.csv"),
        dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_FALSE(contains(r.err, "crosses no region")) << r.err;
    const Csv csv = parse_trace_csv(read_text(dir / "t.csv"));
    ASSERT_EQ(csv.rows.size(), 16u);  // one per texel of the row, from the first
    EXPECT_EQ(csv.rows.front()[kTexelX], "10");
    EXPECT_EQ(csv.rows.back()[kTexelX], "25");
  }
}

// A stroke that meets no region is traced (C/D 1 throughout) with a warning; one that would take more frames than a
// stroke may is refused before a row is written.
TEST(Tool, TraceSaysWhenTheStrokeMissesEveryRegionOrIsTooLong) {
  ScratchDir dir;
  const ToolResult missed =
      run_tool("trace --target " + kBump + " --from 600,600 --to 700,600 -o " + quote(dir / "m.csv"), dir);
  ASSERT_EQ(missed.rc, 0) << missed.err;
  EXPECT_TRUE(contains(missed.err, "warning: the stroke from (600, 600) to (700, 600) crosses no region"))
      << missed.err;
  EXPECT_TRUE(contains(missed.err, "'" + kBump + "' covers (0, 0) to (500, 500)")) << missed.err;
  EXPECT_TRUE(contains(missed.err, "C/D range [1, 1]")) << missed.err;
  EXPECT_TRUE(parse_trace_csv(read_text(dir / "m.csv")).rows.empty());  // no texel of any region stepped on
  const ToolResult crossed = run_tool("trace --target " + kBump + " -o " + quote(dir / "c.csv"), dir);
  ASSERT_EQ(crossed.rc, 0) << crossed.err;
  EXPECT_FALSE(contains(crossed.err, "crosses no region")) << crossed.err;

  expect_clean_failure(run_tool("trace --target " + kBump + " --step 1e-5 -o " + quote(dir / "s.csv"), dir),
                       {"5e+07 frames", "more than the 10000000 a stroke may take", "a larger --step"});
  expect_clean_failure(run_tool("trace --target " + kBump + " --speed 1 --rate 1e5 -o " + quote(dir / "s.csv"), dir),
                       {"a larger --speed or a smaller --rate"});
  EXPECT_FALSE(fs::exists(dir / "s.csv"));
  // A stroke that fits the frames at C/D 1 but not at its C/D: stopped short, a failed run that leaves the file as it
  // was (it had replaced it with the rows so far).
  std::ofstream(dir / "kept.csv") << "old\n";
  const ToolResult short_of_it =
      run_tool("trace --target bump-linear-h1-r100 --step 0.0000526 -o " + quote(dir / "kept.csv"), dir);
  expect_clean_failure(short_of_it, {"stopped after 10000000 frames", "kept.csv is left as it was", "a larger --step"});
  EXPECT_EQ(read_text(dir / "kept.csv"), "old\n");
  // A start past the bounds the cursor model keeps to: refused, not moved in silence.
  expect_clean_failure(run_tool("trace --target " + kBump + " --from 5e9,250 --to 0,250 --step 1e3", dir),
                       {"--from: X and Y must be within ±1e+09 px"});
}

// An empty path, and a negative or overlong seed, are turned down by the command line, naming the argument.
TEST(Tool, EmptyPathsAndNegativeSeedsAreRefused) {
  ScratchDir dir;
  for (const std::string& args : std::initializer_list<std::string>{
           "targets ''", "surfaces ''", "accuracy '' --small", "stability '' --small", "study ''", "inspect ''",
           "check-config ''", "replay '' out.evemu", "replay in.evemu ''", "trace --target " + kBump + " -o ''",
           "trace --scene ''", "status --socket ''"}) {
    SCOPED_TRACE(args);
    const ToolResult r = run_tool(args, dir);
    expect_clean_failure(r, {"is empty: give a path"});
  }
  for (const std::string& seed : std::initializer_list<std::string>{"-1", "18446744073709551616", "1.5", "0x10"}) {
    SCOPED_TRACE(seed);
    expect_clean_failure(run_tool("study " + quote(dir / "s") + " --small --seed " + seed, dir),
                         {"--seed: must be a whole number from 0 to 18446744073709551615, not " + seed});
  }
  EXPECT_FALSE(fs::exists(dir / "s"));
}

// CLI11 reads a whole number with a leading 0 as octal and 0x as hex: --seed 010 ran seed 8, --size 09 was "not in
// range 8 to 8192", and --size W,H of 010,012 gave 8 x 10 texels. The tool reads them in decimal.
TEST(Tool, WholeNumbersAreReadInDecimal) {
  ScratchDir dir;
  const ToolResult study = run_tool("study --small --technique none --seed 010 " + quote(dir / "s"), dir);
  ASSERT_EQ(study.rc, 0) << study.err;
  EXPECT_TRUE(contains(read_text(dir / "s" / "summary.md"), "seed 10,")) << read_text(dir / "s" / "summary.md");

  const ToolResult surfaces = run_tool("surfaces --size 09 " + quote(dir / "m"), dir);
  ASSERT_EQ(surfaces.rc, 0) << surfaces.err;
  EXPECT_EQ(read_image(dir / "m" / "sphere.normal.png").width, 9);

  const ToolResult inspect = run_tool("inspect --normal-map " + quote(dir / "m" / "sphere.normal.png") +
                                          " --size 010,012 --radius 010 " + quote(dir / "i"),
                                      dir);
  ASSERT_EQ(inspect.rc, 0) << inspect.err;
  EXPECT_TRUE(contains(inspect.out, "10 x 12 texels")) << inspect.out;
  EXPECT_TRUE(contains(inspect.out, "filter radius 10")) << inspect.out;

  expect_clean_failure(run_tool("study --small --participants 0x10 " + quote(dir / "p"), dir),
                       {"--participants: must be a whole number from 2 to 100000, not 0x10"});
  expect_clean_failure(run_tool("inspect --normal-map x.png --size 0x10,8 " + quote(dir / "p"), dir),
                       {"--size", "expected W,H"});
  EXPECT_FALSE(fs::exists(dir / "p"));
}

// How many times `part` occurs in `text`.
std::size_t occurrences(const std::string& text, std::string_view part) {
  std::size_t n = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + part.size())) ++n;
  return n;
}

// A map the tool cannot use reads "pseudohaptic: FILE: what went wrong", the file named once, no scene file line.
TEST(Tool, TraceMapErrorsNameTheFileOnce) {
  ScratchDir dir;
  const std::string out = " -o " + quote(dir / "x.csv");
  const fs::path grey = dir / "grey.png";
  write_gray_png16(grey, Grid<float>(8, 8, 0.5f));
  const fs::path rgb = dir / "rgb.png";
  write_normal_png16(rgb, NormalImage(8, 8));
  const fs::path missing = dir / "missing.png";
  struct Case {
    std::string args;
    fs::path file;
    std::string says;
  };
  for (const Case& c :
       {Case{"--normal-map " + quote(grey), grey, "a normal map needs 3 (RGB) or 4 (RGBA) channels"},
        Case{"--depth-map " + quote(rgb), rgb, "a depth map needs 1 channel"},
        Case{"--normal-map " + quote(rgb) + " --depth-map " + quote(rgb) + " --method depth", rgb, "1 channel"},
        Case{"--normal-map " + quote(missing), missing, "cannot open"}}) {
    SCOPED_TRACE(c.args);
    const ToolResult r = run_tool("trace " + c.args + out, dir);
    expect_clean_failure(r, {c.says});
    EXPECT_EQ(r.err.rfind("pseudohaptic: " + c.file.string() + ": ", 0), 0u) << r.err;
    EXPECT_EQ(occurrences(r.err, c.file.string() + ":"), 1u) << r.err;  // OpenImageIO's own words may quote it
    EXPECT_FALSE(contains(r.err, ":0:")) << r.err;
    EXPECT_FALSE(contains(r.err, "region")) << r.err;
  }
}

// Invalid texels are counted and reported at load (docs/METHODS.md, "Screen, regions and fields"); trace warns
// on stderr, per map.
TEST(Tool, TraceWarnsOfInvalidTexels) {
  ScratchDir dir;
  NormalImage holes(4, 4);  // flat, with 3 texels facing away from the viewer
  holes.at(0, 0) = {0.0f, 0.0f, -1.0f};
  holes.at(2, 1) = {0.6f, 0.0f, -0.8f};
  holes.at(3, 3) = {0.0f, 0.0f, -1.0f};
  const fs::path map = dir / "holes.png";
  write_normal_png16(map, holes);
  const std::string warning = "pseudohaptic: warning: ";
  const std::string what = "normal map " + map.string() + ": 3 of 16 texels invalid";
  {
    SCOPED_TRACE("--normal-map");
    const ToolResult r = run_tool("trace --normal-map " + quote(map) + " -o " + quote(dir / "a.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, warning + what)) << r.err;
    EXPECT_EQ(occurrences(r.err, "warning"), 1u) << r.err;
    // Repaired from their flat neighbours: the stroke is flat all along.
    const Csv csv = parse_trace_csv(read_text(dir / "a.csv"));
    ASSERT_EQ(csv.rows.size(), 4u);
    for (std::size_t i = 0; i < csv.rows.size(); ++i) EXPECT_EQ(csv.rows[i][kCd], "1");
  }
  {
    SCOPED_TRACE("--scene");
    const fs::path scene = dir / "scene.toml";
    write_normal_png16(dir / "clean.png", NormalImage(4, 4));
    std::ofstream(scene) << "[[region]]\nname = \"clean\"\nwidth = 4\nheight = 4\nnormal_map = \"clean.png\"\n\n"
                            "[[region]]\nname = \"holes\"\nx = 10\nwidth = 8\nheight = 8\nnormal_map = \"holes.png\"\n";
    const ToolResult r = run_tool("trace --scene " + quote(scene) + " -o " + quote(dir / "b.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, warning + scene.string() + ":7: region 'holes': " + what)) << r.err;
    EXPECT_EQ(occurrences(r.err, "warning"), 1u) << r.err;  // nothing for the clean region
  }
  {
    SCOPED_TRACE("clean map");
    const ToolResult r =
        run_tool("trace --normal-map " + quote(dir / "clean.png") + " -o " + quote(dir / "c.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_FALSE(contains(r.err, "warning")) << r.err;
  }
}

// A flat texel's cos alpha is a signed zero in the arithmetic (-0 on a stroke to the right); the CSV says 0.
// (Every trace() above and below also checks that no cell reads -0.)
TEST(Tool, TraceWritesNoNegativeZero) {
  ScratchDir dir;
  const Csv csv = trace("--target " + kBump, dir);
  ASSERT_EQ(csv.rows.size(), 500u);
  std::size_t zeros = 0;
  for (const auto& row : csv.rows) zeros += row[kCosAlpha] == "0";
  EXPECT_GT(zeros, 80u);  // the flat ends of the target
}

// --speed (with --rate) is a motor step of speed / rate px per frame; the last frame is shortened so that even a
// huge step ends the stroke at --to.
TEST(Tool, TraceSpeedAndRate) {
  ScratchDir dir;
  const Csv step8 = trace("--target " + kBump + " --step 8", dir);
  const Csv step4 = trace("--target " + kBump + " --step 4", dir);
  EXPECT_EQ(trace("--target " + kBump + " --speed 1000", dir).rows, step8.rows);  // default rate 125 Hz
  EXPECT_EQ(trace("--target " + kBump + " --speed 1000 --rate 250", dir).rows, step4.rows);
  // On the flat start (C/D 1) a frame crosses `step` texels: texel k is entered in frame k / step.
  for (std::size_t k = 0; k < 40; ++k) {
    EXPECT_EQ(step8.number(k, kFrame), static_cast<double>(k / 8)) << k;
    EXPECT_EQ(step4.number(k, kFrame), static_cast<double>(k / 4)) << k;
  }
  EXPECT_GT(step4.number(step4.rows.size() - 1, kFrame), step8.number(step8.rows.size() - 1, kFrame));

  {
    SCOPED_TRACE("--speed 1e9: one frame of 8e6 px, stopped at --to");
    const ToolResult r = run_tool("trace --target " + kBump + " --speed 1e9 -o " + quote(dir / "f.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "1 frames, cursor ended at (500.000, 250.000)")) << r.err;
    EXPECT_FALSE(contains(r.err, "stopped before")) << r.err;
    const Csv csv = parse_trace_csv(read_text(dir / "f.csv"));
    ASSERT_EQ(csv.rows.size(), 500u);  // texels 0 to 499, nothing past --to
    EXPECT_EQ(csv.number(499, kTexelX), 499.0);
    for (std::size_t i = 0; i < csv.rows.size(); ++i) EXPECT_EQ(csv.number(i, kFrame), 0.0);
  }
  {
    SCOPED_TRACE("--step past a --to inside a texel");
    const ToolResult r = run_tool(
        "trace --target " + kBump + " --from 10.5,20.5 --to 30.25,20.5 --step 7 -o " + quote(dir / "g.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "3 frames, cursor ended at (30.250, 20.500)")) << r.err;
    const Csv csv = parse_trace_csv(read_text(dir / "g.csv"));
    ASSERT_FALSE(csv.rows.empty());
    EXPECT_EQ(csv.rows.back()[kTexelX], "30");
  }
}

// With --speed and --rate the frames are timed, so a material's damping reads the hand's speed: 600 px/s at k 0.002
// is C/D 2.2 at any rate. Before, trace frames had no time and damping took its 8 ms fallback interval: at 1000 Hz
// the 0.6 px frames read as 75 px/s (C/D 1.15).
TEST(Tool, TraceTimesItsFramesForDamping) {
  ScratchDir dir;
  ASSERT_EQ(run_tool("surfaces --size 32 " + quote(dir / "m"), dir).rc, 0);
  std::ofstream(dir / "m" / "damped.toml")
      << "[[region]]\nname = \"damped\"\nwidth = 32\nheight = 32\nmethod = \"none\"\n"
         "depth_map = \"sphere.depth.png\"\ndepth_zero = 0.5\nrelief_px = 4\n"
         "[region.materials]\nplanar_curvedness = 0\nparabolic_ratio = 1\nelliptic = \"damping\"\n"
         "hyperbolic = \"damping\"\nparabolic = \"damping\"\nplanar = \"damping\"\n"
         "[region.materials.damping]\nk = 0.002\ncd_max = 20\n";
  for (const std::string rate : {"125", "1000"}) {
    SCOPED_TRACE(rate);
    const ToolResult r =
        run_tool("trace --scene " + quote(dir / "m" / "damped.toml") +
                     " --from 0,16.5 --to 32,16.5 --speed 600 --rate " + rate + " -o " + quote(dir / "t.csv"),
                 dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, ", 2.2]")) << r.err;  // the C/D range's top: every whole frame's
  }
}

// --from and --to set the stroke: its texels, in order, and where the cursor stops.
TEST(Tool, TraceFromTo) {
  ScratchDir dir;
  {
    SCOPED_TRACE("part of the middle row");
    const ToolResult r =
        run_tool("trace --target " + kBump + " --from 100,250 --to 400,250 -o " + quote(dir / "a.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "cursor ended at (400.000, 250.000)")) << r.err;
    const Csv csv = parse_trace_csv(read_text(dir / "a.csv"));
    ASSERT_EQ(csv.rows.size(), 300u);
    for (std::size_t i = 0; i < csv.rows.size(); ++i) {
      EXPECT_EQ(csv.number(i, kTexelX), 100.0 + static_cast<double>(i));
      EXPECT_EQ(csv.number(i, kTexelY), 250.0);
    }
    EXPECT_EQ(csv.number(0, kX), 100.0);
  }
  {
    SCOPED_TRACE("upward along a column, across the whole bump");
    const ToolResult r =
        run_tool("trace --target " + kBump + " --from 250.5,490.5 --to 250.5,10.5 -o " + quote(dir / "b.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "cursor ended at (250.500, 10.500)")) << r.err;
    const Csv csv = parse_trace_csv(read_text(dir / "b.csv"));
    ASSERT_EQ(csv.rows.size(), 481u);
    double cd_max = 0.0, cd_min = 10.0;
    for (std::size_t i = 0; i < csv.rows.size(); ++i) {
      EXPECT_EQ(csv.number(i, kTexelX), 250.0);
      EXPECT_EQ(csv.number(i, kTexelY), 490.0 - static_cast<double>(i));
      EXPECT_EQ(csv.number(i, kX), 250.5);
      cd_max = std::max(cd_max, csv.number(i, kCd));
      cd_min = std::min(cd_min, csv.number(i, kCd));
    }
    EXPECT_GT(cd_max, 1.5);  // up the bump from below, then down: as along the row
    EXPECT_LT(cd_min, 0.8);
  }
  {
    SCOPED_TRACE("diagonal");
    const ToolResult r =
        run_tool("trace --target " + kBump + " --from 0,0 --to 300,300 -o " + quote(dir / "c.csv"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "cursor ended at (300.000, 300.000)")) << r.err;
    const Csv csv = parse_trace_csv(read_text(dir / "c.csv"));
    ASSERT_GE(csv.rows.size(), 599u);  // a diagonal crosses two texel boundaries per px, corners once
    for (std::size_t i = 0; i < csv.rows.size(); ++i) {
      EXPECT_NEAR(csv.number(i, kX), csv.number(i, kY), 1e-5);
      EXPECT_LE(csv.number(i, kTexelX), 299.0);
      EXPECT_LE(csv.number(i, kTexelY), 299.0);
    }
  }
  expect_clean_failure(run_tool("trace --target " + kBump + " --from 3,4 --to 3,4", dir), {"no length"});
}

// An error found before the first row (a stroke of no length) leaves the output as it was: an earlier trace is not
// truncated to nothing.
TEST(Tool, TraceErrorBeforeAnyRowLeavesTheOutputAsItWas) {
  ScratchDir dir;
  const fs::path csv = dir / "x.csv";
  ASSERT_EQ(run_tool("trace --target " + kBump + " -o " + quote(csv), dir).rc, 0);
  const std::string earlier = read_text(csv);
  ASSERT_FALSE(earlier.empty());
  expect_clean_failure(run_tool("trace --target " + kBump + " --from 10,10 --to 10,10 -o " + quote(csv), dir),
                       {"the stroke has no length"});
  EXPECT_EQ(read_text(csv), earlier);
  expect_clean_failure(
      run_tool("trace --target " + kBump + " --from 10,10 --to 10,10 -o " + quote(dir / "new.csv"), dir),
      {"the stroke has no length"});
  EXPECT_FALSE(fs::exists(dir / "new.csv"));
}

// -o naming a file the trace reads (the scene file, a map it names, a map given as a flag; by another spelling or
// through a link) is refused before anything is read or written, as replay refuses it.
TEST(Tool, TraceRefusesToWriteOverItsInput) {
  ScratchDir dir;
  const TargetSpec spec = target_named(kBump);
  const std::vector<fs::path> scenes = write_target_files(dir.path(), {spec});
  ASSERT_EQ(scenes.size(), 1u);
  const TargetFilePaths paths = target_file_paths(dir.path(), spec);
  fs::create_symlink(scenes[0], dir / "link.toml");
  const std::string scene = "--scene " + quote(scenes[0]);
  struct Case {
    std::string args;
    fs::path output;
    std::string says;
  };
  for (const Case& c :
       {Case{scene, scenes[0], "is the file --scene reads"},
        Case{scene, dir / "." / scenes[0].filename(), "is the file --scene reads"},
        Case{scene, dir / "link.toml", "is the file --scene reads"},
        Case{scene, paths.normal_map, "is the normal_map of region '" + kBump + "'"},
        Case{scene, paths.depth_map, "is the depth_map of region '" + kBump + "'"},
        Case{"--normal-map " + quote(paths.normal_map), paths.normal_map, "is the file --normal-map reads"},
        Case{"--normal-map " + quote(paths.normal_map) + " --depth-map " + quote(paths.depth_map), paths.depth_map,
             "is the file --depth-map reads"}}) {
    SCOPED_TRACE(c.args + " -o " + c.output.string());
    const std::vector<char> before = read_file_bytes(c.output);
    ASSERT_FALSE(before.empty());
    const ToolResult r = run_tool("trace " + c.args + " -o " + quote(c.output), dir);
    expect_clean_failure(r, {"-o " + c.output.string() + " " + c.says, "write the trace to another file"});
    EXPECT_EQ(read_file_bytes(c.output), before);
  }
  EXPECT_TRUE(fs::is_symlink(dir / "link.toml"));
}

// The N numbers of ones, "1,1,...".
std::string ones(std::size_t n) {
  std::string out;
  for (std::size_t i = 0; i < n; ++i) out += i == 0 ? "1" : ",1";
  return out;
}

// An option of a few numbers ("X,Y") takes one argument, and a wrong count of numbers, an empty one or a word is an
// error that names the option and the form it expects (CLI11's own said "At Most 2 required but received 4", or
// took the positional arguments after the option for its numbers). The command line is refused as it is read: no
// file named need exist, and nothing is written.
TEST(Tool, CommaOptionsSayTheFormTheyExpect) {
  ScratchDir dir;
  const std::string out = quote(dir / "out");
  struct Option {
    std::string command, flag, rest;  // the command line: command, the flag and its argument, rest
    std::string form, words;
    bool integers = false;
  };
  const std::string replay_files = quote(dir / "in.evemu") + " " + out + " --trace " + quote(dir / "t.csv");
  const std::string inspect_files = out + " --normal-map " + quote(dir / "n.png");
  const std::string trace = "trace --target " + kBump;
  const Option options[] = {
      {"replay", "--start", replay_files, "X,Y", "two numbers separated by a comma"},
      {"replay", "--desktop", replay_files, "X,Y,W,H", "four integers separated by commas", true},
      {"inspect", "--size", inspect_files, "W,H", "two integers separated by a comma", true},
      {"inspect", "--light", inspect_files, "X,Y,Z", "three numbers separated by commas"},
      {trace, "--from", "-o " + out, "X,Y", "two numbers separated by a comma"},
      {trace, "--to", "-o " + out, "X,Y", "two numbers separated by a comma"},
      {trace, "--kmax-limits", "-o " + out, "LO,HI", "two numbers separated by a comma"},
      {trace, "--kmin-limits", "-o " + out, "LO,HI", "two numbers separated by a comma"},
      {"cursor", "--set", "--socket " + quote(dir / "socket"), "X,Y", "two numbers separated by a comma"},
  };
  for (const Option& o : options) {
    const std::size_t count = static_cast<std::size_t>(std::count(o.form.begin(), o.form.end(), ',')) + 1;
    std::vector<std::string> wrong = {ones(count - 1), ones(count + 1), ones(count - 1) + ",x", ones(count - 1) + ",",
                                      "," + ones(count - 1)};
    if (o.integers) wrong.push_back(ones(count - 1) + ",1.5");
    for (const std::string& value : wrong) {
      const std::string command = o.command + " " + o.flag + " " + value + " " + o.rest;
      SCOPED_TRACE(command);
      expect_clean_failure(run_tool(command, dir), {o.flag + ": expected " + o.form + " (" + o.words + ")"});
      EXPECT_FALSE(fs::exists(dir / "out"));
    }
  }
}

// Eq. 1-3 from a row's own cells (the values are printed to 6 significant digits).
void expect_eq2(const Csv& csv, std::size_t i, double kmax_lo, double kmax_hi, double kmin_lo, double kmin_hi) {
  SCOPED_TRACE("row " + std::to_string(i));
  const double cos_alpha = csv.number(i, kCosAlpha), delta_beta = csv.number(i, kDeltaBeta);
  const double kmax = csv.number(i, kKmax), kmin = csv.number(i, kKmin), cd = csv.number(i, kCd);
  EXPECT_GE(kmax, kmax_lo);
  EXPECT_LE(kmax, kmax_hi);
  EXPECT_GE(kmin, kmin_lo);
  EXPECT_LE(kmin, kmin_hi);
  EXPECT_NEAR(kmax, std::clamp(4.0 * (1.0 + delta_beta), kmax_lo, kmax_hi), 1e-4 * kmax + 1e-4);
  EXPECT_NEAR(kmin, std::clamp(1.5 * (1.0 - delta_beta), kmin_lo, kmin_hi), 1e-4 * kmin + 1e-4);
  const double want = cos_alpha > 0 ? 1.0 - cos_alpha * (1.0 - 1.0 / kmin) : 1.0 - cos_alpha * (kmax - 1.0);
  EXPECT_NEAR(cd, want, 1e-4 * cd);
}

// --delta-beta-sign -1 reverses delta-beta, and with it kmax and kmin; the --*-limits clamp them.
TEST(Tool, TraceCurvatureOptions) {
  ScratchDir dir;
  const Csv plain = trace("--target " + kBump, dir);
  const Csv reversed = trace("--target " + kBump + " --delta-beta-sign -1", dir);
  const Csv narrow = trace("--target " + kBump + " --kmax-limits 1,2 --kmin-limits 1,1.25", dir);
  const Csv raised = trace("--target " + kBump + " --kmax-limits 3,30 --kmin-limits 1.4,5", dir);
  for (const Csv* csv : {&reversed, &narrow, &raised}) ASSERT_EQ(csv->rows.size(), plain.rows.size());
  std::size_t flipped = 0, cd_changed = 0;
  double plain_max = 0.0, plain_min = 10.0, narrow_max = 0.0, narrow_min = 10.0;
  bool kmax_at_2 = false, kmin_at_125 = false;
  for (std::size_t i = 0; i < plain.rows.size(); ++i) {
    EXPECT_EQ(reversed.rows[i][kCosAlpha], plain.rows[i][kCosAlpha]);
    const double db = plain.number(i, kDeltaBeta);
    EXPECT_EQ(reversed.number(i, kDeltaBeta), -db) << i;
    flipped += db != 0.0;
    cd_changed += reversed.rows[i][kCd] != plain.rows[i][kCd];
    expect_eq2(plain, i, 1, 30, 1, 5);
    expect_eq2(reversed, i, 1, 30, 1, 5);
    expect_eq2(narrow, i, 1, 2, 1, 1.25);
    expect_eq2(raised, i, 3, 30, 1.4, 5);
    plain_max = std::max(plain_max, plain.number(i, kCd));
    plain_min = std::min(plain_min, plain.number(i, kCd));
    narrow_max = std::max(narrow_max, narrow.number(i, kCd));
    narrow_min = std::min(narrow_min, narrow.number(i, kCd));
    kmax_at_2 = kmax_at_2 || narrow.rows[i][kKmax] == "2";
    kmin_at_125 = kmin_at_125 || narrow.rows[i][kKmin] == "1.25";
    EXPECT_GE(raised.number(i, kKmax), 3.0);
    EXPECT_GE(raised.number(i, kKmin), 1.4);
  }
  EXPECT_GT(flipped, 300u);
  EXPECT_GT(cd_changed, 100u);
  EXPECT_GT(plain_max, 3.0);  // unclamped: up to 4 on this bump
  EXPECT_LT(plain_min, 0.75);
  EXPECT_LE(narrow_max, 2.0);
  EXPECT_GE(narrow_min, 1.0 / 1.25 - 1e-6);
  EXPECT_TRUE(kmax_at_2);
  EXPECT_TRUE(kmin_at_125);
  expect_clean_failure(run_tool("trace --target " + kBump + " --kmax-limits 5,2", dir),
                       {"kmax limits must be finite with 1 <= lower <= upper <= 100 (given: --kmax-limits 5,2)"});
  // The message names the flags typed, with their values, not only the scene file's keys.
  expect_clean_failure(
      run_tool("trace --target " + kBump + " --method depth --gain 2 --depth-kmax 0.5", dir),
      {"depth method: kmax must be a finite number from 1 to 100 (given: --gain 2, --depth-kmax 0.5)"});
}

// `targets` writes the 24 targets' files; `demo` reads them (as the daemon would) and prints one row per target.
TEST(Tool, TargetsAndDemo) {
  ScratchDir dir;
  const fs::path folder = dir / "targets";
  const std::vector<TargetSpec> all = all_targets();
  {
    SCOPED_TRACE("targets");
    const ToolResult r = run_tool("targets " + quote(folder), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.out, "24")) << r.out;
    // Standard error is a file here: one progress line per target, no carriage returns.
    EXPECT_TRUE(contains(r.err, "[ 1/24] " + all.front().name() + "\n[ 2/24] ")) << r.err;
    EXPECT_TRUE(contains(r.err, "[24/24] " + all.back().name() + "\n")) << r.err;
    EXPECT_FALSE(contains(r.err, "\r")) << r.err;
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(folder)) {
      EXPECT_TRUE(entry.is_regular_file()) << entry.path();
      EXPECT_GT(entry.file_size(), 0u) << entry.path();
      ++files;
    }
    EXPECT_EQ(files, 72u);
    for (const TargetSpec& t : all) {
      const TargetFilePaths paths = target_file_paths(folder, t);
      EXPECT_TRUE(fs::exists(paths.normal_map)) << paths.normal_map;
      EXPECT_TRUE(fs::exists(paths.depth_map)) << paths.depth_map;
      EXPECT_EQ(read_text(paths.scene), target_scene_text(t)) << paths.scene;
    }
  }

  {
    // Written again and cut short (here by the file size limit, at the first normal map of 100 KiB or more): each
    // file is whole or as it was, none cut short under its own name, which demo and the daemon would read as a
    // target's (before, the normal map was left truncated).
    std::map<std::string, std::vector<char>> earlier;
    for (const auto& entry : fs::directory_iterator(folder)) earlier[entry.path().filename()] = read_file_bytes(entry);
    const std::string limited =
        "ulimit -c 0 && ulimit -f 64 && exec " + quote(std::string(PH_TOOL_PATH)) + " targets " + quote(folder);
    EXPECT_EQ(run_program("/bin/sh", "-c " + quote(limited), dir).rc, 128 + SIGXFSZ);
    // As a full disk is met (SIGXFSZ ignored): the run fails naming the file, not its temporary.
    const ToolResult full = run_program("/bin/sh", "-c " + quote("trap '' XFSZ && " + limited), dir);
    expect_clean_failure(full, {(folder / (all.front().name() + ".normal.png")).string() + ": cannot write"});
    EXPECT_FALSE(contains(full.err, "partial")) << full.err;
    for (const auto& entry : fs::directory_iterator(folder)) {
      const std::string name = entry.path().filename();
      if (name.ends_with(".partial")) continue;  // the temporary of the file it was writing when killed
      EXPECT_TRUE(earlier.contains(name) && earlier.at(name) == read_file_bytes(entry)) << name << " changed";
    }
  }

  SCOPED_TRACE("demo");
  const ToolResult r = run_tool("demo --targets " + quote(folder), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_FALSE(contains(r.err, "writing the 24 targets")) << "the files were there: " << r.err;
  EXPECT_EQ(r.err, "");  // no progress where standard error is not a terminal: the table's rows say as much
  std::vector<std::string> names;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::string name, dots1, dots2;
    double c_lo = 0, c_hi = 0, d_lo = 0, d_hi = 0;
    if (!(words >> name >> c_lo >> dots1 >> c_hi >> d_lo >> dots2 >> d_hi) || dots1 != ".." || dots2 != "..") continue;
    SCOPED_TRACE(line);
    names.push_back(name);
    // Curvature: slower somewhere on the way up, faster somewhere on the way down, within the method's bounds.
    EXPECT_GT(c_hi, 1.0);
    EXPECT_LT(c_lo, 1.0);
    EXPECT_GE(c_lo, 1.0 / 5.0 - 1e-3);
    EXPECT_LE(c_hi, 30.0 + 1e-3);
    // Depth: both ways too, within [1 / kmin, kmax] = [1 / 1.5, 4].
    EXPECT_GT(d_hi, 1.0);
    EXPECT_LT(d_lo, 1.0);
    EXPECT_GE(d_lo, 1.0 / 1.5 - 1e-3);
    EXPECT_LE(d_hi, 4.0 + 1e-3);
  }
  ASSERT_EQ(names.size(), 24u) << r.out;
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(names[i], all[i].name());

  // A step so small that a stroke would stop part way printed that part's range as the target's, with exit 0; and
  // no table's head without a row.
  const ToolResult tiny = run_tool("demo --targets " + quote(folder) + " --step 4e-5", dir);
  expect_clean_failure(tiny, {"more than the 10000000 a stroke may take: give a larger --step"});
  EXPECT_EQ(tiny.out, "");

  // A damaged target file (a run killed while writing it) failed every demo after it: it is written again.
  const TargetSpec& damaged = all[5];
  std::ofstream(target_file_paths(folder, damaged).normal_map, std::ios::binary) << "garbage";
  const ToolResult mended = run_tool("demo --targets " + quote(folder), dir);
  ASSERT_EQ(mended.rc, 0) << mended.err;
  EXPECT_TRUE(contains(mended.err, "not a PNG file; writing the target " + damaged.name() + " again")) << mended.err;
  EXPECT_EQ(mended.out, r.out);
  EXPECT_EQ(run_tool("demo --targets " + quote(folder), dir).err, "");  // mended for good
  // Its depth map too, which the scene's own method (curvature) does not read but the demo's depth column does.
  std::filesystem::resize_file(target_file_paths(folder, damaged).depth_map, 1000);
  const ToolResult depth_mended = run_tool("demo --targets " + quote(folder), dir);
  ASSERT_EQ(depth_mended.rc, 0) << depth_mended.err;
  EXPECT_TRUE(contains(depth_mended.err, "writing the target " + damaged.name() + " again")) << depth_mended.err;
  EXPECT_EQ(depth_mended.out, r.out);

  // A file the targets cannot be written to: the file system's reason.
  fs::create_directories(dir / "blocked" / (all.front().name() + ".toml"));
  expect_clean_failure(run_tool("targets " + quote(dir / "blocked"), dir),
                       {all.front().name() + ".toml: cannot write: Is a directory"});
  // An output folder that is a link to nowhere: said so, not "File exists".
  fs::create_symlink(dir / "gone" / "targets", dir / "dangling");
  const ToolResult dangling = run_tool("targets " + quote(dir / "dangling"), dir);
  expect_clean_failure(dangling, {(dir / "dangling").string() + ": is a link to " +
                                  (dir / "gone" / "targets").string() + ", which does not exist"});
}

// Without FILE, check-config reads the daemon's default file; where there is none the daemon runs its embedded
// default scene, and check-config says so rather than failing.
TEST(Tool, CheckConfigWithoutAFileDescribesTheEmbeddedDefaultScene) {
  const fs::path default_file{std::string(kDefaultSceneFile)};
  if (fs::exists(default_file)) GTEST_SKIP() << default_file << " exists here (an installed service)";
  ScratchDir dir;
  const ToolResult r = run_tool("check-config", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  // Laid out for the displays connected here, as the daemon would; a build machine has none (1920 x 1080).
  std::string no_display;
  const Rect desktop = resolve_desktop(std::nullopt, kDrmDir, no_display);
  const Scene expected = default_scene(desktop);
  const Rect last = expected.regions().back().rect;
  for (const std::string& part :
       {default_file.string() + ": no such file, so pseudohapticd runs its embedded default scene",
        std::string("\n  output: absolute\n"), fmt::format("\nregions: {}\n", expected.regions().size()),
        fmt::format("\nlaid out for: {},{} {}x{} px (", desktop.x, desktop.y, desktop.w, desktop.h),
        fmt::format("\n  [{}] '{}': {},{} 500x500 px, curvature, ", expected.regions().size() - 1,
                    expected.regions().back().name, last.x, last.y)}) {
    EXPECT_TRUE(contains(r.out, part)) << "expected '" << part << "' in: " << r.out;
  }
  EXPECT_TRUE(r.err.empty()) << r.err;
  const ToolResult quiet = run_tool("check-config --quiet", dir);
  EXPECT_EQ(quiet.rc, 0) << quiet.err;
  EXPECT_TRUE(quiet.out.empty()) << quiet.out;
  // A file named and missing is still an error.
  expect_clean_failure(run_tool("check-config " + quote(dir / "nope.toml"), dir), {"nope.toml: cannot open"});
}

TEST(Tool, CheckConfig) {
  ScratchDir dir;
  const TargetSpec target = target_named("bump-gaussian-h1-r100");
  write_target_files(dir.path(), {target});
  const TargetFilePaths paths = target_file_paths(dir.path(), target);
  const fs::path scene = dir / "scene.toml";
  {
    std::ofstream out(scene, std::ios::binary);
    out << "[daemon]\ndevices = [\"name:Logitech*\", \"usb:046d:c077\"]\noutput = \"absolute\"\n"
           "desktop = [0, 0, 2560, 1440]\npointer_speed = 1.5\n\n"
        << read_text(paths.scene);
  }
  {
    SCOPED_TRACE("summary");
    const ToolResult r = run_tool("check-config " + quote(scene), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(without_sandbox_warnings(r.err).empty()) << r.err;
    if (hidden_from_the_service(paths.normal_map)) {  // the scratch folder, under /tmp
      EXPECT_TRUE(contains(r.err, "normal_map " + paths.normal_map.string() + " lies under /tmp, which " +
                                      "pseudohapticd.service cannot read (PrivateTmp=yes"))
          << r.err;
    }
    for (std::string_view part :
         {"name:Logitech*, usb:046d:c077", "absolute", "0,0 2560x1440", "1.5", "'bump-gaussian-h1-r100'", "500x500",
          "curvature", "2000000 bytes", "0 invalid texels repaired", "\n      normal map: 500x500 px\n",
          "\n      depth map: not read: neither the method nor an effect uses it\n"}) {
      EXPECT_TRUE(contains(r.out, part)) << "expected '" << part << "' in: " << r.out;
    }
  }
  {
    SCOPED_TRACE("defaults, quiet");
    const ToolResult r = run_tool("check-config " + quote(paths.scene), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.out, "any pointer")) << r.out;
    EXPECT_TRUE(contains(r.out, "desktop: auto")) << r.out;
    const ToolResult q = run_tool("check-config --quiet " + quote(scene), dir);
    EXPECT_EQ(q.rc, 0) << q.err;
    EXPECT_TRUE(q.out.empty()) << q.out;
    EXPECT_TRUE(without_sandbox_warnings(q.err).empty()) << q.err;
  }
  {
    SCOPED_TRACE("hybrid: the texels it takes the depth C/D at");
    std::string text = read_text(paths.scene);
    const std::size_t at = text.find("method = \"curvature\"");
    ASSERT_NE(at, std::string::npos) << text;
    text.replace(at, std::string("method = \"curvature\"").size(), "method = \"hybrid\"");
    std::ofstream(dir / "hybrid.toml", std::ios::binary) << text;
    // The target's rim, where its truncated Gaussian steps down by about 1 px (docs/METHODS.md, "Hybrid").
    const ToolResult r = run_tool("check-config " + quote(dir / "hybrid.toml"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(contains(r.out, "hybrid")) << r.out;
    EXPECT_TRUE(contains(r.out, "steps: 1132 texels (0.45 %) take the depth C/D")) << r.out;
    // The target's 16-bit normal map: a code is 2 / 65535 in n, a slope sigma of that over sqrt(12).
    EXPECT_TRUE(contains(r.out, "rounding: slope sigma 8.8e-06 from the map's storage")) << r.out;
    // Smoothed nearly everywhere; the flattening taken off almost nowhere: on this steep relief the correction would
    // move most texels further than the 16-bit map's narrow band.
    EXPECT_TRUE(contains(r.out,
                         "the normals are smoothed within it (87.5 % of the texels; at 0.8 % the smoothing's "
                         "flattening taken off again)"))
        << r.out;
    EXPECT_TRUE(contains(r.out, "fusion: none: over most of the region the depth map's slopes explain the normals"))
        << r.out;
    EXPECT_FALSE(contains(run_tool("check-config " + quote(scene), dir).out, "steps:"));  // curvature: no such line
    // noise_slope = 0 keeps the normals as given: neither line gives another reason.
    std::ofstream(dir / "hybrid-as-given.toml", std::ios::binary) << text << "[region.hybrid]\nnoise_slope = 0\n";
    const ToolResult given = run_tool("check-config " + quote(dir / "hybrid-as-given.toml"), dir);
    ASSERT_EQ(given.rc, 0) << given.err;
    EXPECT_TRUE(contains(given.out,
                         "rounding: slope sigma 8.8e-06 from the map's storage: noise_slope = 0 keeps the "
                         "normals as given"))
        << given.out;
    EXPECT_TRUE(contains(given.out, "fusion: none: noise_slope = 0 keeps the normals as given")) << given.out;
  }
  {
    SCOPED_TRACE("hybrid: a generator's 8-bit normals read again from 16-bit heights");
    Grid<float> image(32, 32);  // a dome 0.2 of the default 100 px relief high, as a 16-bit grey image
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 32; ++x) {
        image.at(x, y) = static_cast<float>(0.2 * std::exp(-(std::pow(x - 15.5, 2) + std::pow(y - 15.5, 2)) / 60.0));
      }
    }
    write_gray_png16(dir / "dome_depth.png", image);
    DepthField heights(32, 32);  // what the loader reads back, from which the generator made its normals
    for (std::size_t i = 0; i < heights.values.size(); ++i) {
      heights.values[i] = static_cast<float>(std::round(image.values[i] * 65535.0) / 65535.0 * 100.0);
    }
    write_normal_image(dir / "dome_normals.png", sobel_normals(heights), {ImageFormat::png, 8});
    // check-config on a scene of the dome's two maps as a hybrid region, with `more` in its table.
    const auto check_dome = [&](const std::string& file, const std::string& more) {
      std::ofstream(dir / file, std::ios::binary)
          << "[[region]]\nname = \"dome\"\nx = 0\ny = 0\nwidth = 32\nheight = 32\nmethod = \"hybrid\"\n"
             "normal_map = \"dome_normals.png\"\ndepth_map = \"dome_depth.png\"\n"
          << more;
      return run_tool("check-config " + quote(dir / file), dir);
    };
    const ToolResult r = check_dome("generated.toml", "");
    ASSERT_EQ(r.rc, 0) << r.err;
    // 100 / 65535 px per code through the Sobel filter: 1.5e-3 / sqrt(12) x sqrt(12) / 8 = 1.9e-4; the 8-bit normal
    // map's own, 2 / 255 / sqrt(12) = 2.3e-3.
    EXPECT_TRUE(contains(r.out, "rounding: slope sigma 0.00019: the normals are a generator's reading")) << r.out;
    EXPECT_TRUE(contains(r.out, "(normal map's own: 0.0023) and smoothed within it (")) << r.out;
    EXPECT_TRUE(contains(r.out, "fusion: none: the normals were read again from the heights (above)")) << r.out;
    EXPECT_TRUE(contains(r.out, "scale: the normal map's slopes are 1 times the depth map's")) << r.out;
    EXPECT_FALSE(contains(r.out, "makes them agree")) << r.out;
    // The same maps with the depth map's relief_px halved: its slopes are half the normals', and it says so.
    const ToolResult halved = check_dome("halved.toml", "relief_px = 50\n");
    ASSERT_EQ(halved.rc, 0) << halved.err;
    EXPECT_TRUE(contains(halved.out, "scale: the normal map's slopes are 2 times the depth map's")) << halved.out;
    // (101: the generator's 8-bit normals read the dome's slopes a little apart from its heights' differences.)
    EXPECT_TRUE(contains(halved.out, "relief_px = 101 (now 50) makes them agree")) << halved.out;
    EXPECT_TRUE(contains(halved.err, "warning: " + (dir / "halved.toml").string() +
                                         ":1: region 'dome': the normal map's slopes are 2 times"))
        << halved.err;  // and as a warning, as the daemon logs it
    // trace warns of it as the daemon does, from the scene file or from the maps given by hand.
    const ToolResult traced =
        run_tool("trace --scene " + quote(dir / "halved.toml") + " -o " + quote(dir / "t.csv"), dir);
    ASSERT_EQ(traced.rc, 0) << traced.err;
    EXPECT_TRUE(contains(traced.err, "warning: " + (dir / "halved.toml").string() +
                                         ":1: region 'dome': the normal map's slopes are 2 times the depth map's"))
        << traced.err;
    EXPECT_TRUE(contains(traced.err, "relief_px = 101 (now 50) makes them agree")) << traced.err;
    const ToolResult by_hand =
        run_tool("trace --method hybrid --normal-map " + quote(dir / "dome_normals.png") + " --depth-map " +
                     quote(dir / "dome_depth.png") + " --relief-px 50 -o " + quote(dir / "t.csv"),
                 dir);
    ASSERT_EQ(by_hand.rc, 0) << by_hand.err;
    EXPECT_TRUE(contains(by_hand.err, "warning: the normal map's slopes are 2 times the depth map's")) << by_hand.err;
    const ToolResult agreeing =
        run_tool("trace --scene " + quote(dir / "generated.toml") + " -o " + quote(dir / "t.csv"), dir);
    ASSERT_EQ(agreeing.rc, 0) << agreeing.err;
    EXPECT_FALSE(contains(agreeing.err, "makes them agree")) << agreeing.err;
    // The same heights under normals of their exact slopes with noise of sigma 0.05 on each: pulled to the heights.
    NormalImage noisy(32, 32);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> noise(0.0, 0.05);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 32; ++x) {
        const double e = 20.0 * std::exp(-(std::pow(x - 15.5, 2) + std::pow(y - 15.5, 2)) / 60.0);
        noisy.at(x, y) = normal_from_gradient({static_cast<float>(-2.0 * (x - 15.5) / 60.0 * e + noise(rng)),
                                               static_cast<float>(-2.0 * (y - 15.5) / 60.0 * e + noise(rng))});
      }
    }
    write_normal_png16(dir / "dome_normals.png", noisy);
    const ToolResult fused = run_tool("check-config " + quote(dir / "generated.toml"), dir);
    ASSERT_EQ(fused.rc, 0) << fused.err;
    EXPECT_TRUE(contains(fused.out, "fusion: the normals are pulled toward the depth map's slopes")) << fused.out;
  }
  {
    SCOPED_TRACE("maps resampled: in proportion, and stretched out of it (a warning)");
    std::string text = read_text(paths.scene);
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"width = 500", "width = 800"},
                                   {"height = 500", "height = 300"},
                                   {"method = \"curvature\"", "method = \"depth\""}}) {
      const std::size_t at = text.find(from);
      ASSERT_NE(at, std::string::npos) << from << " in " << text;
      text.replace(at, from.size(), to);
    }
    std::ofstream(dir / "stretched.toml", std::ios::binary) << text;
    const ToolResult r = run_tool("check-config " + quote(dir / "stretched.toml"), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    const std::string stretched =
        "500x500 px, resampled to the region's 800x300; out of proportion: stretched by 1.6 across and 0.6 down";
    EXPECT_TRUE(contains(r.out, "\n      depth map: " + stretched + "\n")) << r.out;
    EXPECT_TRUE(contains(r.out, "\n      normal map: not read")) << r.out;
    EXPECT_TRUE(contains(r.err, "pseudohaptic: warning: " + (dir / "stretched.toml").string() +
                                    ":3: region 'bump-gaussian-h1-r100': depth map " + paths.depth_map.string() + ": " +
                                    stretched + "\n"))
        << r.err;
    // --quiet leaves out the summary, not the warnings: a script checking a file for the service must hear them.
    const ToolResult quiet = run_tool("check-config --quiet " + quote(dir / "stretched.toml"), dir);
    EXPECT_EQ(quiet.rc, 0) << quiet.err;
    EXPECT_TRUE(quiet.out.empty()) << quiet.out;
    EXPECT_EQ(without_sandbox_warnings(quiet.err), without_sandbox_warnings(r.err));
    // The same region at 250 x 250: resampled in proportion, no warning.
    text.replace(text.find("width = 800"), 11, "width = 250");
    text.replace(text.find("height = 300"), 12, "height = 250");
    std::ofstream(dir / "halved.toml", std::ios::binary) << text;
    const ToolResult halved = run_tool("check-config " + quote(dir / "halved.toml"), dir);
    ASSERT_EQ(halved.rc, 0) << halved.err;
    EXPECT_TRUE(contains(halved.out, "\n      depth map: 500x500 px, resampled to the region's 250x250\n"))
        << halved.out;
    EXPECT_TRUE(without_sandbox_warnings(halved.err).empty()) << halved.err;
  }
  {
    SCOPED_TRACE("bad setting");
    std::ofstream(dir / "bad.toml", std::ios::binary) << "[daemon]\noutput = \"abs\"\n";
    const ToolResult r = run_tool("check-config --quiet " + quote(dir / "bad.toml"), dir);
    EXPECT_EQ(r.rc, 1);
    expect_clean_failure(r, {"pseudohaptic: ", "bad.toml:2:", "daemon.output", "\"absolute\""});
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  {
    SCOPED_TRACE("bad image");
    fs::remove(paths.normal_map);
    const ToolResult r = run_tool("check-config " + quote(scene), dir);
    EXPECT_EQ(r.rc, 1);
    expect_clean_failure(r, {"scene.toml:", "bump-gaussian-h1-r100", paths.normal_map.filename().string()});
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

}  // namespace
}  // namespace ph
