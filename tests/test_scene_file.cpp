// Scene files (config/scene_file): parsing of good scenes, an error for every kind of mistake that names the
// file, the line and the key and says what is allowed, and loading the regions' images.
#include "config/scene_file.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/target_files.hpp"
#include "core/effects/effect_materials.hpp"
#include "core/effects/effect_wells.hpp"
#include "core/engine/acceleration.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/engine/targets.hpp"
#include "tests/as_nobody.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scoped_env.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& path, std::string_view text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

bool contains(const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; }

// Where scene texts of the parsing tests come from: a relative folder, so that relative paths stay relative.
const fs::path kOrigin = fs::path("scenes") / "hills.toml";

// The message of the ConfigError that parsing `text` throws, or a test failure.
std::string parse_error(std::string_view text, const fs::path& origin = kOrigin) {
  try {
    parse_scene_text(text, origin);
  } catch (const ConfigError& error) {
    return error.what();
  }
  ADD_FAILURE() << "no ConfigError for:\n" << text;
  return {};
}

// The error names the origin and the line as "FILE:LINE:", the key, and every fragment of what is allowed.
void expect_error(std::string_view text, int line, std::string_view key, std::initializer_list<std::string_view> says) {
  SCOPED_TRACE(std::string(text));
  const std::string message = parse_error(text);
  const std::string where = kOrigin.string() + ":" + std::to_string(line) + ":";
  EXPECT_EQ(message.rfind(where, 0), 0u) << "expected it to start with '" << where << "': " << message;
  EXPECT_TRUE(contains(message, key)) << "expected the key '" << key << "': " << message;
  for (std::string_view part : says) EXPECT_TRUE(contains(message, part)) << "expected '" << part << "': " << message;
}

// ---------------------------------------------------------------------------------------------------------------
// Good scenes

constexpr std::string_view kFullScene = R"(# every key
[[region]]
name = "left"
x = 10
y = -20
width = 300
height = 200
method = "curvature"
normal_map = "maps/left.normal.png"
normal_green = "directx"
normal_encoding = "signed"
depth_map = "/data/left.depth.exr"
depth_zero = 0.5
relief_px = 200

[region.curvature]
kmax_prime = 5.5
kmin_prime = 2
kmax_limits = [1.5, 20]
kmin_limits = [1, 4.5]
delta_beta_sign = -1

[region.depth]
gain = 2.5
kmax = 3
kmin = 2.0

[[region]]
width = 64
height = 32
method = "depth"
depth_map = "d.png"

[[region]]
width = 1
height = 16384
normal_map = "../up.png"
normal_encoding = "unorm"
curvature = { kmax_prime = 3.0 }
)";

TEST(SceneFileParse, ReadsEveryKey) {
  const SceneSpec spec = parse_scene_text(kFullScene, kOrigin);
  EXPECT_EQ(spec.file, kOrigin);
  ASSERT_EQ(spec.regions.size(), 3u);

  const RegionSpec& r = spec.regions[0];
  EXPECT_EQ(r.name, "left");
  EXPECT_EQ(r.line, 2);
  EXPECT_EQ(r.rect.x, 10);
  EXPECT_EQ(r.rect.y, -20);
  EXPECT_EQ(r.rect.w, 300);
  EXPECT_EQ(r.rect.h, 200);
  EXPECT_EQ(r.method, "curvature");
  ASSERT_TRUE(r.sources.normal_map);
  EXPECT_EQ(*r.sources.normal_map, fs::path("scenes") / "maps/left.normal.png");  // relative: against the folder
  ASSERT_TRUE(r.sources.depth_map);
  EXPECT_EQ(*r.sources.depth_map, fs::path("/data/left.depth.exr"));  // absolute: kept
  EXPECT_EQ(r.sources.normal_options.green, GreenConvention::directx);
  EXPECT_EQ(r.sources.normal_options.encoding, NormalEncoding::signed_values);
  EXPECT_DOUBLE_EQ(r.sources.depth_options.depth_zero, 0.5);
  EXPECT_DOUBLE_EQ(r.sources.depth_options.relief_px, 200.0);  // an integer where a number is wanted
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).kmax_prime, 5.5);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).kmin_prime, 2.0);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).kmax_lo, 1.5);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).kmax_hi, 20.0);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).kmin_lo, 1.0);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).kmin_hi, 4.5);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(r).delta_beta_sign, -1.0);
  EXPECT_DOUBLE_EQ(method_params<DepthMethod>(r).gain, 2.5);
  EXPECT_DOUBLE_EQ(method_params<DepthMethod>(r).kmax, 3.0);
  EXPECT_DOUBLE_EQ(method_params<DepthMethod>(r).kmin, 2.0);
}

TEST(SceneFileParse, FillsDefaults) {
  const SceneSpec spec = parse_scene_text(kFullScene, kOrigin);
  ASSERT_EQ(spec.regions.size(), 3u);
  const RegionSpec& r = spec.regions[1];
  const CurvatureParams curvature;
  const DepthParams depth;
  EXPECT_EQ(r.name, "region 1");
  EXPECT_EQ(r.line, 28);
  EXPECT_EQ(r.rect.x, 0);
  EXPECT_EQ(r.rect.y, 0);
  EXPECT_EQ(r.rect.w, 64);
  EXPECT_EQ(r.rect.h, 32);
  EXPECT_EQ(r.method, "depth");
  EXPECT_FALSE(r.sources.normal_map);
  ASSERT_TRUE(r.sources.depth_map);
  EXPECT_EQ(*r.sources.depth_map, fs::path("scenes") / "d.png");
  EXPECT_EQ(r.sources.normal_options.green, GreenConvention::opengl);
  EXPECT_EQ(r.sources.normal_options.encoding, NormalEncoding::automatic);
  EXPECT_DOUBLE_EQ(r.sources.depth_options.depth_zero, 0.0);
  EXPECT_DOUBLE_EQ(r.sources.depth_options.relief_px, 100.0);
  EXPECT_EQ(method_params<CurvatureMethod>(r).kmax_prime, curvature.kmax_prime);
  EXPECT_EQ(method_params<CurvatureMethod>(r).kmin_prime, curvature.kmin_prime);
  EXPECT_EQ(method_params<CurvatureMethod>(r).kmax_lo, curvature.kmax_lo);
  EXPECT_EQ(method_params<CurvatureMethod>(r).kmax_hi, curvature.kmax_hi);
  EXPECT_EQ(method_params<CurvatureMethod>(r).kmin_lo, curvature.kmin_lo);
  EXPECT_EQ(method_params<CurvatureMethod>(r).kmin_hi, curvature.kmin_hi);
  EXPECT_EQ(method_params<CurvatureMethod>(r).delta_beta_sign, 1.0);
  EXPECT_EQ(method_params<DepthMethod>(r).gain, depth.gain);
  EXPECT_EQ(method_params<DepthMethod>(r).kmax, depth.kmax);
  EXPECT_EQ(method_params<DepthMethod>(r).kmin, depth.kmin);

  // The third: the largest side, a path out of the folder, an inline curvature table with one key.
  const RegionSpec& t = spec.regions[2];
  EXPECT_EQ(t.name, "region 2");
  EXPECT_EQ(t.rect.h, 16384);
  EXPECT_EQ(t.method, "curvature");
  ASSERT_TRUE(t.sources.normal_map);
  EXPECT_EQ(*t.sources.normal_map, fs::path("scenes") / "../up.png");
  EXPECT_EQ(t.sources.normal_options.encoding, NormalEncoding::unorm);
  EXPECT_DOUBLE_EQ(method_params<CurvatureMethod>(t).kmax_prime, 3.0);
  EXPECT_EQ(method_params<CurvatureMethod>(t).kmin_prime, curvature.kmin_prime);
}

TEST(SceneFileParse, EmptySceneHasNoRegions) {
  EXPECT_TRUE(parse_scene_text("", kOrigin).regions.empty());
  EXPECT_TRUE(parse_scene_text("# nothing here\n", kOrigin).regions.empty());
}

TEST(SceneFileParse, PathsOfASceneWithoutFolderStayAsWritten) {
  const SceneSpec spec = parse_scene_text("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n", "hills.toml");
  ASSERT_EQ(spec.regions.size(), 1u);
  EXPECT_EQ(*spec.regions[0].sources.normal_map, fs::path("n.png"));
}

TEST(SceneFileParse, MethodNamesAndMethods) {
  const MethodRegistry methods = builtin_methods();
  EXPECT_EQ(methods.names(), "curvature, depth, none, hybrid");
  EXPECT_NE(methods.find("curvature"), nullptr);
  EXPECT_NE(methods.find("depth"), nullptr);
  EXPECT_EQ(methods.find("Depth"), nullptr);
  EXPECT_EQ(methods.find(""), nullptr);

  const SceneSpec spec = parse_scene_text(kFullScene, kOrigin);
  const MethodPtr curvature = make_method(spec.regions[0]);
  EXPECT_EQ(curvature->name(), "curvature");
  EXPECT_DOUBLE_EQ(curvature->cd_upper_bound(), 20.0);     // kmax_limits upper
  EXPECT_DOUBLE_EQ(curvature->cd_lower_bound(), 1 / 4.5);  // 1 / kmin_limits upper
  RegionSpec as_depth = spec.regions[0];
  as_depth.method = "depth";
  const MethodPtr depth = make_method(as_depth);
  EXPECT_EQ(depth->name(), "depth");
  EXPECT_DOUBLE_EQ(depth->cd_upper_bound(), 3.0);
  EXPECT_DOUBLE_EQ(depth->cd_lower_bound(), 0.5);
  // "none": C/D 1, for a region rendered by its effects alone; it reads no field.
  EXPECT_NE(methods.find("none"), nullptr);
  RegionSpec as_none = spec.regions[0];
  as_none.method = "none";
  const MethodPtr none = make_method(as_none);
  EXPECT_EQ(none->name(), "none");
  EXPECT_EQ(none->cd_lower_bound(), 1.0);
  EXPECT_EQ(none->cd_upper_bound(), 1.0);
  EXPECT_FALSE(none->needs().gradient || none->needs().depth);
}

// ---------------------------------------------------------------------------------------------------------------
// Errors: file, line, key, what is allowed

