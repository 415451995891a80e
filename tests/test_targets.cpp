// The 24 analytic targets (core/engine/targets) and the files written from them (config/target_files).
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "config/image_io.hpp"
#include "config/target_files.hpp"
#include "core/engine/decode.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/targets.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

// Points spread over the whole target on an irregular lattice, so none falls on the centre or the rim.
std::vector<Vec2> sample_points(const TargetSpec& spec) {
  std::vector<Vec2> points;
  for (double y = 3.17; y < spec.size; y += 23.3) {
    for (double x = 1.91; x < spec.size; x += 19.7) points.push_back({x, y});
  }
  return points;
}

double distance_from_centre(const TargetSpec& spec, Vec2 p) {
  const double c = spec.size / 2.0;
  return length(p - Vec2{c, c});
}

// The embedded default scene follows the desktop: the targets side by side in its middle, 75 px apart on full HD
// (the layout it was first given), closer where only that lets three fit, and as many as fit its width, at least one.
TEST(DefaultScene, LaysOutAsManyTargetsAsFitInTheMiddleOfTheDesktop) {
  auto xs = [](const Rect& desktop) {
    std::vector<int> out;
    for (const Rect& r : default_scene_layout(desktop)) {
      EXPECT_EQ(r.w, 500);
      EXPECT_EQ(r.h, 500);
      EXPECT_EQ(r.y, desktop.y + (desktop.h - 500) / 2);
      out.push_back(r.x);
    }
    return out;
  };
  EXPECT_EQ(xs(kDefaultSceneDesktop), (std::vector<int>{135, 710, 1285}));
  EXPECT_EQ(xs({0, 0, 3840, 2160}), (std::vector<int>{1095, 1670, 2245}));
  EXPECT_EQ(xs({0, 0, 1536, 864}), (std::vector<int>{9, 518, 1027}));     // 9 px apart
  EXPECT_EQ(xs({0, 0, 1500, 900}), (std::vector<int>{0, 500, 1000}));     // touching
  EXPECT_EQ(xs({0, 0, 1366, 768}), (std::vector<int>{145, 720}));         // two
  EXPECT_EQ(xs({-1366, 0, 1366, 768}), (std::vector<int>{-1221, -646}));  // a desktop left of the origin
  EXPECT_EQ(xs({0, 0, 800, 600}), (std::vector<int>{150}));
  EXPECT_EQ(xs({0, 0, 300, 200}), (std::vector<int>{-100}));  // one, cut: smaller than a target

  const Scene scene = default_scene(Rect{0, 0, 1366, 768});
  ASSERT_EQ(scene.regions().size(), 2u);
  EXPECT_EQ(scene.regions()[0].name, "bump-gaussian-h1-r200");
  EXPECT_EQ(scene.regions()[1].name, "hole-polynomial-h1-r200");
  EXPECT_TRUE(default_scene_laid_out_for(scene, {0, 0, 1366, 768}));
  EXPECT_FALSE(default_scene_laid_out_for(scene, {0, 0, 1370, 768}));
  EXPECT_FALSE(default_scene_laid_out_for(scene, kDefaultSceneDesktop));
  EXPECT_EQ(default_scene_places(scene),
            "bump-gaussian-h1-r200 at 145,134, hole-polynomial-h1-r200 at 720,134 (500x500 px each)");
}

TEST(Targets, AllTargetsHaveDistinctNamesInTheStatedOrder) {
  const std::vector<TargetSpec> targets = all_targets();
  ASSERT_EQ(targets.size(), 24u);
  std::vector<std::string> expected;
  for (const char* shape : {"bump", "hole"}) {
    for (const char* profile : {"linear", "gaussian", "polynomial"}) {
      for (const char* height : {"0.25", "1"}) {
        for (const char* radius : {"100", "200"}) {
          expected.push_back(std::string(shape) + "-" + profile + "-h" + height + "-r" + radius);
        }
      }
    }
  }
  std::set<std::string> distinct;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    EXPECT_EQ(targets[i].name(), expected[i]);
    EXPECT_EQ(targets[i].size, 500);
    EXPECT_EQ(targets[i].relief_px, 100.0);
    distinct.insert(targets[i].name());
  }
  EXPECT_EQ(distinct.size(), 24u);
}

