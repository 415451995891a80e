// End-to-end tests of `pseudohaptic surfaces` and `pseudohaptic inspect`: run the built binary, read what it writes.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "config/field_loader.hpp"
#include "config/image_io.hpp"
#include "core/effects/curvature_class.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/surfaces.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/tool_runner.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

TEST(ToolInterrogation, SurfacesWritesMapsCurvatureAndScenes) {
  ScratchDir dir;
  const fs::path folder = dir / "surfaces";
  const ToolResult r = run_tool("surfaces --size 64 " + quote(folder), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("wrote 9 surfaces"), std::string::npos) << r.out;
  // Standard error is a file here: one progress line per surface, no carriage returns.
  EXPECT_NE(r.err.find("[1/9] plane\n[2/9] cylinder\n"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("[9/9] monkey-saddle\n"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  for (const SurfaceSpec& spec : all_surfaces(64)) {
    SCOPED_TRACE(spec.name());
    const RawImage normal = read_image(folder / (spec.name() + ".normal.png"));
    EXPECT_EQ(normal.width, 64);
    EXPECT_EQ(normal.height, 64);
    EXPECT_EQ(normal.channels, 3);
    EXPECT_EQ(normal.code_max, 65535u);
    const RawImage depth = read_image(folder / (spec.name() + ".depth.png"));
    EXPECT_EQ(depth.channels, 1);
    EXPECT_EQ(depth.code_max, 65535u);
    const RawImage k = read_image(folder / (spec.name() + ".K.exr"));
    ASSERT_EQ(k.channels, 1);
    ASSERT_TRUE(k.is_float);
    const Grid<float> exact = surface_curvature_fields(spec).gaussian;
    ASSERT_EQ(k.pixels.size(), exact.values.size());
    for (std::size_t i = 0; i < k.pixels.size(); ++i) EXPECT_EQ(k.pixels[i], exact.values[i]);
    // The scene loads as the daemon loads it, and its depth map gives back the exact heights.
    const fs::path scene = folder / (spec.name() + ".toml");
    const ToolResult check = run_tool("check-config --quiet " + quote(scene), dir);
    EXPECT_EQ(check.rc, 0) << check.err;
    FieldSources sources;
    sources.depth_map = folder / (spec.name() + ".depth.png");
    sources.depth_options = {0.5, 2 * spec.relief_px()};
    FieldLoadReport report;
    const RegionFields fields = load_region_fields(sources, 64, 64, {false, true}, report);
    const DepthField want = surface_depth_field(spec);
    for (std::size_t i = 0; i < want.values.size(); ++i)
      ASSERT_NEAR(fields.depth->values[i], want.values[i], 2 * spec.relief_px() / 65535.0);
  }
}

// The class colours `inspect` prints in its legend, by class name.
std::map<std::string, std::array<int, 3>> legend(const std::string& out) {
  std::map<std::string, std::array<int, 3>> colours;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::string name, hex;
    if (!(words >> name >> hex) || hex.size() != 7 || hex[0] != '#') continue;
    const unsigned long v = std::stoul(hex.substr(1), nullptr, 16);
    colours[name] = {int(v >> 16), int((v >> 8) & 255), int(v & 255)};
  }
  return colours;
}

// A Gaussian bump has every class: elliptic top, hyperbolic flank, parabolic in between, planar outside.
TEST(ToolInterrogation, InspectWritesPicturesWhoseClassColoursMatchTheClassMap) {
  ScratchDir dir;
  TargetSpec bump;
  bump.size = 120;
  bump.radius = 50;
  const fs::path normal_map = dir / "bump.normal.png";
  write_normal_png16(normal_map, target_normal_image(bump));
  Grid<float> depth = target_depth_field(bump);
  for (float& v : depth.values) v = static_cast<float>(v / 200.0 + 0.5);
  const fs::path depth_map = dir / "bump.depth.png";
  write_gray_png16(depth_map, depth);
  const fs::path out = dir / "inspect";
  const ToolResult r = run_tool("inspect --normal-map " + quote(normal_map) + " --depth-map " + quote(depth_map) +
                                    " --depth-zero 0.5 --relief-px 200 " + quote(out),
                                dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  for (const char* name : {"K.png", "H.png", "class.png", "isophotes.png", "contours.png"}) {
    SCOPED_TRACE(name);
    const RawImage image = read_image(out / name);
    EXPECT_EQ(image.width, 120);
    EXPECT_EQ(image.height, 120);
    EXPECT_EQ(image.channels, 3);
    EXPECT_EQ(image.code_max, 255u);
  }
  const auto colours = legend(r.out);
  ASSERT_EQ(colours.size(), 4u) << r.out;

  // The class map the tool should have drawn: same loader, filter and tolerances (the defaults for 16-bit maps).
  FieldSources sources;
  sources.normal_map = normal_map;
  FieldLoadReport report;
  const RegionFields fields = load_region_fields(sources, 120, 120, {true, false}, report);
  const Grid<std::uint8_t> classes =
      class_map(curvature_from_gradient(*fields.gradient, DerivativeFilter::recommended(false, 16)),
                ClassTolerances::recommended(16));
  const RawImage picture = read_image(out / "class.png");
  std::array<std::size_t, 4> seen{};
  for (std::size_t i = 0; i < classes.values.size(); ++i) {
    const auto want = colours.at(class_name(static_cast<CurvatureClass>(classes.values[i])));
    for (int c = 0; c < 3; ++c) ASSERT_EQ(std::lround(picture.pixels[i * 3 + c] * 255.0), want[c]) << "texel " << i;
    ++seen[classes.values[i]];
  }
  for (std::size_t n : seen) EXPECT_GT(n, 0u) << "every class appears on the bump";
}

// A saddle's depth map, 64 x 64 px, written to `path` (with depth_zero 0.5 and relief_px 16).
void write_saddle_depth_map(const fs::path& path) {
  const SurfaceSpec saddle{SurfaceKind::simple_saddle, 64};
  Grid<float> depth = surface_depth_field(saddle);
  for (float& v : depth.values) v = static_cast<float>(v / (2 * saddle.relief_px()) + 0.5);
  write_gray_png16(path, depth);
}

TEST(ToolInterrogation, InspectOptionsAndErrors) {
  ScratchDir dir;
  const fs::path depth_map = dir / "saddle.depth.png";
  write_saddle_depth_map(depth_map);
  const fs::path out = dir / "out";
  {
    // Depth only, resampled to another size, explicit radius and tolerances.
    const ToolResult r = run_tool("inspect --depth-map " + quote(depth_map) +
                                      " --depth-zero 0.5 --relief-px 16 --size 80,40 --radius 4 "
                                      "--planar-curvedness 1e-4 --parabolic-ratio 0.2 " +
                                      quote(out),
                                  dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_NE(r.out.find("depth map (16-bit), filter radius 4"), std::string::npos) << r.out;
    // 64 x 64 px shown as 80 x 40: warned of, as the daemon warns of a map stretched to its region.
    EXPECT_NE(r.err.find("pseudohaptic: warning: depth map " + depth_map.string() +
                         ": 64x64 px, resampled to the region's 80x40; out of proportion: stretched by 1.25 across and "
                         "0.625 down\n"),
              std::string::npos)
        << r.err;
    const RawImage k = read_image(out / "K.png");
    EXPECT_EQ(k.width, 80);
    EXPECT_EQ(k.height, 40);
    EXPECT_TRUE(fs::exists(out / "contours.png"));
  }
  {
    // The same at 128 x 128: in proportion, no warning.
    const ToolResult r = run_tool("inspect --depth-map " + quote(depth_map) + " --size 128,128 " + quote(out), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
  }
  for (const std::string& args : {std::string("inspect ") + quote(dir / "x"),
                                  "inspect --from normal --depth-map " + quote(depth_map) + " " + quote(dir / "x"),
                                  "inspect --normal-map " + quote(dir / "missing.png") + " " + quote(dir / "x")}) {
    SCOPED_TRACE(args);
    const ToolResult r = run_tool(args, dir);
    EXPECT_EQ(r.rc, 1);
    EXPECT_NE(r.err.find("pseudohaptic: "), std::string::npos) << r.err;
  }
  {
    // No region is wider or taller than 16384 px, so neither is what inspect resamples to.
    const ToolResult r =
        run_tool("inspect --depth-map " + quote(depth_map) + " --size 16385,8 " + quote(dir / "x"), dir);
    expect_clean_failure(r, {"--size", "16384"});
    EXPECT_FALSE(fs::exists(dir / "x"));
  }
  {
    // Nor larger in all than 8192 x 8192, refused before a map is resampled.
    const ToolResult r =
        run_tool("inspect --depth-map " + quote(depth_map) + " --size 16384,4097 " + quote(dir / "x"), dir);
    expect_clean_failure(r, {"67125248 px", "8192 x 8192", "--size"});
    EXPECT_FALSE(fs::exists(dir / "x"));
  }
  {
    // A folder that cannot take the pictures is said before they are computed, by its own name.
    fs::create_directories(dir / "taken" / "class.png");
    const ToolResult r = run_tool("inspect --depth-map " + quote(depth_map) + " " + quote(dir / "taken"), dir);
    expect_clean_failure(r, {(dir / "taken" / "class.png").string() + ": is a folder"});
    EXPECT_EQ(r.err.find("partial"), std::string::npos) << r.err;
  }
}

// --size and --light take their one argument wherever they stand: before OUTDIR with an option after it, CLI11 took
// OUTDIR for another number ("--size: Value ins not in range").
TEST(ToolInterrogation, InspectCommaOptionsBeforeOutdirLeaveItAlone) {
  ScratchDir dir;
  const fs::path depth_map = dir / "saddle.depth.png";
  write_saddle_depth_map(depth_map);
  const fs::path out = dir / "out";
  const ToolResult r = run_tool("inspect --size 80,40 --light 1,1,2 " + quote(out) + " --depth-map " +
                                    quote(depth_map) + " --depth-zero 0.5 --relief-px 16",
                                dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const RawImage k = read_image(out / "K.png");
  EXPECT_EQ(k.width, 80);
  EXPECT_EQ(k.height, 40);
}

// What the computation refuses (a light of no length) fails before any picture is written: no OUTDIR made, and an
// earlier run's pictures left as they were, not some of them replaced by this run's.
TEST(ToolInterrogation, InspectChecksEverythingBeforeWritingAnything) {
  ScratchDir dir;
  const fs::path depth_map = dir / "saddle.depth.png";
  write_saddle_depth_map(depth_map);
  const std::string maps = " --depth-map " + quote(depth_map) + " --depth-zero 0.5 --relief-px 16";
  const fs::path out = dir / "out";
  ASSERT_EQ(run_tool("inspect " + quote(out) + maps, dir).rc, 0);
  const auto pictures = [&out] {
    std::map<std::string, std::vector<char>> files;
    for (const auto& entry : fs::directory_iterator(out))
      files[entry.path().filename().string()] = read_file_bytes(entry.path());
    return files;
  };
  const std::map<std::string, std::vector<char>> earlier = pictures();
  ASSERT_EQ(earlier.size(), 5u);  // K, H, class, isophotes, contours

  // A map whose header reads (its size) but whose pixels do not: the computation fails, after the command line and
  // the size were taken, and before any picture is written.
  const std::vector<char> whole = read_file_bytes(depth_map);
  const fs::path cut = dir / "cut.depth.png";
  std::ofstream(cut, std::ios::binary).write(whole.data(), static_cast<std::streamsize>(whole.size() / 2));
  expect_clean_failure(run_tool("inspect " + quote(out) + " --depth-map " + quote(cut) + " --size 32,32", dir),
                       {cut.string()});
  EXPECT_TRUE(pictures() == earlier) << "a picture of the failed run was written";

  const ToolResult r = run_tool("inspect " + quote(out) + maps + " --size 32,32 --light 0,0,0", dir);
  expect_clean_failure(r, {"--light: must not be 0,0,0"});
  EXPECT_TRUE(pictures() == earlier) << "a picture of the failed run was written";

  // Cut short while it writes (here by the file size limit, which kills it at the first picture): the pictures
  // are replaced together once all are written, so the earlier run's stay whole (before, K.png was left cut).
  const std::string limited = "ulimit -c 0 && ulimit -f 1 && exec " + quote(std::string(PH_TOOL_PATH)) + " inspect " +
                              quote(out) + maps + " --size 48,48";
  EXPECT_EQ(run_program("/bin/sh", "-c " + quote(limited), dir).rc, 128 + SIGXFSZ);
  for (const auto& [name, bytes] : pictures()) {
    if (name.ends_with(".partial")) continue;  // the temporary of the picture it was writing, as for a CSV file
    EXPECT_TRUE(earlier.contains(name) && earlier.at(name) == bytes) << name << " changed";
  }
  // The limit met with SIGXFSZ ignored, as a full disk is met: OpenImageIO's PNG writer says nothing of the picture
  // it cut short (it exited 0 and the set was committed); the picture is read back, and the run fails.
  const ToolResult full = run_program("/bin/sh", "-c " + quote("trap '' XFSZ && " + limited), dir);
  expect_clean_failure(full, {"K.png", "reads back cut short or corrupt"});
  for (const auto& [name, bytes] : pictures()) {
    if (name.ends_with(".partial")) continue;
    EXPECT_TRUE(earlier.contains(name) && earlier.at(name) == bytes) << name << " changed";
  }

  expect_clean_failure(run_tool("inspect " + quote(dir / "new") + maps + " --light 0,0,0", dir), {"--light"});
  EXPECT_FALSE(fs::exists(dir / "new"));
  // Decoding options for a map not given change nothing: refused, naming the option.
  expect_clean_failure(run_tool("inspect " + quote(dir / "new") + maps + " --normal-green directx", dir),
                       {"--normal-green says how to decode a normal map: give --normal-map"});
  EXPECT_FALSE(fs::exists(dir / "new"));
  // Contours are of heights: without a depth map --contours was ignored without a word.
  const fs::path normal_map = dir / "plane.normal.png";
  write_normal_png16(normal_map, surface_normal_image({SurfaceKind::plane, 32}));
  expect_clean_failure(
      run_tool("inspect " + quote(dir / "new") + " --normal-map " + quote(normal_map) + " --contours 3", dir),
      {"--contours sets the contours of a depth map: give --depth-map"});
  EXPECT_FALSE(fs::exists(dir / "new"));
}

// A plane's mean curvature and a cylinder's Gaussian curvature are 0 but for rounding: the pictures of them are white,
// not painted in full colour at the scale of the rounding (which read as a hole and a saddle).
TEST(ToolInterrogation, InspectPaintsRoundingNoiseWhite) {
  ScratchDir dir;
  for (const SurfaceKind kind : {SurfaceKind::plane, SurfaceKind::cylinder}) {
    const SurfaceSpec surface{kind, 64};
    SCOPED_TRACE(surface.name());
    const fs::path normal_map = dir / (surface.name() + ".normal.png");
    write_normal_png16(normal_map, surface_normal_image(surface));
    const fs::path out = dir / surface.name();
    const ToolResult r = run_tool("inspect --normal-map " + quote(normal_map) + " " + quote(out), dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    for (const char* name :
         kind == SurfaceKind::plane ? std::vector<const char*>{"K.png", "H.png"} : std::vector<const char*>{"K.png"}) {
      const RawImage picture = read_image(out / name);
      double darkest = 1.0;
      for (const float v : picture.pixels) darkest = std::min(darkest, static_cast<double>(v));
      EXPECT_GT(darkest, 0.9) << name << " is not white: " << r.out;
    }
    // The legend gives the scale the picture used: the floor, the planar curvedness squared (5e-5 /px for 16-bit
    // maps), also where every K is exactly 0 (it said +-1 there).
    EXPECT_NE(r.out.find("K.png: K in 1/px^2, blue < 0 < red, full colour at +-2.5e-09 "), std::string::npos) << r.out;
  }
  // With no floor, a plane's K, 0 at every texel, is said to be so (not "full colour at +-0", nor at +-1).
  const SurfaceSpec plane{SurfaceKind::plane, 64};
  const ToolResult r = run_tool("inspect --planar-curvedness 0 --normal-map " +
                                    quote(dir / (plane.name() + ".normal.png")) + " " + quote(dir / "no-floor"),
                                dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("K.png: K in 1/px^2, 0 everywhere (all white)\n"), std::string::npos) << r.out;
}

// A light of huge or tiny components is a direction like any other: its length overflowed (1e300^2) or underflowed,
// and the light was refused as "not finite and non-zero".
TEST(ToolInterrogation, InspectTakesALightOfAnyFiniteLength) {
  ScratchDir dir;
  const fs::path depth_map = dir / "saddle.depth.png";
  write_saddle_depth_map(depth_map);
  const std::string maps = " --depth-map " + quote(depth_map) + " --depth-zero 0.5 --relief-px 16";
  ASSERT_EQ(run_tool("inspect " + quote(dir / "unit") + maps + " --light -1,-1,2", dir).rc, 0);
  for (const std::string light : {"-1e300,-1e300,2e300", "-1e-300,-1e-300,2e-300"}) {
    SCOPED_TRACE(light);
    const ToolResult r = run_tool("inspect " + quote(dir / "scaled") + maps + " --light " + light, dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(read_file_bytes(dir / "scaled" / "isophotes.png"), read_file_bytes(dir / "unit" / "isophotes.png"));
  }
}

// A run without a depth map writes no contours.png: one an earlier run left, of another texture, is removed rather
// than left beside this run's pictures.
TEST(ToolInterrogation, InspectLeavesNoContoursOfAnEarlierRun) {
  ScratchDir dir;
  const fs::path depth_map = dir / "saddle.depth.png";
  write_saddle_depth_map(depth_map);
  const fs::path out = dir / "out";
  ASSERT_EQ(run_tool("inspect --depth-map " + quote(depth_map) + " " + quote(out), dir).rc, 0);
  ASSERT_TRUE(fs::exists(out / "contours.png"));
  ASSERT_EQ(run_tool("surfaces --size 32 " + quote(dir / "s"), dir).rc, 0);
  const ToolResult r = run_tool("inspect --normal-map " + quote(dir / "s" / "cone.normal.png") + " " + quote(out), dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "contours.png"));
  EXPECT_TRUE(fs::exists(out / "isophotes.png"));
}

}  // namespace
}  // namespace ph