TEST(SceneFileErrors, UnknownTopLevelKey) {
  expect_error("title = \"hills\"\n[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n", 1, "title",
               {"unknown key", "allowed: daemon, region"});
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[regions]\nx = 1\n", 5, "regions",
               {"unknown key", "region"});
}

TEST(SceneFileErrors, UnknownRegionKeyListsTheAllowedOnes) {
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n\n[[region]]\nwidth = 2\nwidht = 3\n", 8,
               "region[1].widht",
               {"unknown key", "name", "x", "y", "width", "height", "method", "normal_map", "normal_green",
                "normal_encoding", "depth_map", "depth_zero", "relief_px", "curvature", "depth"});
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[region.curvature]\nkmax = 3\n", 6,
               "region[0].curvature.kmax",
               {"unknown key", "kmax_prime", "kmin_prime", "kmax_limits", "kmin_limits", "delta_beta_sign"});
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\ndepth = { gain = 1, kmax_prime = 3 }\n", 5,
               "region[0].depth.kmax_prime", {"unknown key", "gain", "kmax", "kmin"});
}

// In TOML a key below [region.curvature] is that table's: a region's own key written there is said as such, at its
// line, and not as missing from the region (or unknown in the table).
TEST(SceneFileErrors, ARegionsKeyBelowOneOfItsTablesIsSaidAsSuch) {
  const std::string head = "[[region]]\nname = \"a\"\nnormal_map = \"n.png\"\n";  // 3 lines
  expect_error(head + "[region.curvature]\nkmax_prime = 3\nwidth = 200\n", 6, "region[0].curvature.width",
               {"a region's own key", "[region.curvature]",
                "write it with the region's keys, above the region's first [region.NAME] table"});
  expect_error(head +
                   "width = 2\nheight = 2\n[region.materials]\nplanar = \"friction\"\n[region.materials.friction]\n"
                   "stuck_cd = 3\ndepth_map = \"d.png\"\n",
               10, "region[0].materials.friction.depth_map", {"a region's own key", "[region.materials.friction]"});
  expect_error(head + "width = 2\nheight = 2\n[region.wells]\nstrength = 0.5\nmethod = \"none\"\n", 8,
               "region[0].wells.method", {"a region's own key", "[region.wells] table's"});
}

// An unknown key is an error that lists the allowed ones, and says the one a slip away, or the table it belongs in.
TEST(SceneFileErrors, AnUnknownKeySaysWhatItLikelyMeant) {
  const std::string head = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";  // 4 lines
  expect_error(head + "normalmap = \"m.png\"\n", 5, "region[0].normalmap", {"did you mean 'normal_map'?", "allowed"});
  expect_error(head + "Relief_px = 3\n", 5, "region[0].Relief_px", {"did you mean 'relief_px'?"});
  expect_error(head + "[region.curvatur]\nkmax_prime = 3\n", 5, "region[0].curvatur", {"did you mean 'curvature'?"});
  expect_error(head + "[region.curvature]\nkmax_prmie = 3\n", 6, "region[0].curvature.kmax_prmie",
               {"did you mean 'kmax_prime'?"});
  expect_error(head + "output = \"absolute\"\n", 5, "region[0].output", {"a [daemon] key", "[daemon] table"});
  expect_error("[daemon]\nspeeed = 0.5\n", 2, "daemon.speeed", {"did you mean 'speed'?"});
  expect_error("[daemon]\nnormal_map = \"n.png\"\n", 2, "daemon.normal_map", {"a region's key", "[[region]]"});
  expect_error("width = 3\n", 1, "width", {"a region's key"});
  // Nothing close: no guess.
  const std::string far = parse_error(head + "colour = 3\n");
  EXPECT_FALSE(contains(far, "did you mean")) << far;
  EXPECT_FALSE(contains(far, "key,")) << far;
}

// A bare word where a value goes needs quotes, also one that toml++ first takes for nan, inf, true or false.
TEST(SceneFileErrors, BareWordsAreSaidToNeedQuotes) {
  for (const char* word : {"curvature", "none", "flat", "inner", "traced", "nearest"}) {
    expect_error(fmt::format("[[region]]\nwidth = 2\nheight = 2\nmethod = {}\n", word), 4, "", {"text needs quotes"});
  }
  const std::string other = parse_error("[[region]]\nname = \"open\nwidth = 2\n");
  EXPECT_FALSE(contains(other, "quotes")) << other;
}

TEST(SceneFileErrors, UnknownMethod) {
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\nmethod = \"height\"\n", 5,
               "region[0].method", {"'height'", "curvature", "depth"});
}

TEST(SceneFileErrors, WrongTypes) {
  const std::string head = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";  // 4 lines
  expect_error(head + "name = 5\n", 5, "region[0].name", {"must be a string"});
  expect_error(head + "x = 1.5\n", 5, "region[0].x", {"whole number"});
  expect_error(head + "y = \"3\"\n", 5, "region[0].y", {"whole number"});
  expect_error("[[region]]\nheight = 2\nnormal_map = \"n.png\"\nwidth = \"500\"\n", 4, "region[0].width",
               {"whole number"});
  expect_error(head + "method = 1\n", 5, "region[0].method", {"must be a string"});
  expect_error(head + "depth_map = true\n", 5, "region[0].depth_map", {"must be a string"});
  expect_error(head + "normal_green = [\"opengl\"]\n", 5, "region[0].normal_green", {"must be a string"});
  expect_error(head + "depth_zero = \"half\"\n", 5, "region[0].depth_zero", {"must be a number"});
  expect_error(head + "relief_px = true\n", 5, "region[0].relief_px", {"must be a number"});
  expect_error(head + "curvature = 3\n", 5, "region[0].curvature", {"must be a table"});
  expect_error(head + "depth = \"deep\"\n", 5, "region[0].depth", {"must be a table"});
  expect_error(head + "[region.curvature]\nkmax_prime = \"big\"\n", 6, "region[0].curvature.kmax_prime",
               {"must be a number"});
  expect_error(head + "[region.depth]\ngain = [1]\n", 6, "region[0].depth.gain", {"must be a number"});
}

TEST(SceneFileErrors, MissingSize) {
  expect_error("\n[[region]]\nheight = 2\nnormal_map = \"n.png\"\n", 2, "region[0].width", {"required"});
  expect_error("[[region]]\nwidth = 2\nnormal_map = \"n.png\"\n", 1, "region[0].height", {"required"});
}

TEST(SceneFileErrors, SizeAndPositionOutOfRange) {
  expect_error("[[region]]\nwidth = 0\nheight = 2\nnormal_map = \"n.png\"\n", 2, "region[0].width",
               {"between 1 and 16384", "got 0"});
  expect_error("[[region]]\nwidth = 100000\nheight = 2\nnormal_map = \"n.png\"\n", 2, "region[0].width",
               {"between 1 and 16384", "got 100000"});
  expect_error("[[region]]\nwidth = 2\nheight = -5\nnormal_map = \"n.png\"\n", 3, "region[0].height",
               {"between 1 and 16384"});
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\nx = 9999999999\n", 5, "region[0].x",
               {"between"});
  // Each side within its bound, the whole beyond what a region may hold: said at its height.
  expect_error("[[region]]\nwidth = 16384\nheight = 4097\nnormal_map = \"n.png\"\n", 3, "region[0].height",
               {"16384 x 4097", "67125248 px", "8192 x 8192"});
  for (const char* size : {"width = 16384\nheight = 4096", "width = 8192\nheight = 8192"}) {
    const SceneSpec largest = parse_scene_text(fmt::format("[[region]]\n{}\nnormal_map = \"n.png\"\n", size), kOrigin);
    EXPECT_EQ(std::int64_t{largest.regions[0].rect.w} * largest.regions[0].rect.h, kMaxRegionTexels) << size;
  }
}

TEST(SceneFileErrors, BadNormalOptions) {
  const std::string head = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";
  expect_error(head + "normal_green = \"up\"\n", 5, "region[0].normal_green", {"\"opengl\"", "\"directx\""});
  expect_error(head + "normal_encoding = \"float\"\n", 5, "region[0].normal_encoding",
               {"\"auto\"", "\"unorm\"", "\"signed\""});
}

// A region's name goes into log lines, status and CSV cells: empty or with control characters it is refused; a comma
// or a quote is kept (the CSV quotes it).
TEST(SceneFileErrors, RegionNames) {
  const std::string tail = "width = 2\nheight = 2\nnormal_map = \"n.png\"\n";
  expect_error("[[region]]\nname = \"\"\n" + tail, 2, "region[0].name", {"must not be empty"});
  expect_error("[[region]]\nname = \"two\\nlines\"\n" + tail, 2, "region[0].name", {"control characters"});
  expect_error("[[region]]\nname = \"a\\tb\"\n" + tail, 2, "region[0].name", {"control characters"});
  // C1 controls (NEL) and the Unicode line and paragraph separators break lines too; a name of spaces names nothing.
  for (const char* name : {"a\\u0085b", "a\\u2028b", "a\\u2029b", "a\\u009fb"})
    expect_error("[[region]]\nname = \"" + std::string(name) + "\"\n" + tail, 2, "region[0].name",
                 {"control characters"});
  expect_error("[[region]]\nname = \"   \"\n" + tail, 2, "region[0].name", {"must hold more than spaces"});
  EXPECT_EQ(parse_scene_text("[[region]]\nname = \"h\u00f6he \u2013 bump\"\n" + tail, kOrigin).regions.at(0).name,
            "h\u00f6he \u2013 bump");  // other non-ASCII letters and dashes are kept
  EXPECT_EQ(parse_scene_text("[[region]]\nname = 'bump, \"big\"'\n" + tail, kOrigin).regions.at(0).name,
            "bump, \"big\"");
  // Two regions of one name could not be told apart in the logs or in trace's CSV; nor a name that is another
  // region's default.
  expect_error("[[region]]\nname = \"b\"\n" + tail + "[[region]]\nname = \"b\"\n" + tail, 7, "region[1].name",
               {"'b' is already the name of region[0] (line 1)"});
  expect_error("[[region]]\nname = \"region 1\"\n" + tail + "[[region]]\n" + tail, 6, "region[1].name",
               {"'region 1' is already the name of region[0] (line 1)"});
  EXPECT_EQ(parse_scene_text("[[region]]\n" + tail + "[[region]]\n" + tail, kOrigin).regions.at(1).name, "region 1");
}