TEST(Targets, NamesOfTheBrief) {
  EXPECT_EQ((TargetSpec{TargetShape::bump, TargetProfile::gaussian, 1.0, 200.0}.name()), "bump-gaussian-h1-r200");
  EXPECT_EQ((TargetSpec{TargetShape::hole, TargetProfile::linear, 0.25, 100.0}.name()), "hole-linear-h0.25-r100");
  EXPECT_EQ((TargetSpec{TargetShape::bump, TargetProfile::polynomial, 0.25, 200.0}.name()),
            "bump-polynomial-h0.25-r200");
}

TEST(Targets, ExactGradientMatchesCentralDifferencesAwayFromKinks) {
  constexpr double step = 1e-5;  // px
  for (const TargetSpec& spec : all_targets()) {
    std::size_t checked = 0;
    for (const Vec2 p : sample_points(spec)) {
      const double r = distance_from_centre(spec, p);
      if (r < 0.01 || std::abs(r - spec.radius) < 0.01) continue;  // the apex and the rim are kinks or steps
      const double fd_x =
          (target_height(spec, p + Vec2{step, 0}) - target_height(spec, p - Vec2{step, 0})) / (2 * step);
      const double fd_y =
          (target_height(spec, p + Vec2{0, step}) - target_height(spec, p - Vec2{0, step})) / (2 * step);
      const Gradient g = target_gradient(spec, p);
      ASSERT_NEAR(g.x, fd_x, 1e-5 + 1e-5 * std::abs(fd_x)) << spec.name() << " at " << p.x << ", " << p.y;
      ASSERT_NEAR(g.y, fd_y, 1e-5 + 1e-5 * std::abs(fd_y)) << spec.name() << " at " << p.x << ", " << p.y;
      ++checked;
    }
    EXPECT_GT(checked, 500u) << spec.name();
  }
}

TEST(Targets, GradientPointsUphillTowardTheCentreOfABump) {
  const TargetSpec spec{TargetShape::bump, TargetProfile::gaussian, 1.0, 200.0};
  // Right of and below the centre (y down): the height falls with x and with y.
  const Gradient g = target_gradient(spec, {300.0, 320.0});
  EXPECT_LT(g.x, 0.0f);
  EXPECT_LT(g.y, 0.0f);
}

TEST(Targets, BumpAndHoleAreMirrorImages) {
  for (const TargetSpec& bump : all_targets()) {
    if (bump.shape != TargetShape::bump) continue;
    TargetSpec hole = bump;
    hole.shape = TargetShape::hole;
    for (const Vec2 p : sample_points(bump)) {
      EXPECT_EQ(target_height(hole, p), -target_height(bump, p));
      const Gradient gb = target_gradient(bump, p);
      const Gradient gh = target_gradient(hole, p);
      EXPECT_EQ(gh.x, -gb.x);
      EXPECT_EQ(gh.y, -gb.y);
    }
    const NormalImage nb = target_normal_image(bump);
    const NormalImage nh = target_normal_image(hole);
    for (std::size_t i = 0; i < nb.values.size(); i += 997) {
      EXPECT_EQ(nh.values[i].x, -nb.values[i].x);
      EXPECT_EQ(nh.values[i].y, -nb.values[i].y);
      EXPECT_EQ(nh.values[i].z, nb.values[i].z);
    }
  }
}

