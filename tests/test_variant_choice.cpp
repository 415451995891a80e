// Traversal variants per region and traversal = "auto" (core/engine/variant_choice.hpp, Region::options).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/direction_lut.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_flat.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"
#include "core/engine/variant_choice.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

Region curvature_target(const TargetSpec& spec, Vec2 at) {
  Region r;
  r.name = spec.name();
  r.rect = {static_cast<int>(at.x), static_cast<int>(at.y), spec.size, spec.size};
  r.fields.gradient = target_gradient_field(spec);
  r.method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  return r;
}

TargetSpec gentle_bump() {  // a wide Gaussian bump 5 px high: its C/D changes little within a frame
  TargetSpec spec;
  spec.profile = TargetProfile::gaussian;
  spec.height = 0.25;
  spec.radius = 200;
  spec.relief_px = 20.0;
  return spec;
}

TargetSpec sharp_bump() {  // the linear bump: a kink at its apex and its rim
  TargetSpec spec;
  spec.profile = TargetProfile::linear;
  spec.height = 1.0;
  spec.radius = 100;
  return spec;
}

TEST(VariantChoice, CheapVariantOnAGentleRegionExactOnASharpOne) {
  const VariantChoice gentle = choose_variant(curvature_target(gentle_bump(), {0, 0}));
  EXPECT_EQ(gentle.options.traversal, Traversal::frame_midpoint) << gentle.reason;
  EXPECT_LE(gentle.midpoint_error_px, VariantBudget{}.accuracy_px);
  EXPECT_GT(gentle.midpoint_error_px, 0.0) << "the bump does change the C/D";
  EXPECT_NE(gentle.reason.find("within accuracy_px"), std::string::npos) << gentle.reason;

  const VariantChoice sharp = choose_variant(curvature_target(sharp_bump(), {0, 0}));
  EXPECT_EQ(sharp.options.traversal, Traversal::exact) << sharp.reason;
  EXPECT_GT(sharp.midpoint_error_px, VariantBudget{}.accuracy_px);
  EXPECT_NE(sharp.reason.find("more than accuracy_px"), std::string::npos) << sharp.reason;

  // The budget decides: a loose one lets the sharp region take the cheap variant too.
  const VariantChoice loose = choose_variant(curvature_target(sharp_bump(), {0, 0}), {1e6, 10.0});
  EXPECT_EQ(loose.options.traversal, Traversal::frame_midpoint) << loose.reason;
}

// A constant slope: one C/D throughout the region, another (1) on the flat outside. A frame that crosses the
// border is what frame_midpoint gets wrong there, so the estimate counts the border too.
TEST(VariantChoice, ARegionWhoseCdDiffersFromTheOutsideKeepsTheExactWalk) {
  Region slope;
  slope.name = "slope";
  slope.rect = {0, 0, 64, 64};
  DepthField depth(64, 64);
  for (std::int32_t y = 0; y < 64; ++y)
    for (std::int32_t x = 0; x < 64; ++x) depth.at(x, y) = 0.2f * static_cast<float>(x);
  slope.fields.depth = std::move(depth);
  slope.method = std::make_shared<DepthMethod>(DepthParams{});
  const VariantChoice choice = choose_variant(slope);
  EXPECT_EQ(choice.options.traversal, Traversal::exact) << choice.reason;
  EXPECT_GT(choice.midpoint_error_px, 1.0) << "0.2 px of height per px: C/D well away from 1";

  // A loose enough budget accepts the jump at the border.
  const VariantChoice loose = choose_variant(slope, {1e6, 10.0});
  EXPECT_EQ(loose.options.traversal, Traversal::frame_midpoint) << loose.reason;
}

TEST(VariantChoice, FlatMethodTakesTheCheapVariant) {
  Region flat;
  flat.name = "flat";
  flat.rect = {0, 0, 40, 40};
  flat.method = std::make_shared<FlatMethod>();
  const VariantChoice choice = choose_variant(flat);
  EXPECT_EQ(choice.options.traversal, Traversal::frame_midpoint);
  EXPECT_EQ(choice.midpoint_error_px, 0.0);
}