TEST(SceneFileErrors, NonFiniteDepthOptions) {
  const std::string head = "[[region]]\nwidth = 2\nheight = 2\ndepth_map = \"d.png\"\n";
  expect_error(head + "depth_zero = inf\n", 5, "region[0].depth_zero", {"finite"});
  expect_error(head + "relief_px = nan\n", 5, "region[0].relief_px", {"finite"});
  // Beyond a million px per unit the heights of a unorm map overflow a float, and every texel reads as invalid.
  expect_error(head + "relief_px = 1e308\n", 5, "region[0].relief_px", {"from -1e+06 to 1e+06"});
  expect_error(head + "relief_px = -2e6\n", 5, "region[0].relief_px", {"from -1e+06 to 1e+06"});
  // Beyond a million, v - depth_zero keeps none of v: every height the same, or infinite.
  expect_error(head + "depth_zero = 1e38\n", 5, "region[0].depth_zero", {"from -1e+06 to 1e+06"});
  EXPECT_EQ(parse_scene_text(head + "depth_zero = 4000.0\n", kOrigin).regions.at(0).sources.depth_options.depth_zero,
            4000.0);  // an elevation map's sea level, in metres
}

// Two regions, the bad limits on line 12, in the second region's [region.curvature] table (line 10).
std::string limits_scene(std::string_view line12) {
  return "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n\n"
         "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[region.curvature]\nkmax_prime = 3\n" +
         std::string(line12) + "\n";
}

TEST(SceneFileErrors, LimitsNotAPair) {
  expect_error(limits_scene("kmax_limits = 3"), 12, "region[1].curvature.kmax_limits", {"pair", "[lower, upper]"});
  expect_error(limits_scene("kmax_limits = [1, 2, 3]"), 12, "region[1].curvature.kmax_limits", {"pair"});
  expect_error(limits_scene("kmin_limits = [1]"), 12, "region[1].curvature.kmin_limits", {"pair"});
  expect_error(limits_scene("kmin_limits = [\"1\", \"2\"]"), 12, "region[1].curvature.kmin_limits", {"pair"});
}

TEST(SceneFileErrors, LimitsLowerAboveUpper) {
  expect_error(limits_scene("kmax_limits = [5, 2]"), 12, "region[1].curvature.kmax_limits", {"1 <= lower <= upper"});
  expect_error(limits_scene("kmin_limits = [3.5, 3]"), 12, "region[1].curvature.kmin_limits", {"1 <= lower <= upper"});
  // A C/D of 1e300 is a wall the hand never crosses: at most 100 either way.
  expect_error(limits_scene("kmax_limits = [1, 1e300]"), 12, "region[1].curvature.kmax_limits", {"upper <= 100"});
  expect_error(limits_scene("kmin_limits = [1, 101]"), 12, "region[1].curvature.kmin_limits", {"upper <= 100"});
}

TEST(SceneFileErrors, LimitsBelowOne) {
  expect_error(limits_scene("kmax_limits = [0.5, 2]"), 12, "region[1].curvature.kmax_limits", {"1 <= lower"});
  expect_error(limits_scene("kmin_limits = [0, 3]"), 12, "region[1].curvature.kmin_limits", {"1 <= lower"});
}

TEST(SceneFileErrors, BadMethodParameters) {
  const std::string head = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";
  expect_error(head + "[region.curvature]\ndelta_beta_sign = 0\n", 6, "region[0].curvature.delta_beta_sign",
               {"1 or -1"});
  expect_error(head + "[region.curvature]\ndelta_beta_sign = 0.5\n", 6, "region[0].curvature.delta_beta_sign",
               {"1 or -1"});
  expect_error(head + "[region.curvature]\nkmax_prime = -1\n", 6, "region[0].curvature.kmax_prime", {"> 0"});
  expect_error(head + "[region.depth]\nkmin = 0.5\n", 6, "region[0].depth.kmin", {"from 1 to 100"});
  expect_error(head + "depth = { kmax = 0.9 }\n", 5, "region[0].depth.kmax", {"from 1 to 100"});
  expect_error(head + "[region.depth]\nkmin = 1e300\n", 6, "region[0].depth.kmin", {"from 1 to 100"});
}

// A depth region whose gain is 0 feels flat: warned of, as relief_px = 0 is; a curvature region with the same table
// (which trace --method depth would use) is not.
TEST(SceneFileWarnings, ADepthGainOfZeroIsWarnedOf) {
  const std::string region =
      "[[region]]\nname = \"{}\"\nwidth = 2\nheight = 2\ndepth_map = \"d.png\"\n"
      "method = \"{}\"\n[region.depth]\ngain = {}\n";
  const SceneSpec spec = parse_scene_text(fmt::format(fmt::runtime(region), "still", "depth", 0) +
                                              fmt::format(fmt::runtime(region), "sloped", "depth", 3) +
                                              fmt::format(fmt::runtime(region), "other", "curvature", 0),
                                          kOrigin);
  const std::vector<std::string> warnings = method_warnings(spec);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], kOrigin.string() +
                             ":1: region 'still': depth.gain = 0 makes the depth method's C/D 1 everywhere: the "
                             "region feels flat");
}

// A negative gain turns the relief over for the depth method alone: allowed, and said, with the key that reads a
// white-is-deep map the right way round.
TEST(SceneFileWarnings, ANegativeDepthGainIsWarnedOf) {
  const std::string region =
      "[[region]]\nname = \"{}\"\nwidth = 2\nheight = 2\ndepth_map = \"d.png\"\n"
      "method = \"depth\"\n[region.depth]\ngain = {}\n";
  const SceneSpec spec = parse_scene_text(
      fmt::format(fmt::runtime(region), "turned", -2.5) + fmt::format(fmt::runtime(region), "upright", 0.5), kOrigin);
  const std::vector<std::string> warnings = method_warnings(spec);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], kOrigin.string() +
                             ":1: region 'turned': depth.gain = -2.5 turns the relief over: bumps are felt as holes "
                             "(for a depth map stored white-is-deep, a negative relief_px reads it the right way "
                             "round instead)");
}

// A method table for a method the region does not use is read by nothing the daemon does: said, with where it is
// read (trace --method). A hybrid region takes the curvature and depth methods' defaults, not their tables.
TEST(SceneFileWarnings, AMethodTableTheRegionsMethodDoesNotReadIsWarnedOf) {
  const SceneSpec spec = parse_scene_text(
      "[[region]]\nname = \"h\"\nwidth = 2\nheight = 2\nmethod = \"hybrid\"\nnormal_map = \"n.png\"\n"
      "depth_map = \"d.png\"\n[region.curvature]\nkmax_prime = 20.0\n[region.hybrid]\n"
      "[[region]]\nname = \"c\"\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[region.curvature]\n",
      kOrigin);
  const std::vector<std::string> warnings = unused_method_table_warnings(spec);
  ASSERT_EQ(warnings.size(), 1u);  // the curvature region's own table is read
  EXPECT_EQ(warnings[0], kOrigin.string() +
                             ":8: region 'h': [region.curvature] changes nothing here: the region's method is hybrid, "
                             "which takes the curvature and depth methods' defaults (only `pseudohaptic trace` and "
                             "`replay` with --method curvature read it)");
  // Under a tool's --method the region's method changes: the file's own method's table (read by the daemon) and the
  // one --method reads are not warned of.
  SceneSpec replaced = spec;
  for (RegionSpec& r : replaced.regions) r.method = "depth";
  EXPECT_EQ(unused_method_table_warnings(replaced).size(), 1u);  // still the hybrid region's [region.curvature]
  for (RegionSpec& r : replaced.regions) r.method = "curvature";
  EXPECT_TRUE(unused_method_table_warnings(replaced).empty());
}

// mouse_dpi is read by the adaptive profile alone: set beside the flat one (relative output's default) it changes
// nothing, which is said; with the adaptive profile, or left out, nothing is.
// pseudohaptic(1) says check-config warns of keys that change nothing where they are: a decoding key without its map.
TEST(SceneFileWarnings, ADecodingKeyWithoutItsMapIsWarnedOf) {
  const SceneSpec spec = parse_scene_text(
      "[[region]]\nname = \"n\"\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\nrelief_px = 40\ndepth_zero = 0.5\n"
      "normal_green = \"directx\"\n"
      "[[region]]\nname = \"d\"\nwidth = 2\nheight = 2\ndepth_map = \"d.png\"\nnormal_encoding = \"unorm\"\n"
      "relief_px = 40\n",
      kOrigin);
  const std::vector<std::string> warnings = unused_key_warnings(spec);
  ASSERT_EQ(warnings.size(), 3u) << fmt::format("{}", fmt::join(warnings, "\n"));
  EXPECT_EQ(warnings[0], kOrigin.string() +
                             ":7: region 'n': depth_zero changes nothing: it says how to read a "
                             "depth_map, which the region has not");
  EXPECT_EQ(warnings[1], kOrigin.string() +
                             ":6: region 'n': relief_px changes nothing: it says how to read a "
                             "depth_map, which the region has not");
  EXPECT_EQ(warnings[2], kOrigin.string() +
                             ":14: region 'd': normal_encoding changes nothing: it says how to read a "
                             "normal_map, which the region has not");
  // With both maps, none.
  EXPECT_TRUE(
      unused_key_warnings(parse_scene_text("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n"
                                           "depth_map = \"d.png\"\nrelief_px = 40\nnormal_green = \"directx\"\n",
                                           kOrigin))
          .empty());
}

