// End-to-end tests of the `pseudohaptic` command-line tool (tools/): run the built binary, read what it writes.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "config/target_files.hpp"
#include "core/targets.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/tool_runner.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

// A failure the tool reports itself: a non-zero status, a message on stderr, no crash and no stack trace.
void expect_clean_failure(const ToolResult& r, std::initializer_list<std::string_view> names) {
  EXPECT_NE(r.rc, 0);
  EXPECT_LT(r.rc, 128) << "killed by a signal";
  EXPECT_FALSE(r.err.empty());
  for (std::string_view part : names) EXPECT_TRUE(contains(r.err, part)) << "expected '" << part << "' in: " << r.err;
  for (std::string_view crash : {"terminate called", "what():", "Aborted", "Segmentation", "Sanitizer", "#0 ", "#1 "}) {
    EXPECT_FALSE(contains(r.err, crash)) << r.err;
  }
}

constexpr std::string_view kHeader = "frame,x,y,texel_x,texel_y,cos_alpha,delta_beta_deg,kmax,kmin,dh,cd,region";
enum Column { kFrame, kX, kY, kTexelX, kTexelY, kCosAlpha, kDeltaBeta, kKmax, kKmin, kDh, kCd, kRegion, kColumns };

struct Csv {
  std::string header;
  std::vector<std::vector<std::string>> rows;

  double number(std::size_t row, Column column) const { return std::stod(rows[row][column]); }
};

Csv parse_csv(const std::string& text) {
  Csv csv;
  std::istringstream in(text);
  std::string line;
  std::getline(in, csv.header);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1) {
      cells.push_back(line.substr(start, comma - start));
    }
    cells.push_back(line.substr(start));
    csv.rows.push_back(std::move(cells));
  }
  return csv;
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
  return parse_csv(read_text(csv));
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

  expect_clean_failure(run_tool("", dir), {});  // no command
  // A misspelt command is named, with the list of commands.
  const ToolResult unknown = run_tool("trcae --step 2", dir);
  EXPECT_EQ(unknown.rc, 2);
  EXPECT_TRUE(contains(unknown.err, "unknown command 'trcae'")) << unknown.err;
  EXPECT_TRUE(contains(unknown.err, "trace")) << unknown.err;
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
  const Csv csv = parse_csv(r.out);
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
    SCOPED_TRACE("bad --step");
    expect_clean_failure(run_tool("trace --target " + kBump + " --step -1" + out, dir), {"step"});
  }
  {
    SCOPED_TRACE("bad scene file");
    const fs::path scene = dir / "bad.toml";
    std::ofstream(scene) << "[[region]]\nwidth = 20\nheight = 20\nnormal_map = \"n.png\"\nnormal_green = \"up\"\n";
    expect_clean_failure(run_tool("trace --scene " + quote(scene) + out, dir),
                         {scene.string() + ":5:", "region[0].normal_green"});
  }
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

  SCOPED_TRACE("demo");
  const ToolResult r = run_tool("demo --targets " + quote(folder), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_FALSE(contains(r.err, "writing the 24 targets")) << "the files were there: " << r.err;
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
    EXPECT_TRUE(r.err.empty()) << r.err;
    for (std::string_view part :
         {"name:Logitech*, id:046d:c077", "absolute", "0,0 2560x1440", "1.5", "'bump-gaussian-h1-r100'", "500x500",
          "curvature", "2000000 bytes", "0 invalid texels repaired"}) {
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
    EXPECT_TRUE(q.err.empty()) << q.err;
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