// A frame walks with the options of the region it starts in: the same frames give what a scene with those
// options throughout gives, in each region.
TEST(RegionOptions, FramesWalkWithTheirStartingRegionsOptions) {
  EngineOptions midpoint;
  midpoint.traversal = Traversal::frame_midpoint;
  Region a = curvature_target(sharp_bump(), {0, 0});
  Region b = curvature_target(sharp_bump(), {600, 0});
  b.options = midpoint;
  const Scene mixed(std::vector<Region>{a, b});
  Scene all_exact(
      std::vector<Region>{curvature_target(sharp_bump(), {0, 0}), curvature_target(sharp_bump(), {600, 0})});
  Scene all_midpoint(
      std::vector<Region>{curvature_target(sharp_bump(), {0, 0}), curvature_target(sharp_bump(), {600, 0})});
  all_midpoint.set_options(midpoint);
  int differing = 0;
  for (const double start_x : {160.0, 760.0}) {
    CursorState in_mixed = cursor_at({start_x, 250.5}), in_reference = in_mixed;
    const Scene& reference = start_x < 600 ? all_exact : all_midpoint;
    for (int i = 0; i < 40; ++i) {
      const Vec2 motor{7.0, i % 3 == 0 ? 1.5 : -0.5};
      advance(mixed, in_mixed, motor);
      advance(reference, in_reference, motor);
      ASSERT_EQ(in_mixed.position, in_reference.position) << "start x " << start_x << ", frame " << i;
    }
    CursorState exact = cursor_at({start_x, 250.5});
    for (int i = 0; i < 40; ++i) advance(all_exact, exact, {7.0, i % 3 == 0 ? 1.5 : -0.5});
    differing += exact.position != in_mixed.position;
  }
  EXPECT_EQ(differing, 1) << "only the frames starting in the frame_midpoint region walk differently";
}

TEST(RegionOptions, DirectionTablesPerRegionWithTheirOwnDirections) {
  EngineOptions lut8{Traversal::direction_lut, Sampling::nearest, 8};
  EngineOptions lut16{Traversal::direction_lut, Sampling::nearest, 16};
  Region a = curvature_target(sharp_bump(), {0, 0});
  Region b = curvature_target(sharp_bump(), {600, 0});
  Region c = curvature_target(sharp_bump(), {1200, 0});
  a.options = lut8;
  b.options = lut16;
  Scene scene(std::vector<Region>{a, b, c});
  ASSERT_NE(scene.direction_lut(0), nullptr);
  ASSERT_NE(scene.direction_lut(1), nullptr);
  EXPECT_EQ(scene.direction_lut(0)->directions(), 8);
  EXPECT_EQ(scene.direction_lut(1)->directions(), 16);
  EXPECT_EQ(scene.direction_lut(2), nullptr) << "the third region walks with the scene's exact options";
  // A frame from the 8-direction region into the 16-direction one reads each table with its own directions.
  CursorState cursor = cursor_at({450.5, 250.5});
  for (int i = 0; i < 60; ++i) {
    const FrameResult r = advance(scene, cursor, {9.0, 0.3});
    ASSERT_TRUE(std::isfinite(r.display.x) && std::isfinite(r.display.y));
  }
  EXPECT_GT(cursor.position.x, 600.0);
}

std::filesystem::path write_scene(const std::filesystem::path& dir, const std::string& text) {
  const std::filesystem::path file = dir / "scene.toml";
  std::ofstream(file) << text;
  return file;
}

TEST(RegionOptions, SceneFileSetsThemPerRegionAndAutoChoosesAtLoad) {
  const ScratchDir dir("variant-choice");
  TargetSpec gentle = gentle_bump(), sharp = sharp_bump();
  write_target_files(dir.path(), {gentle, sharp});
  const std::string text =
      "[daemon]\ntraversal = \"exact\"\n"
      "[[region]]\nname = \"gentle\"\nwidth = 500\nheight = 500\nnormal_map = \"" +
      gentle.name() + ".normal.png\"\ntraversal = \"auto\"\n" +
      "[[region]]\nname = \"sharp\"\nx = 600\nwidth = 500\nheight = 500\nnormal_map = \"" + sharp.name() +
      ".normal.png\"\ntraversal = \"auto\"\naccuracy_px = 0.1\n" +
      "[[region]]\nname = \"lut\"\nx = 1200\nwidth = 500\nheight = 500\nnormal_map = \"" + sharp.name() +
      ".normal.png\"\ntraversal = \"direction_lut\"\nlut_directions = 8\n" +
      "[[region]]\nname = \"plain\"\ny = 600\nwidth = 500\nheight = 500\nnormal_map = \"" + sharp.name() +
      ".normal.png\"\n";
  const SceneSpec spec = parse_scene_file(write_scene(dir.path(), text));
  ASSERT_EQ(spec.regions.size(), 4u);
  EXPECT_TRUE(spec.regions[0].engine_auto);
  EXPECT_EQ(spec.regions[1].accuracy_px, 0.1);
  SceneLoadReport report;
  const Scene scene = load_scene(spec, &report);
  ASSERT_EQ(report.variants.size(), 4u);
  EXPECT_EQ(scene.regions()[0].options->traversal, Traversal::frame_midpoint) << report.variants[0];
  EXPECT_EQ(scene.regions()[1].options->traversal, Traversal::exact) << report.variants[1];
  EXPECT_EQ(scene.regions()[2].options->traversal, Traversal::direction_lut);
  EXPECT_EQ(scene.direction_lut(2)->directions(), 8);
  EXPECT_FALSE(scene.regions()[3].options.has_value());
  EXPECT_EQ(report.variants[0].rfind("auto: frame_midpoint", 0), 0u) << report.variants[0];
  EXPECT_EQ(report.variants[1].rfind("auto: exact", 0), 0u) << report.variants[1];
  EXPECT_EQ(report.variants[2], "direction_lut8 (set in the region)");
  EXPECT_EQ(report.variants[3], "exact (the [daemon] table's)");
}