TEST(SceneFileWarnings, AMouseDpiTheFlatProfileDoesNotReadIsWarnedOf) {
  const auto warnings = [](const std::string& daemon) {
    return daemon_warnings(parse_scene_text("[daemon]\n" + daemon, kOrigin));
  };
  const std::vector<std::string> flat = warnings("output = \"relative\"\nmouse_dpi = 1600\n");
  ASSERT_EQ(flat.size(), 1u);
  EXPECT_EQ(flat[0].rfind(kOrigin.string() + ":3: daemon.mouse_dpi changes nothing with the flat profile", 0), 0u)
      << flat[0];
  EXPECT_EQ(warnings("acceleration = \"flat\"\nmouse_dpi = 1600\n").size(), 1u);
  EXPECT_TRUE(warnings("acceleration = \"adaptive\"\nmouse_dpi = 1600\n").empty());
  EXPECT_TRUE(warnings("mouse_dpi = 1600\n").empty());  // absolute output: adaptive by default
  EXPECT_TRUE(warnings("acceleration = \"flat\"\n").empty());
}

// The [daemon] table's lut_directions is read only by a walk with direction tables: the [daemon] traversal's, or a
// region's that sets traversal = "direction_lut" without a count of its own. Set where none reads it, it is said.
TEST(SceneFileWarnings, ALutDirectionsNoWalkReadsIsWarnedOf) {
  const auto warnings = [](const std::string& text) { return daemon_warnings(parse_scene_text(text, kOrigin)); };
  const std::string region = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";
  const std::vector<std::string> unread = warnings("[daemon]\ntraversal = \"exact\"\nlut_directions = 16\n" + region);
  ASSERT_EQ(unread.size(), 1u);
  EXPECT_EQ(unread[0].rfind(kOrigin.string() + ":3: daemon.lut_directions changes nothing", 0), 0u) << unread[0];
  EXPECT_EQ(warnings("[daemon]\nlut_directions = 8\n" + region +
                     "traversal = \"direction_lut\"\n"
                     "lut_directions = 16\n")
                .size(),
            1u);  // the one region that walks with tables counts its own directions
  EXPECT_EQ(warnings("[daemon]\nlut_directions = 8\n" + region + "traversal = \"auto\"\n").size(), 1u);
  EXPECT_TRUE(warnings("[daemon]\nlut_directions = 8\n" + region + "traversal = \"direction_lut\"\n").empty());
  EXPECT_TRUE(warnings("[daemon]\ntraversal = \"direction_lut\"\nlut_directions = 8\n" + region).empty());
  EXPECT_TRUE(warnings("[daemon]\ntraversal = \"exact\"\n" + region).empty());
}

TEST(SceneFileErrors, DepthMethodWithoutDepthMap) {
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\nmethod = \"depth\"\n", 1,
               "region[0].depth_map", {"depth method needs a depth_map"});
}

TEST(SceneFileErrors, RegionWithoutMap) {
  expect_error("[[region]]\nwidth = 2\nheight = 2\n\n[[region]]\nwidth = 2\nheight = 2\n", 1, "region[0]",
               {"normal_map", "depth_map"});
}

TEST(SceneFileErrors, TomlSyntaxErrorReportsTheLine) {
  const std::string m1 = parse_error("[[region]]\nwidth = 2\nheight = = 2\n");
  EXPECT_EQ(m1.rfind(kOrigin.string() + ":3:", 0), 0u) << m1;
  const std::string m2 = parse_error("[[region]]\nwidth = 2\n\nname = \"open\nheight = 2\n");
  EXPECT_EQ(m2.rfind(kOrigin.string() + ":4:", 0), 0u) << m2;
  const std::string m3 = parse_error("[[region]]\nwidth = 2\nwidth = 3\n");  // a key given twice
  EXPECT_EQ(m3.rfind(kOrigin.string() + ":3:", 0), 0u) << m3;
}

TEST(SceneFileErrors, RegionMustBeAnArrayOfTables) {
  expect_error("[region]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n", 1, "region", {"[[region]]"});
  expect_error("\nregion = 5\n", 2, "region", {"[[region]]"});
  expect_error("region = [1, 2]\n", 1, "region", {"[[region]]"});
  expect_error("region = [{ width = 2, height = 2, normal_map = \"n.png\" }, 3]\n", 1, "region", {"[[region]]"});
}

// traversal = "auto" chooses among nearest-sampling variants: bilinear asked for in the region is an error at its
// line; the [daemon] table's bilinear, the other regions' default, does not apply to it.
TEST(SceneFileErrors, AutoWithBilinearSamplingInTheRegionIsRefusedAndNotInherited) {
  const std::string region = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\ntraversal = \"auto\"\n";
  expect_error(region + "sampling = \"bilinear\"\n", 6, "region[0].sampling",
               {"chooses with nearest sampling", "set sampling = \"nearest\" or leave it out"});
  const SceneSpec spec = parse_scene_text("[daemon]\nsampling = \"bilinear\"\n" + region, kOrigin);
  EXPECT_EQ(spec.daemon.engine.sampling, Sampling::bilinear);
  ASSERT_EQ(spec.regions.size(), 1u);
  ASSERT_TRUE(spec.regions[0].engine.has_value());
  EXPECT_TRUE(spec.regions[0].engine_auto);
  EXPECT_EQ(spec.regions[0].engine->sampling, Sampling::nearest);
}

// A map's path that is empty, or a folder, is said as such at its line: "" used to resolve to the scene file's own
// folder and reach the image reader, which said "ImageInput::create() called with no filename" or could not find "a
// format reader".
TEST(SceneFileErrors, AnEmptyMapPathOrAFolderIsSaidAsSuch) {
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"\"\n", 4, "region[0].normal_map",
               {"must be the path of an image file, not empty"});
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\ndepth_map = \"\"\n", 5,
               "region[0].depth_map", {"not empty"});
  const ScratchDir dir("scene-folder-map");
  std::filesystem::create_directories(dir / "maps");
  const SceneSpec spec =
      parse_scene_text("[[region]]\nname = \"r\"\nwidth = 2\nheight = 2\nnormal_map = \"maps\"\n", dir / "scene.toml");
  try {
    load_scene(spec);
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_TRUE(contains(e.what(), (dir / "scene.toml").string() + ":5: region 'r': normal_map " +
                                       (dir / "maps").string() + ": is a folder, not an image file"))
        << e.what();
  }
}

// check-config run as root reads what the service's own user cannot: a file only its owner may read (made under a
// umask of 077), or one in a folder others may not enter. Said, with the key's line.
TEST(SceneFileErrors, FilesOthersCannotReadAreWarnedOf) {
  const ScratchDir dir("scene-private");
  using std::filesystem::perms;
  std::filesystem::permissions(dir.path(), perms::owner_all | perms::others_exec);
  std::filesystem::create_directories(dir / "private");
  std::filesystem::permissions(dir / "private", perms::owner_all);
  for (const char* name : {"private/n.png", "private/scene.toml", "mine.png", "open.png"})
    std::ofstream(dir / name) << "x";
  std::filesystem::permissions(dir / "mine.png", perms::owner_read | perms::owner_write);
  // The folders above the scratch folder are the machine's: open.png is readable where they all let others through.
  bool above_open = true;
  for (fs::path f = dir.path().parent_path(); !f.empty(); f = f.parent_path()) {
    above_open = above_open && (fs::status(f).permissions() & perms::others_exec) != perms::none;
    if (f == f.root_path()) break;
  }
  EXPECT_EQ(unreadable_by_others(dir / "open.png").has_value(), !above_open);
  // Reached through a link, the folders its target lies in count too.
  fs::create_symlink(dir / "private/scene.toml", dir / "link.toml");
  ASSERT_TRUE(unreadable_by_others(dir / "link.toml").has_value());
  EXPECT_TRUE(contains(*unreadable_by_others(dir / "link.toml"), "the folder " + (dir / "private").string()));
  // The service's groups (SupplementaryGroups=input uinput) read what they own.
  if (const ::group* input = ::getgrnam("input")) {
    std::ofstream(dir / "input.png") << "x";
    ASSERT_EQ(::chown((dir / "input.png").c_str(), static_cast<uid_t>(-1), input->gr_gid), 0);
    std::filesystem::permissions(dir / "input.png", perms::owner_read | perms::owner_write | perms::group_read);
    EXPECT_EQ(unreadable_by_others(dir / "input.png").has_value(), !above_open);
  }
  ASSERT_TRUE(unreadable_by_others(dir / "mine.png").has_value());
  EXPECT_TRUE(contains(*unreadable_by_others(dir / "mine.png"), "its mode 600 does not let others read it"));
  ASSERT_TRUE(unreadable_by_others(dir / "private/n.png").has_value());
  EXPECT_TRUE(contains(*unreadable_by_others(dir / "private/n.png"),
                       "the folder " + (dir / "private").string() + " (mode 700) does not let others through"));
  EXPECT_FALSE(unreadable_by_others(dir / "missing.png").has_value());  // the load says it is missing
  const SceneSpec spec = parse_scene_text(
      "[[region]]\nname = \"p\"\nwidth = 2\nheight = 2\nmethod = \"hybrid\"\nnormal_map = \"mine.png\"\n"
      "depth_map = \"private/n.png\"\n",
      "/etc/pseudohaptic/scene.toml");
  SceneSpec in_scratch = spec;
  in_scratch.file = dir / "private/scene.toml";
  in_scratch.regions[0].sources.normal_map = dir / "mine.png";
  in_scratch.regions[0].sources.depth_map = dir / "private/n.png";
  const std::string said = fmt::format("{}", fmt::join(service_path_warnings(in_scratch), "\n"));
  // (The scratch folder lies under /tmp, which the service does not see: that warning comes first where it does.)
  if (!hidden_from_the_service(dir.path())) {
    EXPECT_TRUE(contains(said, (dir / "private/scene.toml").string() + ": the folder " + (dir / "private").string() +
                                   " (mode 700) does not let others through; pseudohapticd.service runs as a user of "
                                   "its own (DynamicUser=yes)"))
        << said;
    EXPECT_TRUE(contains(said, (dir / "private/scene.toml").string() + ":6: region 'p': normal_map " +
                                   (dir / "mine.png").string() + ": its mode 600"))
        << said;
    EXPECT_TRUE(contains(said, ":7: region 'p': depth_map ")) << said;
    EXPECT_TRUE(contains(said, "DynamicUser=yes")) << said;
  } else {
    EXPECT_TRUE(contains(said, (dir / "private/scene.toml").string() + " lies under ")) << said;
    EXPECT_TRUE(contains(said, ":6: region 'p': normal_map " + (dir / "mine.png").string() + " lies under")) << said;
  }
}

