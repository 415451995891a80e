// End-to-end test of `pseudohaptic study --small`: the files it writes, the seeded result's ordering, the same
// seed giving the same CSV, and the technique changing the outcome.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/csv_table.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/tool_runner.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

// Rows of a CSV file as maps from the header's names.
std::vector<std::map<std::string, std::string>> read_rows(const fs::path& path) { return named_rows(read_csv(path)); }

// summary.csv's value of `column` for one technique and group.
double summary_value(const std::vector<std::map<std::string, std::string>>& rows, const std::string& technique,
                     const std::string& group, const std::string& column) {
  for (const auto& r : rows) {
    if (r.at("technique") == technique && r.at("group") == group) return std::stod(r.at(column));
  }
  ADD_FAILURE() << "no summary row for " << technique << " " << group;
  return 0.0;
}

TEST(ToolStudy, SmallRunIsSeededOrderedAndDependsOnTheTechnique) {
  ScratchDir dir;
  const ToolResult r = run_tool("study --small --seed 5 " + quote(dir / "a"), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const ToolResult again = run_tool("study --small --seed 5 " + quote(dir / "b"), dir);
  ASSERT_EQ(again.rc, 0) << again.err;
  const std::string csv = read_text(dir / "a" / "trials.csv");
  EXPECT_EQ(csv, read_text(dir / "b" / "trials.csv"));
  EXPECT_EQ(read_text(dir / "a" / "summary.csv"), read_text(dir / "b" / "summary.csv"));

  // 4 participants x 2 techniques x 3 blocks x 24 targets, a third of them training.
  const auto trials = read_rows(dir / "a" / "trials.csv");
  ASSERT_EQ(trials.size(), 4u * 2 * 3 * 24);
  int scored = 0;
  std::map<std::string, std::vector<std::string>> outcome;  // per technique, every trial's answer and time
  for (const auto& t : trials) {
    scored += t.at("scored") == "1";
    EXPECT_EQ(t.at("correct") == "1", t.at("answer") == t.at("shape")) << t.at("target");
    outcome[t.at("technique")].push_back(t.at("answer") + " " + t.at("time_s"));
  }
  EXPECT_EQ(scored, 4 * 2 * 2 * 24);
  // The techniques meet the same hands and the same noise: only the texture differs, and it changes the trials.
  ASSERT_EQ(outcome.size(), 2u);
  EXPECT_NE(outcome["curvature:sign+1"], outcome["depth"]);

  // The seeded ordering: well above chance for both techniques, and low reliefs take longer than high ones (the
  // paper's H2.2), for both.
  const auto summary = read_rows(dir / "a" / "summary.csv");
  for (const std::string technique : {"curvature:sign+1", "depth"}) {
    EXPECT_LT(summary_value(summary, technique, "all", "error_pct"), 20.0) << technique;
    EXPECT_GT(summary_value(summary, technique, "h0.25-r100", "time_s"),
              summary_value(summary, technique, "h1-r200", "time_s") + 1.0)
        << technique;
  }
  // The model's prediction (docs/STUDY.md, "Results"), which this seed's small run already shows: the depth
  // method is read at least as well as the curvature method, and faster. A change to the engine or the observer
  // that turns this round changes the doc's conclusion too.
  EXPECT_LE(summary_value(summary, "depth", "all", "error_pct"),
            summary_value(summary, "curvature:sign+1", "all", "error_pct"));
  EXPECT_LT(summary_value(summary, "depth", "all", "time_s"),
            summary_value(summary, "curvature:sign+1", "all", "time_s"));
  EXPECT_EQ(summary_value(summary, "depth", "all", "paper_error_pct"), 7.47);

  // Without a texture the observer is at chance: the answers come from the cursor, not from the observer.
  const ToolResult none = run_tool("study --small --seed 5 --participants 2 --technique none " + quote(dir / "c"), dir);
  ASSERT_EQ(none.rc, 0) << none.err;
  const double chance = summary_value(read_rows(dir / "c" / "summary.csv"), "none", "all", "error_pct");
  EXPECT_GT(chance, 30.0);
  EXPECT_LT(chance, 70.0);
}

// tools/study_paired.py, which docs/STUDY.md's paired table comes from, reads what the study wrote (its differences
// agree in sign with summary.csv's means), and names the file and line of a trials.csv that is not what it wrote
// rather than ending in a traceback.
TEST(ToolStudy, StudyPairedReadsTheRunAndNamesAMalformedFile) {
  ScratchDir dir;
  ASSERT_EQ(run_tool("study --small --seed 5 " + quote(dir / "a"), dir).rc, 0);
  const fs::path script = PH_STUDY_PAIRED;
  const ToolResult paired = run_program("python3", quote(script) + " " + quote(dir / "a"), dir);
  ASSERT_EQ(paired.rc, 0) << paired.err;
  const std::string row = "| curvature:sign+1 \u2212 depth, all targets | ";
  const std::size_t at = paired.out.find(row);
  ASSERT_NE(at, std::string::npos) << paired.out;
  // The decision time's difference, the row's last cell: depth is faster (the first test), so it is positive.
  const std::string line = paired.out.substr(at, paired.out.find('\n', at) - at);
  const std::size_t last_bar = line.rfind('|');
  const std::size_t cell_start = line.rfind('|', last_bar - 1);
  EXPECT_EQ(line.substr(cell_start, 3), "| +") << line;

  std::vector<std::string> lines;
  std::istringstream in(read_text(dir / "a" / "trials.csv"));
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_GT(lines.size(), 6u);
  const auto write_trials = [&](const std::string& name, const std::vector<std::string>& text) {
    fs::create_directories(dir / name);
    std::ofstream out(dir / name / "trials.csv", std::ios::binary);
    for (const std::string& l : text) out << l << '\n';
  };
  std::vector<std::string> bad_time = lines;
  // time_s is the 14th column: made a word on line 6.
  std::vector<std::string> cells;
  std::istringstream cells_in(bad_time[5]);
  for (std::string c; std::getline(cells_in, c, ',');) cells.push_back(c);
  ASSERT_GT(cells.size(), 13u);
  cells[13] = "abc";
  bad_time[5].clear();
  for (std::size_t i = 0; i < cells.size(); ++i) bad_time[5] += (i ? "," : "") + cells[i];
  write_trials("word", bad_time);
  write_trials("short", {lines[0], lines[1], "0,depth"});
  write_trials("other", {"a,b", "1,2"});
  for (const auto& [name, said] : std::vector<std::pair<std::string, std::string>>{
           {"word", "trials.csv:6: time_s: not a number: 'abc'"},
           {"short", "trials.csv:3: fewer cells than the header has"},
           {"other", "trials.csv: missing column(s) participant, technique"}}) {
    SCOPED_TRACE(name);
    const ToolResult r = run_program("python3", quote(script) + " " + quote(dir / name), dir);
    EXPECT_EQ(r.rc, 1) << r.err;
    EXPECT_NE(r.err.find(said), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("Traceback"), std::string::npos) << r.err;
  }
}

// A technique named twice runs once: the files are those of naming it once, not every row twice.
TEST(ToolStudy, ATechniqueNamedTwiceRunsOnce) {
  ScratchDir dir;
  const ToolResult once = run_tool("study --small --participants 2 --technique depth " + quote(dir / "a"), dir);
  ASSERT_EQ(once.rc, 0) << once.err;
  const ToolResult twice =
      run_tool("study --small --participants 2 --technique depth --technique depth " + quote(dir / "b"), dir);
  ASSERT_EQ(twice.rc, 0) << twice.err;
  for (const char* file : {"summary.csv", "trials.csv", "summary.md"}) {
    EXPECT_EQ(read_text(dir / "b" / file), read_text(dir / "a" / file)) << file;
  }
}

TEST(ToolStudy, UnknownTechniqueIsNamedWithTheKnownOnes) {
  ScratchDir dir;
  const ToolResult r = run_tool("study --small --technique bogus " + quote(dir / "a"), dir);
  EXPECT_GE(r.rc, 2);  // a value of the command line refused: as the man page's EXIT STATUS says
  EXPECT_NE(r.err.find("--technique"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown technique 'bogus'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("depth"), std::string::npos) << r.err;
}

// Without a texture the observer is at chance whatever its noise, so no Weber fraction of the range gives the
// paper's pooled error: the calibration says so and fails, rather than print the end of the range as the answer.
TEST(ToolStudy, CalibrationThatCannotReachThePapersErrorFails) {
  ScratchDir dir;
  const ToolResult r = run_tool("study --calibrate --participants 2 --technique none", dir);
  expect_clean_failure(r, {"pseudohaptic: calibrate: the paper's pooled error of 5.47 % is not reached with a Weber "
                           "fraction from 0.02 to 2: the pooled error was "});
  EXPECT_EQ(r.out.find("gives the paper's pooled error"), std::string::npos) << r.out;
}

// A folder that cannot take the files fails before the participants run, with none of the files written; what
// --calibrate finds or would not write is not also taken from the command line.
TEST(ToolStudy, WhatCannotBeUsedIsSaidBeforeTheRun) {
  ScratchDir dir;
  std::filesystem::create_directories(dir / "out" / "summary.md");
  const ToolResult r = run_tool("study --small --technique none " + quote(dir / "out"), dir);
  expect_clean_failure(r, {(dir / "out" / "summary.md").string() + ": is a folder"});
  EXPECT_EQ(r.err.find("participant runs"), std::string::npos) << r.err;  // no progress: nothing ran
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "trials.csv"));
  expect_clean_failure(run_tool("study --calibrate --weber 0.3 --technique none", dir),
                       {"--calibrate finds the Weber fraction: give it or --weber, not both"});
  expect_clean_failure(run_tool("study --calibrate --technique none " + quote(dir / "c"), dir),
                       {"--calibrate writes nothing: leave out OUTDIR"});
  EXPECT_FALSE(std::filesystem::exists(dir / "c"));
}