TEST(Targets, HeightsAtCentreRimAndOutside) {
  for (const TargetSpec& spec : all_targets()) {
    const double sign = spec.shape == TargetShape::bump ? 1.0 : -1.0;
    const double peak = sign * spec.height * spec.relief_px;
    const Vec2 centre{250.0, 250.0};
    EXPECT_DOUBLE_EQ(target_height(spec, centre), peak) << spec.name();
    EXPECT_EQ(target_gradient(spec, centre).x, 0.0f);
    EXPECT_EQ(target_gradient(spec, centre).y, 0.0f);

    // Exactly on the rim the inside value holds; the Gaussian keeps exp(-4.5) of its peak there (a step).
    const Vec2 rim{250.0 + spec.radius, 250.0};
    const double rim_fraction = spec.profile == TargetProfile::gaussian ? std::exp(-4.5) : 0.0;
    EXPECT_NEAR(target_height(spec, rim), peak * rim_fraction, 1e-12) << spec.name();
    const Gradient just_inside = target_gradient(spec, rim - Vec2{1e-9, 0.0});
    EXPECT_NEAR(target_gradient(spec, rim).x, just_inside.x, 1e-6) << spec.name();
    EXPECT_NE(target_gradient(spec, rim).x, 0.0f) << spec.name();  // every profile has a kink at the rim

    const Vec2 outside{250.0 + spec.radius + 1e-6, 250.0};
    EXPECT_EQ(target_height(spec, outside), 0.0);
    EXPECT_EQ(target_gradient(spec, outside).x, 0.0f);
    EXPECT_EQ(target_height(spec, {0.5, 0.5}), 0.0);
  }
}

TEST(Targets, RasterisedFieldsSampleTexelCentres) {
  const TargetSpec spec{TargetShape::hole, TargetProfile::polynomial, 1.0, 100.0};
  const DepthField depth = target_depth_field(spec);
  const GradientField gradient = target_gradient_field(spec);
  ASSERT_EQ(depth.width, 500);
  ASSERT_EQ(depth.height, 500);
  ASSERT_EQ(gradient.width, 500);
  ASSERT_EQ(gradient.height, 500);
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{249, 250}, std::pair{300, 220}, std::pair{499, 499}}) {
    const Vec2 centre{x + 0.5, y + 0.5};
    EXPECT_EQ(depth.at(x, y), static_cast<float>(target_height(spec, centre)));
    EXPECT_EQ(gradient.at(x, y).x, target_gradient(spec, centre).x);
    EXPECT_EQ(gradient.at(x, y).y, target_gradient(spec, centre).y);
  }
  // The texels around the centre are symmetric: the centre lies on the corner between four texels.
  EXPECT_EQ(depth.at(249, 249), depth.at(250, 250));
  EXPECT_EQ(depth.at(249, 250), depth.at(250, 249));
}

TEST(Targets, NormalsAreUnitFacingTheViewerAndMatchTheExactGradient) {
  for (const TargetSpec& spec : all_targets()) {
    const NormalImage normals = target_normal_image(spec);
    ASSERT_EQ(normals.width, spec.size);
    ASSERT_EQ(normals.height, spec.size);
    for (const Normal& n : normals.values) {
      const double len = std::sqrt(double{n.x} * n.x + double{n.y} * n.y + double{n.z} * n.z);
      ASSERT_NEAR(len, 1.0, 1e-6) << spec.name();
      ASSERT_GT(n.z, 0.0f) << spec.name();
    }
    for (const auto& [x, y] : {std::pair{130, 270}, std::pair{250, 180}, std::pair{330, 330}}) {
      const Normal expected = normal_from_gradient(target_gradient(spec, {x + 0.5, y + 0.5}));
      EXPECT_EQ(normals.at(x, y).x, expected.x);
      EXPECT_EQ(normals.at(x, y).y, expected.y);
      EXPECT_EQ(normals.at(x, y).z, expected.z);
    }
  }
}

TEST(TargetFiles, SceneTextHasTheLoaderFormat) {
  const TargetSpec spec{TargetShape::bump, TargetProfile::gaussian, 1.0, 200.0};
  EXPECT_EQ(target_scene_text(spec),
            "# pseudohaptic scene: target bump-gaussian-h1-r200 of Argelaguet et al. 2012, Fig. 3\n"
            "# Both maps are given, so the region works with either method (\"curvature\" or \"depth\").\n"
            "[[region]]\n"
            "name = \"bump-gaussian-h1-r200\"\n"
            "x = 0\n"
            "y = 0\n"
            "width = 500\n"
            "height = 500\n"
            "method = \"curvature\"\n"
            "normal_map = \"bump-gaussian-h1-r200.normal.png\"\n"
            "normal_green = \"opengl\"\n"
            "depth_map = \"bump-gaussian-h1-r200.depth.png\"\n"
            "depth_zero = 0.5\n"
            "relief_px = 200.0   # normalised depth 1 = 100 px of relief: v in [0,1] holds (depth + 1) / 2\n");

  TargetSpec odd = spec;
  odd.relief_px = 60.25;
  EXPECT_NE(target_scene_text(odd).find("relief_px = 120.5   # normalised depth 1 = 60.25 px"), std::string::npos);
}