// An image that cannot be read, or is not the kind of map its key says, is said at that key's line and names the key
// (the region's header line and the path alone left the reader to find which of two maps it was).
TEST(SceneFileErrors, AnImagesErrorNamesItsKeyAndLine) {
  ScratchDir dir;
  const TargetSpec target = all_targets().front();
  write_target_files(dir.path(), {target});
  const std::string normals = target.name() + ".normal.png";
  const auto error_of = [&](const std::string& text) -> std::string {
    try {
      load_scene(parse_scene_text(text, dir / "scene.toml"));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "no ConfigError";
  };
  const std::string missing =
      error_of("[[region]]\nname = \"a\"\nwidth = 500\nheight = 500\n\nnormal_map = \"nothere.png\"\ndepth_map = \"" +
               normals + "\"\n");
  EXPECT_TRUE(contains(missing, (dir / "scene.toml").string() +
                                    ":6: region 'a': normal_map: " + (dir / "nothere.png").string() + ": cannot open"))
      << missing;
  // A normal map (three channels) given as the depth map.
  const std::string wrong = error_of(
      "[[region]]\nname = \"d\"\nmethod = \"depth\"\nwidth = 500\nheight = 500\n"
      "depth_map = \"" +
      normals + "\"\n");
  EXPECT_TRUE(contains(wrong, ":6: region 'd': depth_map: " + (dir / normals).string() + ": ")) << wrong;
}

// An effect's parameter out of its range is said at the key's own line, not at its table's header.
TEST(SceneFileErrors, AnEffectsParameterOutOfRangeNamesItsLine) {
  const std::string region = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";
  expect_error(region +
                   "[region.materials]\nplanar = \"friction\"\n[region.materials.friction]\nbreakaway_px = 10.0\n"
                   "stuck_cd = 50\n",
               9, "region[0].materials", {"friction.stuck_cd = 50 is outside [1, 20]"});
  expect_error(region + "[region.wells]\nradius_px = 16\nmax_gain = 9\n", 7, "region[0].wells", {"max_gain"});
  // The key is `tolerance` in the file, whatever the field is called in the code.
  expect_error(region + "[region.wells]\nradius_px = 16\nrule = \"band\"\ntolerance = -1\n", 8, "region[0].wells",
               {"wells isophote tolerance must be a finite number >= 0"});
  // A tolerance for the crossing rule (the default), which has none, and an empty list of levels, which would read
  // as the default count, are said rather than ignored.
  expect_error(region + "[region.wells]\nradius_px = 16\ntolerance = 0.1\n", 7, "region[0].wells.tolerance",
               {"is for rule = \"band\""});
  expect_error(
      "[[region]]\nwidth = 2\nheight = 2\ndepth_map = \"d.png\"\n[region.wells]\npattern = \"contours\"\n"
      "levels = []\n",
      7, "region[0].wells.levels", {"is an empty list"});
}

// A huge file given by mistake is refused once past the longest scene file, not read into memory; /dev/zero, a
// device, is not read at all (and /dev/null is an empty scene).
TEST(SceneFileErrors, AFileLongerThanAnySceneIsRefused) {
  try {
    parse_scene_file("/dev/zero");  // a device: not read at all
    ADD_FAILURE() << "expected an error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/dev/zero: is not a regular file (a FIFO, a device or a socket), not a scene file");
  }
  EXPECT_TRUE(parse_scene_file("/dev/null").regions.empty());
  const ScratchDir dir("scene-long");
  std::string text = "# a comment\n";
  text.resize(kMaxSceneFileBytes, ' ');
  std::ofstream(dir / "just.toml", std::ios::binary) << text;
  EXPECT_TRUE(parse_scene_file(dir / "just.toml").regions.empty());  // at the bound: read
  std::ofstream(dir / "over.toml", std::ios::binary) << text << ' ';
  try {
    parse_scene_file(dir / "over.toml");
    ADD_FAILURE() << "expected an error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "over.toml").string() + ": longer than 4 MiB, which no scene file is: is it the file meant?");
  }
}

TEST(SceneFileErrors, MissingSceneFileIsNamed) {
  const fs::path missing = "/ph-test-no-such-folder/nope.toml";  // not where the service's sandbox hides files
  try {
    parse_scene_file(missing);
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_TRUE(contains(e.what(), missing.string())) << e.what();
    EXPECT_TRUE(contains(e.what(), "cannot open the scene file: No such file or directory")) << e.what();
    EXPECT_FALSE(contains(e.what(), "pseudohapticd.service")) << e.what();
  }
}

// pseudohapticd.service hides /home, /root and /run/user (ProtectHome=yes), and has a /tmp and /var/tmp of its own
// (PrivateTmp=yes): a scene that works by hand and in check-config fails under the service, where its files are
// simply not there. Both are said.
TEST(SceneFileErrors, FilesTheServiceCannotReadAreWarnedOfAndNamedWhenMissing) {
  const auto folder = [](const char* path) {
    const std::optional<HiddenFolder> hidden = hidden_from_the_service(path);
    return hidden ? std::string(hidden->folder) + " " + std::string(hidden->setting) : std::string("readable");
  };
  EXPECT_EQ(folder("/home/ann/maps/n.png"), "/home ProtectHome=yes");
  EXPECT_EQ(folder("/root/n.png"), "/root ProtectHome=yes");
  EXPECT_EQ(folder("/run/user/1000/n.png"), "/run/user ProtectHome=yes");
  EXPECT_EQ(folder("/tmp/maps/n.png"), "/tmp PrivateTmp=yes");
  EXPECT_EQ(folder("/var/tmp/n.png"), "/var/tmp PrivateTmp=yes");
  EXPECT_EQ(folder("/home/../etc/pseudohaptic/n.png"), "readable");
  for (const char* readable : {"/homework/n.png", "/run/udev/n.png", "/etc/pseudohaptic/n.png",
                               "/usr/local/share/n.png", "/tmpfs/n.png", "/var/lib/n.png"})
    EXPECT_EQ(folder(readable), "readable") << readable;
  // A link outside the hidden folders that leads into one: /proc/self/root is a link to /.
  EXPECT_EQ(folder("/proc/self/root/tmp/ph-test-maps/n.png"), "/tmp PrivateTmp=yes");
  // Also where the link's target cannot be entered (as under the service, to which the folder is hidden): the link
  // itself is read, not where it leads.
  const ScratchDir dir("scene-hidden-link");
  std::filesystem::create_directories(dir / "private");
  std::filesystem::permissions(dir.path(), std::filesystem::perms::all);
  std::filesystem::permissions(dir / "private", std::filesystem::perms::owner_all);
  std::ofstream(dir / "private/n.png") << "x";
  const std::optional<HiddenFolder> direct = hidden_from_the_service(dir / "private/n.png");
  const std::string through_link = "/proc/self/root" + (dir / "private/n.png").string();
  if (::getuid() != 0) std::filesystem::permissions(dir / "private", std::filesystem::perms::none);
  EXPECT_EQ(as_nobody([&] { return hidden_from_the_service(through_link) == direct ? 1 : 0; }), 1);
  std::filesystem::permissions(dir / "private", std::filesystem::perms::owner_all);

  const std::string missing_home = "/home/ph-test-no-such-user/maps";
  const SceneSpec spec = parse_scene_text(
      "[[region]]\nname = \"mine\"\nwidth = 2\nheight = 2\nmethod = \"hybrid\"\n"
      "normal_map = \"" +
          missing_home + "/n.png\"\ndepth_map = \"/etc/d.png\"\n",
      "/etc/pseudohaptic/scene.toml");
  const std::vector<std::string> warnings = service_path_warnings(spec);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "/etc/pseudohaptic/scene.toml:6: region 'mine': normal_map " + missing_home +
                                        "/n.png lies under /home, which pseudohapticd.service cannot read"))
      << warnings[0];
  EXPECT_TRUE(service_path_warnings(parse_scene_text("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"/etc/n.png\"\n",
                                                     "/etc/pseudohaptic/scene.toml"))
                  .empty());
  // The hint is for the service (started by systemd, which sets INVOCATION_ID): run by hand, a file missing there is
  // missing, and the hint would point at the wrong cause.
  // (A scene file missing under /run/user: a folder the user may search, so that the error is "No such file or
  // directory" whoever runs the test; under /root it is "Permission denied" for anyone but root.)
  const std::string missing_scene = "/run/user/" + std::to_string(::getuid()) + "/ph-test-no-such/scene.toml";
  for (const bool under_systemd : {false, true}) {
    SCOPED_TRACE(under_systemd ? "under systemd" : "run by hand");
    // Unset run by hand: as where a service started the tests.
    const ScopedEnv invocation(
        "INVOCATION_ID", under_systemd ? std::optional<std::string>("0123456789abcdef0123456789abcdef") : std::nullopt);
    try {
      load_scene(spec);
      ADD_FAILURE() << "no ConfigError";
    } catch (const ConfigError& e) {
      EXPECT_EQ(contains(e.what(), "(/home is hidden from pseudohapticd.service, ProtectHome=yes"), under_systemd)
          << e.what();
    }
    try {
      parse_scene_file(missing_scene);
      ADD_FAILURE() << "no ConfigError";
    } catch (const ConfigError& e) {
      EXPECT_TRUE(contains(e.what(), "No such file or directory")) << e.what();
      EXPECT_EQ(contains(e.what(), "(/run/user is hidden from pseudohapticd.service"), under_systemd) << e.what();
    }
  }
  // The scene file itself, where a drop-in's -c would point the service: warned of as its images are.
  for (const char* file : {"/tmp/scene.toml", "/home/ph-test-no-such-user/scene.toml"}) {
    const std::vector<std::string> scene_hidden = service_path_warnings(parse_scene_text("", file));
    ASSERT_EQ(scene_hidden.size(), 1u) << file;
    EXPECT_EQ(scene_hidden[0].rfind(std::string(file) + " lies under /", 0), 0u) << scene_hidden[0];
    EXPECT_TRUE(contains(scene_hidden[0], "which pseudohapticd.service cannot read")) << scene_hidden[0];
  }
  const std::vector<std::string> in_tmp = service_path_warnings(
      parse_scene_text("[[region]]\nname = \"tried\"\nwidth = 2\nheight = 2\nnormal_map = \"/tmp/targets/n.png\"\n",
                       "/etc/pseudohaptic/scene.toml"));
  ASSERT_EQ(in_tmp.size(), 1u);
  EXPECT_TRUE(contains(in_tmp[0],
                       "normal_map /tmp/targets/n.png lies under /tmp, which pseudohapticd.service cannot "
                       "read (PrivateTmp=yes; the daemon run by hand can)"))
      << in_tmp[0];
  // A map the region names but neither its method nor an effect reads is not opened: nothing to warn of (a target's
  // scene names both maps; the curvature method reads the normals alone). The depth method reads the heights alone.
  const std::string both_maps =
      "[[region]]\nname = \"t\"\nwidth = 2\nheight = 2\nnormal_map = "
      "\"/tmp/targets/n.png\"\ndepth_map = \"/tmp/targets/d.png\"\n";
  const std::vector<std::string> curvature =
      service_path_warnings(parse_scene_text(both_maps, "/etc/pseudohaptic/scene.toml"));
  ASSERT_EQ(curvature.size(), 1u);
  EXPECT_TRUE(contains(curvature[0], ":5: region 't': normal_map /tmp/targets/n.png lies under /tmp")) << curvature[0];
  const std::vector<std::string> depth =
      service_path_warnings(parse_scene_text(both_maps + "method = \"depth\"\n", "/etc/pseudohaptic/scene.toml"));
  ASSERT_EQ(depth.size(), 1u);
  EXPECT_TRUE(contains(depth[0], ":6: region 't': depth_map /tmp/targets/d.png lies under /tmp")) << depth[0];
  EXPECT_EQ(service_path_warnings(parse_scene_text(both_maps + "method = \"hybrid\"\n", "/etc/pseudohaptic/scene.toml"))
                .size(),
            2u);
}