// --participants is kept with --small (12 was taken for "not given" and became 4); OUTDIR missing is a command-line
// error, with CLI11's exit status, as a missing argument of any other command is.
TEST(ToolStudy, ParticipantsAreAsGivenAndOutdirIsAnArgument) {
  ScratchDir dir;
  const ToolResult twelve = run_tool("study --small --technique none --participants 12 " + quote(dir / "s"), dir);
  ASSERT_EQ(twelve.rc, 0) << twelve.err;
  EXPECT_NE(twelve.out.find("1 technique x 12 participants"), std::string::npos) << twelve.out;
  const ToolResult small = run_tool("study --small --technique none " + quote(dir / "t"), dir);
  ASSERT_EQ(small.rc, 0) << small.err;
  EXPECT_NE(small.out.find("x 4 participants"), std::string::npos) << small.out;

  const ToolResult none = run_tool("study --small", dir);
  expect_clean_failure(none, {"OUTDIR is required", "Run with --help"});
  EXPECT_GE(none.rc, 2);
}

// One participant has no interval over participants: the summaries' would read as certainty ([4.22, 4.22]).
TEST(ToolStudy, OneParticipantIsRefused) {
  ScratchDir dir;
  const ToolResult r = run_tool("study --small --participants 1 " + quote(dir / "one"), dir);
  expect_clean_failure(r, {"--participants: must be a whole number from 2 to 100000, not 1"});
  EXPECT_FALSE(std::filesystem::exists(dir / "one"));
}

// --technique chooses what --calibrate pools over, and its help says so.
TEST(ToolStudy, CalibrateHelpSaysWhichTechniquesItPools) {
  ScratchDir dir;
  const ToolResult r = run_tool("study --help", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::size_t at = r.out.find("--calibrate");
  ASSERT_NE(at, std::string::npos) << r.out;
  const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
  EXPECT_NE(line.find("the paper's two techniques unless --technique names others"), std::string::npos) << line;
}

}  // namespace
}  // namespace ph