TEST(TargetFiles, RoundTripThroughTheWrittenFiles) {
  const ScratchDir dir("roundtrip");
  const std::vector<TargetSpec> targets = {
      TargetSpec{TargetShape::bump, TargetProfile::gaussian, 1.0, 200.0},
      TargetSpec{TargetShape::hole, TargetProfile::linear, 0.25, 100.0},
      TargetSpec{TargetShape::hole, TargetProfile::polynomial, 1.0, 100.0},
  };
  EXPECT_FALSE(target_files_present(dir.path(), targets));

  std::vector<std::size_t> progress_calls;
  const std::vector<std::filesystem::path> scenes = write_target_files(
      dir.path() / "nested", targets, [&](std::size_t done, std::size_t total, const TargetSpec& spec) {
        EXPECT_EQ(total, targets.size());
        EXPECT_EQ(spec.name(), targets[done - 1].name());
        progress_calls.push_back(done);
      });
  EXPECT_EQ(progress_calls, (std::vector<std::size_t>{1, 2, 3}));
  ASSERT_EQ(scenes.size(), targets.size());
  EXPECT_TRUE(target_files_present(dir.path() / "nested", targets));
  EXPECT_FALSE(target_files_present(dir.path() / "nested", all_targets()));

  for (std::size_t t = 0; t < targets.size(); ++t) {
    const TargetSpec& spec = targets[t];
    const std::string name = spec.name();
    const TargetFilePaths paths = target_file_paths(dir.path() / "nested", spec);
    EXPECT_EQ(scenes[t], paths.scene);
    EXPECT_EQ(paths.normal_map.filename(), name + ".normal.png");
    EXPECT_EQ(paths.depth_map.filename(), name + ".depth.png");
    EXPECT_EQ(paths.scene.filename(), name + ".toml");

    const std::string scene = read_file_text(paths.scene);
    EXPECT_EQ(scene, target_scene_text(spec));
    EXPECT_NE(scene.find("name = \"" + name + "\""), std::string::npos);
    EXPECT_NE(scene.find("normal_map = \"" + name + ".normal.png\""), std::string::npos);
    EXPECT_NE(scene.find("depth_map = \"" + name + ".depth.png\""), std::string::npos);

    DecodeReport report;
    const NormalImage decoded = decode_normals(read_image(paths.normal_map), NormalDecodeOptions{}, report);
    const NormalImage exact = target_normal_image(spec);
    ASSERT_EQ(decoded.width, exact.width);
    ASSERT_EQ(decoded.height, exact.height);
    EXPECT_EQ(report.invalid_texels, 0u);
    for (std::size_t i = 0; i < exact.values.size(); ++i) {
      ASSERT_NEAR(decoded.values[i].x, exact.values[i].x, 2e-4) << name << " texel " << i;
      ASSERT_NEAR(decoded.values[i].y, exact.values[i].y, 2e-4) << name << " texel " << i;
      ASSERT_NEAR(decoded.values[i].z, exact.values[i].z, 2e-4) << name << " texel " << i;
    }

    const RawImage depth = read_image(paths.depth_map);
    ASSERT_EQ(depth.width, spec.size);
    ASSERT_EQ(depth.height, spec.size);
    ASSERT_EQ(depth.channels, 1);
    const DepthField heights = target_depth_field(spec);
    for (std::size_t i = 0; i < heights.values.size(); ++i) {
      const double v = (heights.values[i] / spec.relief_px + 1.0) / 2.0;
      ASSERT_NEAR(depth.pixels[i], v, 2.0 / 65535.0) << name << " texel " << i;
    }
  }
}

}  // namespace
}  // namespace ph