// A region the cursor cannot reach on the configured desktop, wholly or in part, is warned of; with desktop = "auto"
// nothing can be said before the daemon runs.
TEST(SceneFileErrors, RegionsOffTheConfiguredDesktopAreWarnedOf) {
  const std::string regions =
      "[[region]]\nname = \"inside\"\nx = 0\ny = 0\nwidth = 800\nheight = 600\nnormal_map = \"n.png\"\n"
      "[[region]]\nname = \"right\"\nx = 800\ny = 0\nwidth = 100\nheight = 100\nnormal_map = \"n.png\"\n"
      "[[region]]\nname = \"corner\"\nx = -20\ny = 590\nwidth = 100\nheight = 30\nnormal_map = \"n.png\"\n";
  const SceneSpec spec = parse_scene_text("[daemon]\ndesktop = [0, 0, 800, 600]\n" + regions, "s.toml");
  const std::vector<std::string> warnings = desktop_warnings(spec);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0],
            "s.toml:10: region 'right' at 800,0 (100x100 px) lies outside the desktop 0,0 800x600 px: the cursor never "
            "reaches it, and its fields are loaded for nothing");
  EXPECT_EQ(warnings[1],
            "s.toml:17: region 'corner' at -20,590 (100x30 px): only 80x10 px of it lie on the desktop 0,0 "
            "800x600 px");
  EXPECT_TRUE(desktop_warnings(parse_scene_text(regions, "auto.toml")).empty());
}

// A folder opens as a stream and reads as nothing: an empty scene, unless it is refused.
// A FIFO (or a device, a socket) named as the scene file is refused at once, not waited on for ever; a pipe the
// caller opened (a shell's <(...), /dev/fd/N) is read as the file it stands for.
TEST(SceneFileErrors, AFifoIsNotASceneFileButAnOpenPipeIsRead) {
  ScratchDir dir;
  const fs::path fifo = dir / "scene.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  try {
    parse_scene_file(fifo);
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), fifo.string() +
                                         ": is not a regular file (a FIFO, a device or a socket), not a "
                                         "scene file");
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  int ends[2];
  ASSERT_EQ(::pipe(ends), 0);
  const std::string_view text = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n";
  ASSERT_EQ(::write(ends[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(ends[1]);
  const SceneSpec spec = parse_scene_file(fs::path("/dev/fd") / std::to_string(ends[0]));
  ::close(ends[0]);
  ASSERT_EQ(spec.regions.size(), 1u);
  EXPECT_EQ(spec.regions[0].rect.w, 2);
}

// A scene file that is a symbolic link finds its images where the file it leads to lies: a target's scene linked into
// another folder loads.
TEST(SceneFileLoad, ALinkedSceneFileFindsTheImagesBesideTheFileItLeadsTo) {
  ScratchDir dir;
  fs::create_directories(dir / "targets");
  fs::create_directories(dir / "etc" / "sub");
  const std::vector<fs::path> scenes = write_target_files(dir / "targets", {all_targets()[0]});
  ASSERT_EQ(scenes.size(), 1u);
  fs::create_symlink(scenes[0], dir / "etc" / "scene.toml");
  fs::create_symlink(fs::path("..") / "scene.toml", dir / "etc" / "sub" / "chained.toml");  // a link to the link
  for (const fs::path& link : {dir / "etc" / "scene.toml", dir / "etc" / "sub" / "chained.toml"}) {
    SCOPED_TRACE(link.string());
    const SceneSpec spec = parse_scene_file(link);
    ASSERT_EQ(spec.regions.size(), 1u);
    ASSERT_TRUE(spec.regions[0].sources.normal_map);
    EXPECT_EQ(spec.regions[0].sources.normal_map->parent_path(), fs::canonical(dir / "targets"));
    EXPECT_EQ(load_scene(spec).regions().size(), 1u);
  }
  // A file that is not a link: its own folder, as written.
  const SceneSpec own = parse_scene_file(scenes[0]);
  EXPECT_EQ(own.regions[0].sources.normal_map->parent_path(), scenes[0].parent_path());
}

TEST(SceneFileErrors, AFolderIsNotASceneFile) {
  ScratchDir dir;
  try {
    parse_scene_file(dir.path());
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), dir.path().string() + ": is a folder, not a scene file");
  }
}