// A hybrid region's steps are found when the scene prepares it: auto must look at the region after that. Before, it
// saw curvature on flat normals, chose the cheap walk, and the step (C/D 0.67 to 4 with the exact walk) was not felt.
TEST(RegionOptions, AutoSeesAHybridRegionsSteps) {
  const ScratchDir dir("variant-choice-hybrid");
  write_normal_png16(dir / "flat.normal.png", NormalImage(64, 64));
  Grid<float> block(64, 64, 0.25f);
  for (int y = 16; y < 48; ++y)
    for (int x = 16; x < 48; ++x) block.at(x, y) = 0.75f;
  write_gray_png16(dir / "block.depth.png", block);
  const SceneSpec spec = parse_scene_file(
      write_scene(dir.path(),
                  "[[region]]\nwidth = 64\nheight = 64\nmethod = \"hybrid\"\nnormal_map = \"flat.normal.png\"\n"
                  "depth_map = \"block.depth.png\"\nrelief_px = 16\ntraversal = \"auto\"\n"));
  SceneLoadReport report;
  const Scene scene = load_scene(spec, &report);
  ASSERT_TRUE(scene.regions()[0].options.has_value());
  EXPECT_EQ(scene.regions()[0].options->traversal, Traversal::exact) << report.variants.at(0);
  EXPECT_EQ(report.variants.at(0).rfind("auto: exact", 0), 0u) << report.variants.at(0);
}

TEST(RegionOptions, SceneFileRejectsWhatAutoCannotUse) {
  const ScratchDir dir("variant-choice-errors");
  const std::string region = "[[region]]\nwidth = 10\nheight = 10\nnormal_map = \"n.png\"\n";
  auto error_of = [&](const std::string& extra) {
    try {
      parse_scene_file(write_scene(dir.path(), region + extra));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("accuracy_px = 0.5\n").find("region[0].accuracy_px: applies to traversal = \"auto\" only"),
            std::string::npos);
  EXPECT_NE(error_of("traversal = \"auto\"\naccuracy_px = 0\n").find("region[0].accuracy_px: must be a number > 0"),
            std::string::npos);
  EXPECT_NE(error_of("traversal = \"auto\"\nsampling = \"bilinear\"\n").find("nearest sampling"), std::string::npos);
  EXPECT_NE(error_of("traversal = \"fast\"\n").find("unknown 'fast'"), std::string::npos);
  EXPECT_NE(error_of("lut_directions = 12\n").find("must be 8 or 16"), std::string::npos);
  // A count for a traversal without a direction table changes nothing: said, as accuracy_px without "auto" is.
  EXPECT_NE(error_of("lut_directions = 8\n")
                .find(":5: region[0].lut_directions: applies to traversal = \"direction_lut\" only"),
            std::string::npos)
      << error_of("lut_directions = 8\n");
  EXPECT_EQ(error_of("traversal = \"direction_lut\"\nlut_directions = 8\n"), "no error");
  // Nor with "auto", which never walks with a direction table.
  EXPECT_NE(error_of("traversal = \"auto\"\nlut_directions = 8\n").find("changes nothing with traversal = \"auto\""),
            std::string::npos);
  // A sampling the direction table cannot take, from the [daemon] table, is said at the region's traversal.
  const std::string daemon_bilinear = "[daemon]\nsampling = \"bilinear\"\n";
  try {
    parse_scene_file(write_scene(dir.path(), daemon_bilinear + region + "traversal = \"direction_lut\"\n"));
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(":7: region[0].traversal: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(the sampling is the [daemon] table's)"), std::string::npos) << e.what();
  }
  EXPECT_NE(error_of("traversal = \"direction_lut\"\nsampling = \"bilinear\"\n"), "no error");
}

}  // namespace
}  // namespace ph
