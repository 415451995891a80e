// End-to-end test of `pseudohaptic accuracy --small`: the three CSV files the charts read.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
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

// Header line and rows of a CSV file.
std::pair<std::string, std::vector<std::vector<std::string>>> read_csv_rows(const fs::path& path) {
  CsvTable table = read_csv(path);
  return {table.header, std::move(table.rows)};
}

// A folder in the way of a result file fails the run before it measures (the whole run takes minutes), naming it,
// and writes none of the three files.
TEST(ToolAccuracy, AFolderInTheWayFailsBeforeTheMeasuring) {
  ScratchDir dir;
  const fs::path out = dir / "acc";
  fs::create_directories(out / "fig2_grid.csv");
  const ToolResult r = run_tool("accuracy --small " + quote(out), dir);
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_NE(r.err.find((out / "fig2_grid.csv").string() + ": is a folder"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("engine variants"), std::string::npos) << "it began measuring: " << r.err;
  EXPECT_FALSE(fs::exists(out / "variants.csv"));
}

TEST(ToolAccuracy, SmallRunWritesTheThreeCsvFiles) {
  ScratchDir dir;
  const fs::path out = dir / "acc";
  const ToolResult r = run_tool("accuracy --small " + quote(out), dir);
  ASSERT_EQ(r.rc, 0) << r.err;

  const auto [vh, variants] = read_csv_rows(out / "variants.csv");
  // Progress counts the rows it measures, against the total it said at the start.
  const std::string last = fmt::format("[{0}/{0}] ", variants.size());
  EXPECT_NE(r.err.find(fmt::format(": {} rows (", variants.size())), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(last), std::string::npos) << r.err;
  ASSERT_EQ(vh,
            "variant,method,traversal,storage,sampling,ns_per_frame_median,ns_per_frame_p99,ns_per_step,"
            "bytes_per_texel,precompute_ms,cd_err_rms,cd_err_max,end_err_rms_px,end_err_max_px,drift_px");
  std::map<std::string, std::vector<std::string>> by_variant;
  std::map<std::string, int> per_method;
  for (const auto& row : variants) {
    ASSERT_EQ(row.size(), 15u);
    for (std::size_t i = 5; i < row.size(); ++i) EXPECT_TRUE(finite_number(row[i])) << row[0] << " column " << i;
    EXPECT_TRUE(by_variant.emplace(row[0], row).second) << "duplicate " << row[0];
    ++per_method[row[1]];
  }
  EXPECT_GE(per_method["curvature"], 1);
  EXPECT_GE(per_method["depth"], 1);
  auto value = [&](const std::string& variant, std::size_t column) {
    const auto it = by_variant.find(variant);
    EXPECT_NE(it, by_variant.end()) << variant;
    return it == by_variant.end() ? NAN : std::stod(it->second[column]);
  };
  constexpr std::size_t kCdRms = 10, kEndRms = 12;
  // Quantisation costs accuracy: C/D errors grow from float to 8-bit maps for both methods, and the cursor ends
  // farther from the truth with an 8-bit depth map than with float gradients. (The end error of an 8-bit normal
  // map is not reliably above the float one: its zero-mean rounding averages out along a stroke and the
  // traversal's own error dominates; see the report in tools/cmd_accuracy.cpp.)
  EXPECT_LT(value("curvature/exact/f32/nearest", kCdRms), value("curvature/exact/n8/nearest", kCdRms));
  EXPECT_LT(value("depth/exact/f32/nearest", kCdRms), value("depth/exact/d8/nearest", kCdRms));
  EXPECT_LT(value("curvature/exact/f32/nearest", kEndRms), value("curvature/exact/d8/nearest", kEndRms));
  // The hybrid's smoothing within the map's noise: on 8-bit normal maps its C/D error is well below the curvature
  // method's (measured 0.032 against 0.071).
  EXPECT_LT(value("hybrid/exact/n8/nearest", kCdRms), 0.6 * value("curvature/exact/n8/nearest", kCdRms));

  // Each variant ends within its documented bound of the ground truth (docs/SPEED_VS_ACCURACY.md, "Error
  // bounds": the --small run's worst end error, plus a quarter, per method, traversal and sampling; 8-bit depth
  // maps apart). The run is seeded, so a variant that gets worse fails here.
  struct Bound {
    const char* prefix;  // "method/traversal/"
    const char* suffix;  // "/sampling"
    double other_px, depth8_px;
  };
  const Bound bounds[] = {
      {"curvature/exact/", "/nearest", 3, 137},
      {"curvature/exact/", "/bilinear", 5, 140},
      {"curvature/unit_steps/", "/nearest", 5, 128},
      {"curvature/unit_steps/", "/bilinear", 4, 119},
      {"curvature/frame_midpoint/", "/nearest", 8, 217},
      {"curvature/frame_midpoint/", "/bilinear", 6, 260},
      {"curvature/direction_lut8/", "/nearest", 25, 128},
      {"curvature/direction_lut16/", "/nearest", 7, 154},
      {"depth/exact/", "/nearest", 2, 28},
      {"depth/exact/", "/bilinear", 4, 16},
      {"depth/unit_steps/", "/nearest", 4, 99},
      {"depth/unit_steps/", "/bilinear", 2, 11},
      {"depth/frame_midpoint/", "/nearest", 5, 251},
      {"depth/frame_midpoint/", "/bilinear", 5, 72},
      {"depth/direction_lut8/", "/nearest", 56, 27},
      {"depth/direction_lut16/", "/nearest", 19, 28},
      {"hybrid/exact/", "/nearest", 2, 137},
      {"hybrid/exact/", "/bilinear", 5, 140},
      {"hybrid/unit_steps/", "/nearest", 2, 129},
      {"hybrid/unit_steps/", "/bilinear", 4, 128},
      {"hybrid/frame_midpoint/", "/nearest", 5, 215},
      {"hybrid/frame_midpoint/", "/bilinear", 5, 251},
      {"hybrid/direction_lut8/", "/nearest", 26, 131},
      {"hybrid/direction_lut16/", "/nearest", 7, 154},
  };
  constexpr std::size_t kEndMax = 13;
  std::size_t checked = 0;
  std::size_t autos = 0;
  for (const auto& [name, row] : by_variant) {
    if (row[2].rfind("auto", 0) == 0) {
      // traversal = "auto" runs each shape with exact or frame_midpoint, so its worst end error is never above
      // the worse of theirs on the same maps.
      const std::string maps = "/" + row[3] + "/" + row[4];
      const double worse =
          std::max(value(row[1] + "/exact" + maps, kEndMax), value(row[1] + "/frame_midpoint" + maps, kEndMax));
      EXPECT_LE(std::stod(row[kEndMax]), worse) << name;
      ++autos;
      continue;
    }
    for (const Bound& b : bounds) {
      if (name.rfind(b.prefix, 0) != 0 || name.size() < std::string(b.suffix).size() ||
          name.compare(name.size() - std::string(b.suffix).size(), std::string::npos, b.suffix) != 0) {
        continue;
      }
      const double bound = row[3] == "d8" ? b.depth8_px : b.other_px;
      EXPECT_LE(std::stod(row[kEndMax]), bound) << name << ": end error above its documented bound";
      ++checked;
    }
  }
  EXPECT_EQ(checked + autos, by_variant.size()) << "a variant without a documented bound";
  // The default budget keeps the exact walk on the accuracy set's targets; the loosest takes frame_midpoint on
  // some shape, so its strokes end elsewhere.
  EXPECT_EQ(value("curvature/auto0.25/f32/nearest", kEndRms), value("curvature/exact/f32/nearest", kEndRms));
  EXPECT_NE(value("curvature/auto8/f32/nearest", kEndRms), value("curvature/exact/f32/nearest", kEndRms));

  const auto [th, traces] = read_csv_rows(out / "fig5_traces.csv");
  ASSERT_EQ(th, "target,method,x,cd,cd_truth");
  std::map<std::string, int> trace_methods;
  for (const auto& row : traces) {
    ASSERT_EQ(row.size(), 5u);
    for (std::size_t i = 2; i < 5; ++i) EXPECT_TRUE(finite_number(row[i])) << row[0];
    ++trace_methods[row[1]];
  }
  EXPECT_GE(trace_methods["curvature"], 1);
  EXPECT_GE(trace_methods["depth"], 1);

  const auto [gh, grid] = read_csv_rows(out / "fig2_grid.csv");
  ASSERT_EQ(gh, "cos_alpha,delta_beta_deg,cd");
  ASSERT_FALSE(grid.empty());
  for (const auto& row : grid) {
    ASSERT_EQ(row.size(), 3u);
    for (const auto& cell : row) EXPECT_TRUE(finite_number(cell));
    // Uphill (cos alpha < 0) slows, downhill speeds up.
    const double c = std::stod(row[0]), cd = std::stod(row[2]);
    if (c < 0) {
      EXPECT_GE(cd, 1.0);
    }
    if (c > 0) {
      EXPECT_LE(cd, 1.0);
    }
  }
}

}  // namespace
}  // namespace ph