TEST(SceneFileErrors, ErrorsOfAFileNameTheFile) {
  ScratchDir dir;
  const fs::path file = dir / "bad.toml";
  write_text(file, "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\nnormal_green = \"up\"\n");
  try {
    parse_scene_file(file);
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(file.string() + ":5:", 0), 0u) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Loading

TEST(SceneFileLoad, MissingImageNamesSceneRegionAndImage) {
  ScratchDir dir;
  const fs::path file = dir / "scene.toml";
  write_text(file,
             "[[region]]\nname = \"lonely\"\nwidth = 20\nheight = 10\nnormal_map = \"maps/missing.normal.png\"\n\n"
             "[[region]]\nname = \"deep\"\nwidth = 20\nheight = 10\nmethod = \"depth\"\nnormal_map = \"n.png\"\n"
             "depth_map = \"gone.png\"\n");
  SceneSpec spec = parse_scene_file(file);
  ASSERT_EQ(spec.regions.size(), 2u);
  for (int which = 0; which < 2; ++which) {
    SceneSpec one = spec;
    one.regions.erase(one.regions.begin() + (1 - which));
    const std::string image = (which == 0 ? dir / "maps" / "missing.normal.png" : dir / "gone.png").string();
    const std::string region = which == 0 ? "lonely" : "deep";
    try {
      load_scene(one);
      ADD_FAILURE() << "no ConfigError";
    } catch (const ConfigError& e) {
      const std::string message = e.what();
      EXPECT_TRUE(contains(message, file.string())) << message;
      EXPECT_TRUE(contains(message, region)) << message;
      EXPECT_TRUE(contains(message, image)) << message;
    }
  }
}

TEST(SceneFileLoad, TargetFilesRoundTrip) {
  ScratchDir dir;
  const std::vector<TargetSpec> targets = all_targets();
  const std::vector<fs::path> scenes = write_target_files(dir.path(), targets);
  ASSERT_EQ(scenes.size(), 24u);
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const TargetSpec& target = targets[i];
    SCOPED_TRACE(target.name());
    const SceneSpec spec = parse_scene_file(scenes[i]);
    ASSERT_EQ(spec.regions.size(), 1u);
    EXPECT_EQ(spec.regions[0].name, target.name());
    EXPECT_EQ(spec.regions[0].method, "curvature");

    SceneLoadReport report;
    const Scene curvature = load_scene(spec, &report);
    EXPECT_EQ(report.regions.size(), 1u);
    ASSERT_EQ(curvature.regions().size(), 1u);
    const Region& c = curvature.regions()[0];
    EXPECT_EQ(c.rect.x, 0);
    EXPECT_EQ(c.rect.y, 0);
    EXPECT_EQ(c.rect.w, 500);
    EXPECT_EQ(c.rect.h, 500);
    EXPECT_EQ(c.method->name(), "curvature");
    ASSERT_TRUE(c.fields.gradient);
    EXPECT_FALSE(c.fields.depth);
    EXPECT_EQ(c.fields.gradient->width, 500);
    EXPECT_EQ(c.fields.gradient->height, 500);

    SceneSpec as_depth = spec;
    as_depth.regions[0].method = "depth";
    const Scene depth = load_scene(as_depth);
    ASSERT_EQ(depth.regions().size(), 1u);
    const Region& d = depth.regions()[0];
    EXPECT_EQ(d.rect.w, 500);
    EXPECT_EQ(d.rect.h, 500);
    EXPECT_EQ(d.method->name(), "depth");
    ASSERT_TRUE(d.fields.depth);
    EXPECT_FALSE(d.fields.gradient);
    EXPECT_EQ(d.fields.depth->width, 500);
    EXPECT_EQ(d.fields.depth->height, 500);

    // The values are the target's, up to 16-bit quantisation, along the middle row and column.
    const GradientField exact_gradient = target_gradient_field(target);
    const DepthField exact_depth = target_depth_field(target);
    int bad_gradient = 0, bad_depth = 0;
    for (std::int32_t k = 0; k < 500; ++k) {
      for (const Texel t : {Texel{k, 250}, Texel{250, k}, Texel{k, k}}) {
        const Gradient g = c.fields.gradient->at(t.x, t.y);
        const Gradient e = exact_gradient.at(t.x, t.y);
        const double scale = 1.0 + e.x * e.x + e.y * e.y;
        if (std::abs(g.x - e.x) > 2e-3 * scale * scale || std::abs(g.y - e.y) > 2e-3 * scale * scale) ++bad_gradient;
        if (std::abs(d.fields.depth->at(t.x, t.y) - exact_depth.at(t.x, t.y)) > 0.01) ++bad_depth;
      }
    }
    EXPECT_EQ(bad_gradient, 0);
    EXPECT_EQ(bad_depth, 0);
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Surface interrogation: [region.materials] and [region.wells]

constexpr std::string_view kInterrogationHead =
    "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\ndepth_map = \"d.png\"\nmethod = \"none\"\n";

TEST(SceneFileInterrogation, MaterialsAndWellsTablesAreRead) {
  const std::string text = std::string(kInterrogationHead) +
                           "[region.materials]\nsource = \"depth\"\nfilter_radius = 4\nplanar_curvedness = 0.001\n"
                           "elliptic = \"damping\"\nhyperbolic = \"none\"\n"
                           "[region.materials.friction]\nstuck_cd = 8\nbreakaway_px = 20\n"
                           "[region.materials.stick_slip]\nslip_px = 9\n"
                           "[region.wells]\npattern = \"contours\"\nlevels = [1.5, 10]\nradius_px = 24\n"
                           "strength = 0.5\nrule = \"band\"\ntolerance = 0.25\n";
  const SceneSpec spec = parse_scene_text(text, kOrigin);
  ASSERT_EQ(spec.regions.size(), 1u);
  const RegionSpec& r = spec.regions[0];
  EXPECT_EQ(r.method, "none");
  ASSERT_TRUE(r.materials);
  EXPECT_EQ(r.materials->source, ClassSource::depth);
  EXPECT_EQ(r.materials->filter_radius, 4);
  EXPECT_EQ(r.materials->planar_curvedness, 0.001);
  EXPECT_FALSE(r.materials->parabolic_ratio);
  EXPECT_EQ(r.materials->material(CurvatureClass::planar), Material::none);
  EXPECT_EQ(r.materials->material(CurvatureClass::parabolic), Material::damping);
  EXPECT_EQ(r.materials->material(CurvatureClass::elliptic), Material::damping);
  EXPECT_EQ(r.materials->material(CurvatureClass::hyperbolic), Material::none);
  EXPECT_EQ(r.materials->friction.stuck_cd, 8.0);
  EXPECT_EQ(r.materials->friction.breakaway_px, 20.0);
  EXPECT_EQ(r.materials->friction.rest_ms, FrictionParams{}.rest_ms);
  EXPECT_EQ(r.materials->stick_slip.slip_px, 9.0);
  ASSERT_TRUE(r.wells);
  EXPECT_EQ(r.wells->pattern, WellPattern::contours);
  EXPECT_EQ(r.wells->contours.levels, (std::vector<double>{1.5, 10.0}));
  EXPECT_EQ(r.wells->contours.rule, PatternRule::band);
  EXPECT_EQ(r.wells->contours.tol, 0.25);
  EXPECT_EQ(r.wells->radius_px, 24.0);
  EXPECT_EQ(r.wells->strength, 0.5);

  const SceneSpec isophotes = parse_scene_text(
      std::string(kInterrogationHead) + "[region.wells]\nlight = [0, -1, 1]\ncos_alpha = 0.5\nsnap_px = 3\n", kOrigin);
  const WellsParams& w = *isophotes.regions[0].wells;
  EXPECT_EQ(w.pattern, WellPattern::isophotes);
  EXPECT_EQ(w.isophotes.light.y, -1.0);
  EXPECT_EQ(w.isophotes.cos_alpha, 0.5);
  EXPECT_EQ(w.snap_px, 3.0);
  EXPECT_FALSE(parse_scene_text(std::string(kInterrogationHead), kOrigin).regions[0].materials);
}

TEST(SceneFileInterrogation, MistakesNameTheKeyAndWhatIsAllowed) {
  const std::string head(kInterrogationHead);
  expect_error(head + "[region.materials]\nelliptic = \"glue\"\n", 8, "region[0].materials.elliptic",
               {"unknown 'glue'", "none, damping, friction, stick_slip"});
  expect_error(head + "[region.materials]\nsource = \"colour\"\n", 8, "region[0].materials.source",
               {"auto, normals, depth"});
  expect_error(head + "[region.materials]\nfriction = { stuck_cd = 50 }\n", 8, "region[0].materials",
               {"stuck_cd", "20"});
  expect_error(head + "[region.materials.damping]\nspeed = 1\n", 8, "region[0].materials.damping.speed",
               {"unknown key", "cd_max"});
  expect_error(head + "[region.wells]\npattern = \"ridges\"\n", 8, "region[0].wells.pattern", {"isophotes, contours"});
  expect_error(head + "[region.wells]\nlight = [0, 1]\n", 8, "region[0].wells.light", {"three numbers"});
  expect_error(head + "[region.wells]\nlevels = 4\n", 8, "region[0].wells.levels", {"contours"});
  expect_error(head + "[region.wells]\npattern = \"contours\"\ncos_alpha = 0.5\n", 9, "region[0].wells.cos_alpha",
               {"isophotes"});
  expect_error(head + "[region.wells]\npattern = \"contours\"\nlevels = \"many\"\n", 9, "region[0].wells.levels",
               {"count", "list"});
  expect_error(head + "[region.wells]\nradius_px = 0\n", 8, "region[0].wells", {"radius_px"});
  expect_error("[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[region.wells]\npattern = \"contours\"\n", 6,
               "region[0].wells.pattern", {"depth_map"});  // at the pattern's line
  expect_error(
      "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[region.materials]\nplanar = \"friction\"\n"
      "source = \"depth\"\n",
      7, "region[0].materials.source", {"source = \"depth\" needs a depth_map"});
  // And "normals" a normal map: from a depth map's slopes the classes would be filtered at the normal map's radius.
  expect_error("[[region]]\nwidth = 2\nheight = 2\ndepth_map = \"d.png\"\n[region.materials]\nsource = \"normals\"\n",
               6, "region[0].materials.source", {"source = \"normals\" needs a normal_map"});
}

// min_gain may go down to its bound without a snap_fraction beside it: left out, snap_fraction stays within
// min_gain / 2 (its own bound). Given, it is held to that bound at its own line.
TEST(SceneFileInterrogation, ALowMinGainNeedsNoSnapFractionBesideIt) {
  const std::string head = "[[region]]\nwidth = 2\nheight = 2\nnormal_map = \"n.png\"\n[region.wells]\n";
  const SceneSpec spec = parse_scene_text(head + "min_gain = 0.1\n", kOrigin);
  ASSERT_TRUE(spec.regions[0].wells.has_value());
  EXPECT_EQ(spec.regions[0].wells->min_gain, 0.1);
  EXPECT_EQ(spec.regions[0].wells->snap_fraction, 0.05);
  EXPECT_EQ(parse_scene_text(head + "min_gain = 0.8\n", kOrigin).regions[0].wells->snap_fraction,
            WellsParams{}.snap_fraction);
  expect_error(head + "min_gain = 0.4\nsnap_fraction = 0.25\n", 7, "region[0].wells", {"snap_fraction", "0.2"});
}

TEST(SceneFileInterrogation, LoadingBuildsTheEffectsAndKeepsOnlyWhatTheMethodWalks) {
  ScratchDir dir;
  const TargetSpec target = all_targets().front();
  write_target_files(dir.path(), {target});
  const std::string base = target.name();
  const fs::path file = dir / "interrogation.toml";
  std::ofstream(file) << "[[region]]\nwidth = 500\nheight = 500\nmethod = \"none\"\n"
                      << "normal_map = \"" << base << ".normal.png\"\ndepth_map = \"" << base << ".depth.png\"\n"
                      << "relief_px = 100\n[region.materials]\n[region.wells]\npattern = \"contours\"\n";
  const Scene scene = load_scene(parse_scene_file(file));
  ASSERT_EQ(scene.regions().size(), 1u);
  const Region& region = scene.regions()[0];
  ASSERT_EQ(region.effects.size(), 2u);
  EXPECT_EQ(region.effects[0]->name(), "materials");
  EXPECT_EQ(region.effects[1]->name(), "wells");
  EXPECT_TRUE(scene.has_effects());
  // The flat method walks no field: only the effects' own data stays (1 + 4 bytes per texel), beside the scene's
  // flat tiles (a few hundred bytes).
  EXPECT_FALSE(region.fields.gradient);
  EXPECT_FALSE(region.fields.depth);
  EXPECT_EQ(scene.bytes(), 500u * 500u * 5u + scene.flat_tiles().bytes());
  EXPECT_LT(scene.flat_tiles().bytes(), 1000u);

  // With the curvature method the gradient stays for the walk.
  std::ofstream(file) << "[[region]]\nwidth = 500\nheight = 500\n"
                      << "normal_map = \"" << base << ".normal.png\"\n[region.wells]\n";
  const Scene layered = load_scene(parse_scene_file(file));
  EXPECT_TRUE(layered.regions()[0].fields.gradient);
  EXPECT_EQ(layered.regions()[0].effects.size(), 1u);
}

TEST(SceneFileEngine, TraversalAndSamplingAreDaemonKeysAppliedByTheLoader) {
  const SceneSpec spec = parse_scene_text("[daemon]\ntraversal = \"unit_steps\"\nsampling = \"bilinear\"\n", kOrigin);
  EXPECT_EQ(spec.daemon.engine.traversal, Traversal::unit_steps);
  EXPECT_EQ(spec.daemon.engine.sampling, Sampling::bilinear);
  EXPECT_EQ(load_scene(spec).options(), spec.daemon.engine);
  EXPECT_TRUE(parse_scene_text("[daemon]\n", kOrigin).daemon.engine.is_default());
  expect_error("[daemon]\ntraversal = \"fast\"\n", 2, "daemon.traversal",
               {"unknown 'fast'", "exact, unit_steps, frame_midpoint, direction_lut"});
  // Two counts, said as two: a range would suggest the counts between.
  for (const char* count : {"12", "4", "32", "-8", "16.0", "\"16\""}) {
    const std::string text = std::string("[daemon]\nlut_directions = ") + count + "\n";
    expect_error(text, 2, "daemon.lut_directions", {"must be 8 or 16"});
    EXPECT_FALSE(contains(parse_error(text), "between")) << parse_error(text);
    expect_error(
        "[[region]]\nname = \"r\"\nx = 0\ny = 0\nwidth = 4\nheight = 4\nnormal_map = \"n.png\"\n"
        "traversal = \"direction_lut\"\n"
        "lut_directions = " +
            std::string(count) + "\n",
        9, "region[0].lut_directions", {"must be 8 or 16"});
  }
  expect_error("[daemon]\nlut_directions = 4\n", 2, "daemon.lut_directions", {"(got 4)"});
  // At the line that asked for bilinear sampling, not at the table's head.
  expect_error("[daemon]\ntraversal = \"direction_lut\"\nsampling = \"bilinear\"\n", 3, "daemon.sampling", {"nearest"});
}

// The shipped example's commented lines, uncommented: its [daemon] table and the [region.METHOD] tables say
// "these are the defaults", and a user who uncomments them must get just that.
std::string uncommented(std::string_view text) {
  std::string out;
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
    if (line.starts_with("# ")) {
      const std::string_view rest = line.substr(2);
      const std::size_t key_end = rest.find_first_not_of("abcdefghijklmnopqrstuvwxyz_0123456789");
      const bool table = rest.starts_with('[');
      const bool assignment =
          key_end != 0 && key_end != std::string_view::npos && rest.substr(key_end).starts_with(" = ");
      if (table || assignment) line = rest;
    }
    out.append(line).append("\n");
  }
  return out;
}

TEST(SceneFileDocs, TheExamplesDefaultsAreTheParsersDefaults) {
  const std::string example = read_file_text(PH_EXAMPLE_SCENE);
  const SceneSpec as_shipped = parse_scene_text(example, PH_EXAMPLE_SCENE);
  EXPECT_TRUE(as_shipped.regions.empty());

  const std::string text = uncommented(example);
  SCOPED_TRACE(text);
  const SceneSpec spec = parse_scene_text(text, PH_EXAMPLE_SCENE);
  const DaemonSettings& got = spec.daemon;
  const DaemonSettings defaults;
  EXPECT_TRUE(got.devices.empty());
  EXPECT_EQ(got.output, defaults.output);
  EXPECT_EQ(got.desktop, defaults.desktop);
  const AccelSettings accel = acceleration_of(got), default_accel = acceleration_of(defaults);
  EXPECT_EQ(accel.profile, default_accel.profile);
  EXPECT_EQ(accel.speed, default_accel.speed);
  EXPECT_EQ(accel.dpi, default_accel.dpi);
  EXPECT_EQ(got.pointer_speed, defaults.pointer_speed);
  EXPECT_EQ(got.engine, defaults.engine);

  ASSERT_EQ(spec.regions.size(), 1u);
  RegionSpec region = spec.regions[0];
  // Each table the example shows was read (a table left out would give its defaults whatever the example says).
  for (const char* method : {"curvature", "depth", "hybrid"}) {
    EXPECT_TRUE(region.method_params.contains(method)) << method;
  }
  const CurvatureParams curvature = method_params<CurvatureMethod>(region), default_curvature;
  EXPECT_EQ(curvature.kmax_prime, default_curvature.kmax_prime);
  EXPECT_EQ(curvature.kmin_prime, default_curvature.kmin_prime);
  EXPECT_EQ(curvature.kmax_lo, default_curvature.kmax_lo);
  EXPECT_EQ(curvature.kmax_hi, default_curvature.kmax_hi);
  EXPECT_EQ(curvature.kmin_lo, default_curvature.kmin_lo);
  EXPECT_EQ(curvature.kmin_hi, default_curvature.kmin_hi);
  EXPECT_EQ(curvature.delta_beta_sign, default_curvature.delta_beta_sign);
  const DepthParams depth = method_params<DepthMethod>(region), default_depth;
  EXPECT_EQ(depth.gain, default_depth.gain);
  EXPECT_EQ(depth.kmax, default_depth.kmax);
  EXPECT_EQ(depth.kmin, default_depth.kmin);
  const HybridParams hybrid = method_params<HybridMethod>(region), default_hybrid;
  EXPECT_EQ(hybrid.discontinuity_px, default_hybrid.discontinuity_px);
  EXPECT_EQ(hybrid.noise_slope, default_hybrid.noise_slope);
  EXPECT_EQ(hybrid.far_noise_gain, default_hybrid.far_noise_gain);

  ASSERT_TRUE(region.materials.has_value());
  const MaterialsParams default_materials;
  EXPECT_EQ(region.materials->source, default_materials.source);
  EXPECT_EQ(region.materials->materials, default_materials.materials);
  ASSERT_TRUE(region.wells.has_value());
  const WellsParams default_wells;
  EXPECT_EQ(region.wells->pattern, default_wells.pattern);
  EXPECT_EQ(region.wells->radius_px, default_wells.radius_px);
  EXPECT_EQ(region.wells->strength, default_wells.strength);
  EXPECT_EQ(region.wells->max_gain, default_wells.max_gain);
  EXPECT_EQ(region.wells->min_gain, default_wells.min_gain);
}

// The keys the parser allows in a table, as its error for an unknown key lists them.
std::vector<std::string> allowed_keys(const std::string& table_path) {
  constexpr std::string_view region = "[[region]]\nwidth = 9\nheight = 9\nnormal_map = \"a.png\"\n";
  const std::string text = table_path == "daemon" ? "[daemon]\nunknown_key = 1\n"
                           : table_path == "region"
                               ? std::string(region) + "unknown_key = 1\n"
                               : std::string(region) + "[region." + table_path + "]\nunknown_key = 1\n";
  const std::string message = parse_error(text);
  const std::size_t from = message.find("(allowed: ");
  const std::size_t to = message.rfind(')');
  if (from == std::string::npos || to == std::string::npos || to < from) {
    ADD_FAILURE() << message;
    return {};
  }
  std::vector<std::string> keys;
  std::string_view list = std::string_view(message).substr(from + 10, to - from - 10);
  while (!list.empty()) {
    const std::size_t comma = list.find(", ");
    keys.emplace_back(list.substr(0, comma));
    list = comma == std::string_view::npos ? std::string_view{} : list.substr(comma + 2);
  }
  return keys;
}

// The words the man page sets in bold (.B, .BR and .RB lines), where it names keys.
std::set<std::string, std::less<>> bold_words(std::string_view roff) {
  std::set<std::string, std::less<>> words;
  while (!roff.empty()) {
    const std::size_t end = roff.find('\n');
    const std::string_view line = roff.substr(0, end);
    roff = end == std::string_view::npos ? std::string_view{} : roff.substr(end + 1);
    if (!line.starts_with(".B ") && !line.starts_with(".BR ") && !line.starts_with(".RB ")) continue;
    std::string word;
    for (const char c : line.substr(line.find(' '))) {
      if ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_') {
        word += c;
      } else {
        if (!word.empty()) words.insert(word);
        word.clear();
      }
    }
    if (!word.empty()) words.insert(word);
  }
  return words;
}

// The README's scene file, its three toml blocks ([daemon], a region, its effects) one after the other as a user
// copies them into one file, is a valid scene: one region with both effects. (Its wells block once set both the
// isophotes' light and the contours' levels, which the parser refuses.)
TEST(SceneFileDocs, TheReadmesSceneIsValid) {
  const std::string readme = read_file_text(PH_README);
  std::string scene;
  int blocks = 0;
  for (std::size_t at = readme.find("```toml\n"); at != std::string::npos; at = readme.find("```toml\n", at)) {
    at += 8;
    const std::size_t end = readme.find("```", at);
    ASSERT_NE(end, std::string::npos);
    scene += readme.substr(at, end - at);
    blocks += 1;
  }
  ASSERT_EQ(blocks, 3) << "the README's toml blocks changed: check that they still make one scene";
  SCOPED_TRACE(scene);
  try {
    const SceneSpec spec = parse_scene_text(scene, "README.md");
    ASSERT_EQ(spec.regions.size(), 1u);
    EXPECT_EQ(spec.regions[0].name, "bump");
    EXPECT_TRUE(spec.regions[0].materials.has_value());
    EXPECT_TRUE(spec.regions[0].wells.has_value());
  } catch (const ConfigError& e) {
    ADD_FAILURE() << e.what();
  }
}

TEST(SceneFileDocs, TheManPageNamesEveryKeyTheParserAllows) {
  const std::set<std::string, std::less<>> documented = bold_words(read_file_text(PH_DAEMON_MAN_PAGE));
  for (const char* table : {"daemon", "region", "curvature", "depth", "hybrid", "materials", "materials.damping",
                            "materials.friction", "materials.stick_slip", "wells"}) {
    const std::vector<std::string> keys = allowed_keys(table);
    EXPECT_GE(keys.size(), 3u) << table;
    for (const std::string& key : keys) {
      EXPECT_TRUE(documented.contains(key)) << "pseudohapticd.8 does not name " << table << "." << key;
    }
  }
}

// Why a region's key below a table can be told from the table's own: no table within a region has a key of the
// region's own (other than the tables themselves).
TEST(SceneFileErrors, NoTableWithinARegionSharesAKeyWithTheRegion) {
  std::set<std::string> region_keys;
  for (const std::string& key : allowed_keys("region")) region_keys.insert(key);
  for (const char* table : {"curvature", "depth", "hybrid", "materials", "materials.damping", "materials.friction",
                            "materials.stick_slip", "wells"}) {
    const std::vector<std::string> keys = allowed_keys(table);
    ASSERT_FALSE(keys.empty()) << table;
    for (const std::string& key : keys) EXPECT_FALSE(region_keys.contains(key)) << table << "." << key;
  }
}

}  // namespace
}  // namespace ph
