// The hybrid method (docs/METHODS.md, "Hybrid"): the depth method's C/D where the heights jump more than the
// normals explain, the curvature method's elsewhere, on normals smoothed within the map's noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/decode.hpp"
#include "core/engine/engine_options.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/row_bands.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"
#include "core/lab/map_storage.hpp"
#include "tests/band_agreement.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

class Recorder final : public StepObserver {
 public:
  void on_step(const StepRecord& step) override { steps.push_back(step); }
  std::vector<StepRecord> steps;
};

Scene one_region(RegionFields fields, Rect rect, MethodPtr method) {
  Region region;
  region.name = "r";
  region.rect = rect;
  region.fields = std::move(fields);
  region.method = std::move(method);
  std::vector<Region> regions;
  regions.push_back(std::move(region));
  return Scene(std::move(regions));
}

// A 64 x 16 region, flat normals everywhere, heights 0 left of x = 32 and 10 px from x = 32 on: a cliff that a
// normal map cannot show.
RegionFields cliff_fields() {
  RegionFields fields;
  fields.gradient = GradientField(64, 16, Gradient{});
  fields.depth = DepthField(64, 16, 0.0f);
  for (int y = 0; y < 16; ++y) {
    for (int x = 32; x < 64; ++x) fields.depth->at(x, y) = 10.0f;
  }
  return fields;
}

// C/D of each texel entered along the row y = 8.5 from x0 to x1 (px), keyed by texel x.
std::vector<std::pair<int, double>> row_cds(const Scene& scene, double x0, double x1) {
  Recorder recorder;
  CursorState cursor = cursor_at({x0, 8.5});
  const Vec2 m{x1 > x0 ? 1.0 : -1.0, 0.0};
  for (int i = 0; i < 1000 && (x1 - cursor.position.x) * m.x > 0.0; ++i) advance(scene, cursor, m * 0.5, &recorder);
  std::vector<std::pair<int, double>> out;
  for (const StepRecord& s : recorder.steps) {
    if (s.entered) out.emplace_back(s.texel.x, s.cd);
  }
  return out;
}

TEST(HybridMethod, TakesTheDepthCdAtACliffTheNormalsDoNotShow) {
  const auto hybrid = std::make_shared<HybridMethod>(HybridParams{});
  const Scene scene = one_region(cliff_fields(), {0, 0, 64, 16}, hybrid);
  const DiscontinuityField& marks = *scene.regions()[0].fields.discontinuity;
  for (int x = 0; x < 64; ++x) EXPECT_EQ(marks.at(x, 8), x == 31 || x == 32 ? 1 : 0) << x;
  const DepthParams depth;
  // Uphill across the cliff: the texel after it has the depth method's C/D for a 10 px rise (its kmax).
  for (const auto& [x, cd] : row_cds(scene, 5.0, 60.0)) {
    if (x == 32) {
      EXPECT_EQ(cd, depth.kmax) << x;
    } else {
      EXPECT_EQ(cd, 1.0) << x;  // flat on both sides: the curvature method's C/D 1
    }
  }
  // Downhill: its smallest C/D.
  for (const auto& [x, cd] : row_cds(scene, 60.0, 5.0)) {
    if (x == 31) {
      EXPECT_EQ(cd, 1.0 / depth.kmin) << x;
    } else {
      EXPECT_EQ(cd, 1.0) << x;
    }
  }
  // The curvature method on the same fields never sees it.
  const Scene curvature =
      one_region(cliff_fields(), {0, 0, 64, 16}, std::make_shared<CurvatureMethod>(CurvatureParams{}));
  for (const auto& [x, cd] : row_cds(curvature, 5.0, 60.0)) EXPECT_EQ(cd, 1.0) << x;
}

// The cliff with its normals made from the heights by Sobel, as a generator does: slopes of h/2 on the two texels of
// its edge. The normals explain half of the 10 px, so the edge is still a discontinuity; the texels beside the band,
// level with it but flat, are marked too: the curvature method pairs each texel with the ones behind it and would feel
// the smeared normals there as a wall.
TEST(HybridMethod, TakesTheDepthCdBesideAStepWhoseNormalsAGeneratorSmeared) {
  const auto smeared = [] {
    RegionFields fields = cliff_fields();
    for (int y = 0; y < 16; ++y) fields.gradient->at(31, y).x = fields.gradient->at(32, y).x = 5.0f;
    return fields;
  };
  const Scene scene = one_region(smeared(), {0, 0, 64, 16}, std::make_shared<HybridMethod>(HybridParams{}));
  const DiscontinuityField& marks = *scene.regions()[0].fields.discontinuity;
  for (int x = 0; x < 64; ++x) EXPECT_EQ(marks.at(x, 8), x >= 30 && x <= 33 ? 1 : 0) << x;
  const DepthParams depth;
  for (const auto& [x, cd] : row_cds(scene, 5.0, 60.0)) EXPECT_EQ(cd, x == 32 ? depth.kmax : 1.0) << x;
  for (const auto& [x, cd] : row_cds(scene, 60.0, 5.0)) EXPECT_EQ(cd, x == 31 ? 1.0 / depth.kmin : 1.0) << x;
  // The curvature method on the same fields: a wall over the band and the texel after it.
  const Scene curvature = one_region(smeared(), {0, 0, 64, 16}, std::make_shared<CurvatureMethod>(CurvatureParams{}));
  double largest = 0.0;
  for (const auto& [x, cd] : row_cds(curvature, 5.0, 60.0)) largest = std::max(largest, cd);
  EXPECT_GT(largest, 10.0);
}

// The C/D of every step of a stroke from `from` along the unit vector `m` over `length` px.
std::vector<double> stroke_cds(const Scene& scene, Vec2 from, Vec2 m, double length) {
  Recorder recorder;
  CursorState cursor = cursor_at(from);
  for (double done = 0.0; done < length; done += 0.5) advance(scene, cursor, m * 0.5, &recorder);
  std::vector<double> out;
  for (const StepRecord& s : recorder.steps) out.push_back(s.cd);
  return out;
}

// Steps of 1, 2 and 4 px along a diagonal with their normals made from the heights by Sobel, as a generator
// does: the two texels of each edge carry gradients of length 0.53 h and the texels beside them 0.18 h where the
// heights are level, so a texel two away from the marked edge pairs a flat normal with a smeared one behind it. The
// band of depth's C/D reaches every such texel: crossed at 0, 30, 45 and 60 degrees the hybrid's C/D is the depth
// method's, step for step (before, the flat texels two away kept curvature's and met the smeared normals as a ripple:
// at 4 px until the band was passed on, at 2 px until its decrement became 0.4 `discontinuity_px`, at 1 px until a
// jump between level treads was all unexplained and the band passed on to a residue of a quarter of the steepness).
TEST(HybridMethod, TakesTheDepthCdWhereverAGeneratorSmearedADiagonalStep) {
  for (const float height : {1.0f, 2.0f, 4.0f}) {
    const auto diagonal_step = [height] {
      RegionFields fields;
      fields.depth = DepthField(48, 48, 0.0f);
      for (int y = 0; y < 48; ++y) {
        for (int x = 0; x < 48; ++x) fields.depth->at(x, y) = x + y >= 48 ? height : 0.0f;
      }
      fields.gradient = gradient_from_normals(sobel_normals(*fields.depth));
      return fields;
    };
    const Scene hybrid = one_region(diagonal_step(), {0, 0, 48, 48}, std::make_shared<HybridMethod>(HybridParams{}));
    const Scene depth = one_region(diagonal_step(), {0, 0, 48, 48}, std::make_shared<DepthMethod>(DepthParams{}));
    for (const double degrees : {0.0, 30.0, 45.0, 60.0}) {
      const double a = degrees * std::numbers::pi / 180.0;
      const Vec2 m{std::cos(a), std::sin(a)};
      const Vec2 from = Vec2{24.0, 24.0} - m * 16.0 + Vec2{0.3, 0.1};
      const std::vector<double> by_hybrid = stroke_cds(hybrid, from, m, 32.0),
                                by_depth = stroke_cds(depth, from, m, 32.0);
      ASSERT_EQ(by_hybrid.size(), by_depth.size()) << height << " px at " << degrees << " degrees";
      for (std::size_t i = 0; i < by_hybrid.size(); ++i)
        EXPECT_EQ(by_hybrid[i], by_depth[i]) << height << " px at " << degrees << " degrees, step " << i;
      EXPECT_GT(*std::max_element(by_hybrid.begin(), by_hybrid.end()), 1.5) << degrees;  // the step is felt
    }
  }
}

// A step of 1 px across the rows, its normals the heights' own reading: Sobel's (a generator's) or, where no normal
// map is given, the central differences the region's gradient is then made of. Either gives the edge's two texels a
// slope of 0.5, which explains 0.54 of the step (unexplained: the trapezoid rule with its end correction), so it
// stayed below the default threshold of 0.5 px and the curvature method felt the smeared normals as a ridge. The
// heights are level on both sides: all of it is unexplained, and it is a step.
TEST(HybridMethod, TakesAOnePixelStepBetweenLevelTreadsWhateverReadTheNormals) {
  const auto step_fields = [](bool normal_map) {
    RegionFields fields;
    fields.depth = DepthField(40, 12, 0.0f);
    for (int y = 0; y < 12; ++y) {
      for (int x = 20; x < 40; ++x) fields.depth->at(x, y) = 1.0f;
    }
    fields.gradient =
        normal_map ? gradient_from_normals(sobel_normals(*fields.depth)) : gradient_from_depth(*fields.depth);
    return fields;
  };
  for (const bool normal_map : {true, false}) {
    SCOPED_TRACE(normal_map ? "Sobel normals" : "no normal map");
    const Scene hybrid =
        one_region(step_fields(normal_map), {0, 0, 40, 12}, std::make_shared<HybridMethod>(HybridParams{}));
    EXPECT_FLOAT_EQ(hybrid.regions()[0].fields.gradient->at(19, 6).x, 0.5f);
    const Scene depth =
        one_region(step_fields(normal_map), {0, 0, 40, 12}, std::make_shared<DepthMethod>(DepthParams{}));
    EXPECT_EQ(row_cds(hybrid, 3.0, 37.0), row_cds(depth, 3.0, 37.0));
    EXPECT_EQ(row_cds(hybrid, 37.0, 3.0), row_cds(depth, 37.0, 3.0));
  }
}

// A gentle slope (0.03 px a texel) in a depth map stored in steps of 0.64 px: its heights are level for 21 texels and
// then rise by one step, which its exact normals explain only in part. A single step of the storage is how the map
// rounds the slope, and it is not taken for a jump between level treads (the level edges beside it, whose slopes
// the flat heights leave unexplained by 0.03 each, take back 0.12 of it: 0.52 px left as a jump, 0.49 px as what the
// normals leave unexplained, against the default threshold of 0.5 px); a rise of two steps (1.28 px) onto a tread is
// a step.
TEST(HybridMethod, TakesNoStepOfTheDepthMapsStorageForAJump) {
  for (const bool with_jump : {false, true}) {
    RegionFields fields;
    fields.depth = DepthField(40, 8, 0.0f);
    fields.gradient = GradientField(40, 8, Gradient{0.03f, 0.0f});
    fields.depth_rounding = 0.64 / std::sqrt(12.0);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 40; ++x) {
        const double exact = 0.03 * (x + 0.5) + (with_jump && x >= 30 ? 1.28 : 0.0);
        fields.depth->at(x, y) = static_cast<float>(0.64 * std::floor(exact / 0.64));
      }
    }
    HybridParams params;
    params.noise_slope = 0.0;  // the normals as given
    prepare_hybrid_fields(params, fields);
    for (int x = 0; x < 40; ++x) EXPECT_EQ(fields.discontinuity->at(x, 4), with_jump && (x == 29 || x == 30)) << x;
  }
}

// A wall 1 px wide between level ground and a plateau 2 px higher, with its exact normals: a texel whose centre lies
// on the wall has the wall's slope, which explains the change across its edge however the wall falls between the
// centres, and no texel is marked (the curvature method's rim and foot, as the paper counts them). Heights and
// normals are sampled with the wall's start at every tenth of a texel, off the centres by a twentieth (a wall that
// starts on one centre and ends on the next is flat at both, and its samples are a jump's).
TEST(HybridMethod, MarksNoTexelOfAWallItsExactNormalsShow) {
  for (int tenth = 0; tenth < 10; ++tenth) {
    const double start = 20.05 + tenth / 10.0;
    RegionFields fields;
    fields.depth = DepthField(40, 8, 0.0f);
    fields.gradient = GradientField(40, 8);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 40; ++x) {
        const double u = x + 0.5 - start;
        fields.depth->at(x, y) = static_cast<float>(2.0 * std::clamp(u, 0.0, 1.0));
        fields.gradient->at(x, y) = {u > 0.0 && u < 1.0 ? 2.0f : 0.0f, 0.0f};
      }
    }
    prepare_hybrid_fields(HybridParams{}, fields);
    for (std::uint8_t mark : fields.discontinuity->values) ASSERT_EQ(mark, 0) << "wall from " << start;
  }
}

// With bilinear sampling too: a marked texel takes depth's reading, and the texel after it pairs with flat values,
// not with the smeared normals.
TEST(HybridMethod, BilinearSamplingTakesTheDepthCdAtSteps) {
  EngineOptions bilinear;
  bilinear.sampling = Sampling::bilinear;
  for (const float smear : {0.0f, 5.0f}) {
    RegionFields fields = cliff_fields();
    for (int y = 0; y < 16; ++y) fields.gradient->at(31, y).x = fields.gradient->at(32, y).x = smear;
    Scene scene = one_region(fields, {0, 0, 64, 16}, std::make_shared<HybridMethod>(HybridParams{}));
    scene.set_options(bilinear);
    const DepthParams depth;
    for (const auto& [x, cd] : row_cds(scene, 5.0, 60.0))
      EXPECT_EQ(cd, x == 32 ? depth.kmax : 1.0) << smear << " " << x;
    for (const auto& [x, cd] : row_cds(scene, 60.0, 5.0))
      EXPECT_EQ(cd, x == 31 ? 1.0 / depth.kmin : 1.0) << smear << " " << x;
  }
}

// The C/D of each texel the row y = 8.5 crosses from x0 to x1 (px), as first walked in, keyed by texel x; unlike
// row_cds, also the texel where a region begins (the walk starts a leg there: not "entered").
std::vector<std::pair<int, double>> texel_cds(const Scene& scene, double x0, double x1) {
  std::vector<std::pair<int, double>> out;
  for (const auto& [x, cd] : [&] {
         Recorder recorder;
         CursorState cursor = cursor_at({x0, 8.5});
         const Vec2 m{x1 > x0 ? 1.0 : -1.0, 0.0};
         for (int i = 0; i < 1000 && (x1 - cursor.position.x) * m.x > 0.0; ++i)
           advance(scene, cursor, m * 0.5, &recorder);
         std::vector<std::pair<int, double>> all;
         for (const StepRecord& s : recorder.steps) all.emplace_back(s.texel.x, s.cd);
         return all;
       }()) {
    if (out.empty() || out.back().first != x) out.emplace_back(x, cd);
  }
  return out;
}

// A region of flat normals and a constant height, on the flat desktop or over another region.
RegionFields plateau_fields(int w, int h, float height) {
  RegionFields fields;
  fields.gradient = GradientField(w, h, Gradient{});
  fields.depth = DepthField(w, h, height);
  return fields;
}

Region region_of(std::string name, RegionFields fields, Rect rect, MethodPtr method) {
  Region region;
  region.name = std::move(name);
  region.rect = rect;
  region.fields = std::move(fields);
  region.method = std::move(method);
  return region;
}

// A region raised above the desktop, with flat normals: the depth method feels its border (the desktop counts as
// height 0 there), the hybrid does not look for a step against the desktop, which has no depth map: a surface whose
// border stands off its depth map's zero (the accuracy set's interrogation surfaces, at +-25 px) is not a cliff.
TEST(HybridMethod, LeavesTheBorderWithTheDesktopToTheCurvatureMethod) {
  const auto raised = [](MethodPtr method) {
    return one_region(plateau_fields(32, 16, 2.0f), {20, 0, 32, 16}, method);
  };
  for (const auto& [x, cd] : texel_cds(raised(std::make_shared<HybridMethod>(HybridParams{})), 5.0, 60.0))
    EXPECT_EQ(cd, 1.0) << x;
  const std::vector<std::pair<int, double>> depth =
      texel_cds(raised(std::make_shared<DepthMethod>(DepthParams{})), 5.0, 60.0);
  ASSERT_FALSE(depth.empty());
  EXPECT_EQ(depth.front(), std::make_pair(20, DepthParams{}.kmax));
}

// A region whose surface rises from its border with the slope its normals show: the border is explained, and the
// C/D there is the curvature method's, whatever the height of the border texel.
TEST(HybridMethod, LeavesARegionBorderTheNormalsExplainToTheCurvatureMethod) {
  RegionFields ramp;
  ramp.gradient = GradientField(32, 16, Gradient{1.5f, 0.0f});
  ramp.depth = DepthField(32, 16, 0.0f);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 32; ++x) ramp.depth->at(x, y) = 1.5f * (static_cast<float>(x) + 0.5f);
  }
  RegionFields same = ramp;
  same.depth.reset();
  const Scene hybrid = one_region(std::move(ramp), {20, 0, 32, 16}, std::make_shared<HybridMethod>(HybridParams{}));
  const Scene curvature =
      one_region(std::move(same), {20, 0, 32, 16}, std::make_shared<CurvatureMethod>(CurvatureParams{}));
  const auto expected = texel_cds(curvature, 5.0, 45.0);
  const auto got = texel_cds(hybrid, 5.0, 45.0);
  ASSERT_EQ(got.size(), expected.size());
  ASSERT_FALSE(got.empty());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], expected[i]) << got[i].first;
  EXPECT_NE(got.front().second, DepthParams{}.kmax);  // the border texel, x = 20: not depth's cap
}

// Two overlapping regions: crossing into the upper one where it lies 3 px above the one below is a step; where the
// two are level it is not. The same with bilinear sampling, whose samples carry their heights for it.
TEST(HybridMethod, TakesTheDepthCdWhereARegionOverlapsAnotherBelowIt) {
  const DepthParams depth;
  const auto hybrid = std::make_shared<HybridMethod>(HybridParams{});
  for (const Sampling sampling : {Sampling::nearest, Sampling::bilinear}) {
    for (const float upper : {3.0f, 1.0f}) {
      std::vector<Region> regions;
      regions.push_back(region_of("below", plateau_fields(40, 16, 1.0f), {0, 0, 40, 16}, hybrid));
      regions.push_back(region_of("above", plateau_fields(40, 16, upper), {20, 0, 40, 16}, hybrid));
      Scene scene(std::move(regions));
      EngineOptions options;
      options.sampling = sampling;
      scene.set_options(options);
      for (const auto& [x, cd] : texel_cds(scene, 5.0, 50.0)) {
        const bool step = x == 20 && upper == 3.0f;
        EXPECT_EQ(cd, step ? depth.kmax : 1.0)  // a 2 px rise: 1 + 3 x 2, capped at kmax
            << "x " << x << ", upper region at " << upper << " px, " << name_of(sampling);
      }
    }
  }
}

// Two overlapping regions holding one slope of 0.2 px per px, the upper one raised by exactly discontinuity_px: where
// the walk crosses into it the height changes by the slope plus that, which is no step, however the float heights and
// their sums round (before, crossings at some heights were steps and others not). Raised by a hundredth more, each
// crossing is one. The exact input decides alike at the tie.
TEST(HybridMethod, ARiseOfExactlyTheThresholdIsNoStepHoweverItRounds) {
  const HybridParams params;
  const auto hybrid = std::make_shared<HybridMethod>(params);
  const auto sloped = [](float base) {
    RegionFields fields;
    fields.gradient = GradientField(40, 16, Gradient{0.2f, 0.0f});
    fields.depth = DepthField(40, 16);
    for (int y = 0; y < 16; ++y) {
      for (int x = 0; x < 40; ++x) fields.depth->at(x, y) = static_cast<float>(base + 0.2 * (x + 0.5));
    }
    return fields;
  };
  for (const double offset : {params.discontinuity_px, params.discontinuity_px + 0.01}) {
    int steps = 0, crossings = 0;
    for (int i = 0; i < 40; ++i) {
      const double base = 0.37 * i;  // heights from 0 to about 23 px, each rounding its own way
      std::vector<Region> regions;
      regions.push_back(region_of("below", sloped(static_cast<float>(base)), {0, 0, 40, 16}, hybrid));
      // The upper region's first texel holds the lower slope continued 20 px, plus the offset.
      regions.push_back(
          region_of("above", sloped(static_cast<float>(base + 0.2 * 20 + offset)), {20, 0, 40, 16}, hybrid));
      const Scene scene(std::move(regions));
      for (const auto& [x, cd] : texel_cds(scene, 5.0, 50.0)) {
        if (x != 20) continue;
        ++crossings;
        if (cd == DepthParams{}.kmax || cd > 3.0) ++steps;
      }
    }
    EXPECT_EQ(crossings, 40) << offset;
    EXPECT_EQ(steps, offset == params.discontinuity_px ? 0 : 40) << offset;
  }
  SurfacePoint tie;
  tie.height = 17.3;
  tie.rise = 0.7;
  tie.unexplained_rise = params.discontinuity_px;
  // A step's sample carries v2 = +infinity (curvature's is finite or NaN).
  constexpr double kStep = std::numeric_limits<double>::infinity();
  EXPECT_NE(hybrid->sample_exact(tie, {1.0, 0.0}).v2, kStep);
  tie.unexplained_rise = params.discontinuity_px + 1e-3;
  EXPECT_EQ(hybrid->sample_exact(tie, {1.0, 0.0}).v2, kStep);
}

TEST(HybridMethod, ASlopeTheNormalsExplainIsNoDiscontinuity) {
  // A ramp of 2 px per px along x with matching normals, and a 0.4 px step (below discontinuity_px).
  RegionFields fields;
  fields.gradient = GradientField(32, 8, Gradient{2.0f, 0.0f});
  fields.depth = DepthField(32, 8);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 32; ++x) fields.depth->at(x, y) = 2.0f * x + (x >= 16 ? 0.4f : 0.0f);
  }
  const Scene scene = one_region(std::move(fields), {0, 0, 32, 8}, std::make_shared<HybridMethod>(HybridParams{}));
  for (std::uint8_t mark : scene.regions()[0].fields.discontinuity->values) EXPECT_EQ(mark, 0);
}

// On the 24 targets the only discontinuities are the Gaussian profile's rim, where the truncated Gaussian
// steps down by about 1 px (docs/METHODS.md, "The 24 targets"); kinks (the linear apex, the rims of the linear and
// polynomial profiles) are explained by the normals. Where nothing is marked, and with no smoothing asked for,
// the hybrid is the curvature method, bit for bit, step by step.
TEST(HybridMethod, IsTheCurvatureMethodOnContinuousMapsWithoutSmoothing) {
  HybridParams no_smoothing;
  no_smoothing.noise_slope = 0.0;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const TargetSpec& spec : all_targets()) {
    const Rect rect{0, 0, spec.size, spec.size};
    RegionFields fields;
    fields.gradient = target_gradient_field(spec);
    fields.depth = target_depth_field(spec);
    const Scene hybrid = one_region(fields, rect, std::make_shared<HybridMethod>(no_smoothing));
    const DiscontinuityField& marks = *hybrid.regions()[0].fields.discontinuity;
    int marked = 0;
    for (int y = 0; y < spec.size; ++y) {
      for (int x = 0; x < spec.size; ++x) {
        if (marks.at(x, y) == 0) continue;
        ++marked;
        const double r = std::hypot(x + 0.5 - spec.size / 2.0, y + 0.5 - spec.size / 2.0);
        ASSERT_LT(std::abs(r - spec.radius), 1.5) << spec.name() << " " << x << "," << y;
      }
    }
    const bool gaussian_step = spec.profile == TargetProfile::gaussian && spec.height == 1.0;
    EXPECT_EQ(marked > 0, gaussian_step) << spec.name();
    if (marked > 0) continue;
    const Scene curvature = one_region(fields, rect, std::make_shared<CurvatureMethod>(CurvatureParams{}));
    for (int k = 0; k < 6; ++k) {
      const double phi = 2.0 * std::numbers::pi * u(rng);
      const Vec2 m{std::cos(phi), std::sin(phi)};
      CursorState a = cursor_at({spec.size / 2.0 - 200.0 * m.x, spec.size / 2.0 - 200.0 * m.y}), b = a;
      for (int f = 0; f < 100; ++f) {
        const Vec2 motor = m * (0.3 + 6.0 * u(rng));
        const FrameResult ra = advance(hybrid, a, motor), rb = advance(curvature, b, motor);
        ASSERT_EQ(ra.display.x, rb.display.x) << spec.name();
        ASSERT_EQ(ra.display.y, rb.display.y) << spec.name();
        ASSERT_EQ(ra.cd_max, rb.cd_max) << spec.name();
      }
    }
  }
}

// Smoothing within the noise band: an 8-bit-like rounding of a gentle slope (steps of 1/128 in the gradient, as
// the fields say) becomes the slope again, and a rim (a jump of 0.5 in the gradient) stays sharp.
TEST(HybridMethod, SmoothsNoiseAndKeepsFeatures) {
  RegionFields fields;
  fields.gradient = GradientField(64, 8);
  fields.gradient_rounding = gradient_rounding_of_normals(1.0 / 128.0);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 64; ++x) {
      const double exact = 0.002 * x;  // the slope of a gentle curve
      const double rounded = std::round(exact * 128.0) / 128.0;
      fields.gradient->at(x, y) = {static_cast<float>(x < 48 ? rounded : 0.5 + rounded), 0.0f};
    }
  }
  const RegionFields before = fields;
  prepare_hybrid_fields(HybridParams{}, fields);
  double rounded_error = 0.0, smoothed_error = 0.0;
  for (int x = 4; x < 44; ++x) {
    rounded_error += std::abs(before.gradient->at(x, 4).x - 0.002 * x);
    smoothed_error += std::abs(fields.gradient->at(x, 4).x - 0.002 * x);
  }
  EXPECT_LT(smoothed_error, 0.5 * rounded_error);
  // Either side of the rim keeps its own value.
  EXPECT_EQ(fields.gradient->at(47, 4).x, before.gradient->at(47, 4).x);
  EXPECT_EQ(fields.gradient->at(48, 4).x, before.gradient->at(48, 4).x);
}

// A Gaussian hill 6 px high on a 64 x 64 region: its exact gradient and its heights at texel centres.
RegionFields hill_fields() {
  RegionFields fields;
  fields.gradient = GradientField(64, 64);
  fields.depth = DepthField(64, 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const double dx = x + 0.5 - 32.0, dy = y + 0.5 - 32.0, s2 = 2.0 * 12.0 * 12.0;
      const double h = 6.0 * std::exp(-(dx * dx + dy * dy) / s2);
      fields.depth->at(x, y) = static_cast<float>(h);
      fields.gradient->at(x, y) = {static_cast<float>(-2.0 * dx / s2 * h), static_cast<float>(-2.0 * dy / s2 * h)};
    }
  }
  return fields;
}

double rms_difference(const GradientField& a, const GradientField& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    sum += std::pow(a.values[i].x - b.values[i].x, 2) + std::pow(a.values[i].y - b.values[i].y, 2);
  }
  return std::sqrt(sum / static_cast<double>(a.values.size()));
}

// `fields` with Gaussian noise of standard deviation `sigma` added to both slopes of every texel's normal.
RegionFields with_gaussian_noise(RegionFields fields, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (Gradient& g : fields.gradient->values) {
    g.x += static_cast<float>(noise(rng));
    g.y += static_cast<float>(noise(rng));
  }
  return fields;
}

// Normals far noisier than the map's rounding over a clean depth map: the noise is estimated from the maps and the
// gradient pulled to the depth map's slopes, which the smoothing within the fixed band alone could not do.
TEST(HybridMethod, PullsNoisyNormalsToTheSlopesOfACleanDepthMap) {
  const RegionFields clean = hill_fields();
  RegionFields noisy = with_gaussian_noise(clean, 0.05, 5);
  const double before = rms_difference(*noisy.gradient, *clean.gradient);
  RegionFields normals_only = noisy;
  normals_only.depth.reset();
  prepare_hybrid_fields(HybridParams{}, normals_only);
  prepare_hybrid_fields(HybridParams{}, noisy);
  EXPECT_GT(rms_difference(*normals_only.gradient, *clean.gradient), 0.5 * before);  // the band is far too narrow
  EXPECT_LT(rms_difference(*noisy.gradient, *clean.gradient), 0.05 * before);        // measured 0.028
  ASSERT_TRUE(noisy.fused_normals_weight);                                           // what check-config reports
  EXPECT_LT(*noisy.fused_normals_weight, 0.01);
  EXPECT_FALSE(normals_only.fused_normals_weight);
  for (std::uint8_t mark : noisy.discontinuity->values) EXPECT_EQ(mark, 0);
}

// A plane rising 0.1 px per px, width x height, as exact heights and normals with noise of sigma 0.05 added where
// `noisy(x)`; `noise` gets the noise's root sum of squares.
RegionFields noisy_plane(int width, int height, std::uint64_t seed, bool (*noisy)(int x), double& noise) {
  RegionFields fields;
  fields.gradient = GradientField(width, height);
  fields.depth = DepthField(width, height);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 0.05);
  double sum = 0.0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      fields.depth->at(x, y) = 0.1f * static_cast<float>(x);
      const double nx = noisy(x) ? gauss(rng) : 0.0, ny = noisy(x) ? gauss(rng) : 0.0;
      fields.gradient->at(x, y) = {static_cast<float>(0.1 + nx), static_cast<float>(ny)};
      sum += nx * nx + ny * ny;
    }
  }
  noise = std::sqrt(sum);
  return fields;
}

// The root sum of squares of a plane's gradient errors after the hybrid's preparation.
double error_after_preparing(RegionFields fields) {
  prepare_hybrid_fields(HybridParams{}, fields);
  double sum = 0.0;
  for (const Gradient& g : fields.gradient->values) sum += std::pow(g.x - 0.1, 2) + std::pow(g.y, 2);
  return std::sqrt(sum);
}

// The same on a region of more than 2^20 texels, whose noise is estimated from a sample of its texels.
TEST(HybridMethod, EstimatesTheNoiseOfALargeRegionFromASample) {
  double noise = 0.0;
  const RegionFields fields = noisy_plane(
      1200, 900, 7, [](int) { return true; }, noise);
  EXPECT_LT(error_after_preparing(fields), 0.01 * noise);
}

// A region too large to read every texel (1200 x 300 px: every third is read where every texel would be, up to
// 2^17) whose normals are noisy on two columns in three, clean on the third: the texels read must fall on every
// column, or the noise is not seen (with every third texel read, a width divisible by three reads one column in
// three on every row) and the depth map's clean slopes are not taken.
TEST(HybridMethod, ReadsEveryColumnOfALargeRegion) {
  double noise = 0.0;
  const RegionFields fields = noisy_plane(
      1200, 300, 11, [](int x) { return x % 3 != 0; }, noise);
  // Measured 0.35: a third of the texels are clean, which narrows the band of what is noise (fuse_with_depth_gradient).
  EXPECT_LT(error_after_preparing(fields), 0.5 * noise);
}

// Two maps of one relief that each explain the other, with the noise band the same everywhere: the hybrid fuses
// nothing, so its gradient is bit for bit the one it prepares from the normal map alone.
void expect_not_fused(const RegionFields& fields) {
  HybridParams same_band;
  same_band.far_noise_gain = 0.0;
  RegionFields with_depth = fields, alone = fields;
  alone.depth.reset();
  prepare_hybrid_fields(same_band, with_depth);
  prepare_hybrid_fields(same_band, alone);
  EXPECT_FALSE(with_depth.fused_normals_weight);
  for (std::size_t i = 0; i < alone.gradient->values.size(); ++i) {
    ASSERT_EQ(with_depth.gradient->values[i].x, alone.gradient->values[i].x) << i;
    ASSERT_EQ(with_depth.gradient->values[i].y, alone.gradient->values[i].y) << i;
  }
}

// Normals that agree with their heights within the rounding: the depth map changes nothing but what it marks.
TEST(HybridMethod, LeavesACleanNormalMapAsTheNormalMapAloneWouldBe) { expect_not_fused(hill_fields()); }

// The normals' slopes over the depth map's where both show resolved relief: 1 on the hill, whose two maps hold it at
// one scale; 2 with its heights halved (a depth map whose relief_px is half the normal map's scale); still 1 with a
// 10 px cliff across the hill, whose steps and the slopes beside them are not read; none on a flat region with a
// jump, where no resolved slope is left to compare. What the preparation keeps for check-config and the daemon's
// warning (config/scene_file.hpp, relief_scale).
TEST(HybridMethod, ReadsTheRatioOfTheNormalsSlopesToTheDepthMaps) {
  const auto ratio_of = [](RegionFields fields) {
    prepare_hybrid_fields(HybridParams{}, fields);
    return fields.slope_comparison ? fields.slope_comparison->ratio : std::nullopt;
  };
  const std::optional<double> same = ratio_of(hill_fields());
  ASSERT_TRUE(same);
  EXPECT_NEAR(*same, 1.0, 0.02);
  RegionFields halved = hill_fields();
  for (float& h : halved.depth->values) h *= 0.5f;
  const std::optional<double> twice = ratio_of(halved);
  ASSERT_TRUE(twice);
  EXPECT_NEAR(*twice, 2.0, 0.04);
  RegionFields cliff = hill_fields();
  for (int y = 0; y < 64; ++y) {
    for (int x = 40; x < 64; ++x) cliff.depth->at(x, y) += 10.0f;
  }
  const std::optional<double> with_cliff = ratio_of(cliff);
  ASSERT_TRUE(with_cliff);
  EXPECT_NEAR(*with_cliff, 1.0, 0.02);
  EXPECT_FALSE(ratio_of(cliff_fields()));
  RegionFields alone = hill_fields();
  alone.depth.reset();
  EXPECT_FALSE(ratio_of(alone));  // no depth map: nothing to compare
}

// A rough relief of three octaves (periods 24, 11 and 5 px, 4 x `scale` px high in all) stored as a height image
// with `depth_codes`, and the normal map a generator makes from that image by Sobel, stored as 8 bits (the failure-
// mode suite's `fbm`): the normals are the heights read across as well as along, and rounded.
RegionFields generated_rough_maps(double scale, std::uint32_t depth_codes) {
  DepthField exact(64, 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const double u = x + 0.5, v = y + 0.5, tau = 2.0 * std::numbers::pi;
      exact.at(x, y) = static_cast<float>(scale * (1.2 * std::sin(tau * (u + 0.4 * v) / 24.0) +
                                                   0.5 * std::sin(tau * (0.3 * u - v) / 11.0) +
                                                   0.3 * std::sin(tau * (u + v) / 5.0)));
    }
  }
  RegionFields fields;
  DecodeReport depth_report, normals_report;
  fields.depth = stored_depth(exact, depth_codes, &depth_report);
  fields.depth_rounding = height_rounding_of_depth(depth_report.value_step);
  fields.gradient = gradient_from_normals(stored_normals(sobel_normals(*fields.depth), 255, &normals_report));
  fields.gradient_rounding = gradient_rounding_of_normals(normals_report.value_step);
  return fields;
}

// What the comparison says of maps that disagree in sign or hold far different scales, where the ratio alone said
// nothing (too few slopes of one sign, or none the depth map resolves): the hill's heights upside down, its normals'
// y slopes flipped (the other green convention), its heights at a 64th (a relief_px far too small) and at 100 times
// (every texel a step: the ratio is read over the marked slopes). The hill itself and a generator's 8-bit normals of
// an 8-bit height image show none of it.
TEST(HybridMethod, ComparesTheSignsAndTheFlatnessOfTheSlopes) {
  const auto compared = [](RegionFields fields) {
    prepare_hybrid_fields(HybridParams{}, fields);
    EXPECT_TRUE(fields.slope_comparison);
    return fields.slope_comparison.value_or(SlopeComparison{});
  };
  const auto changed = [](auto change) {
    RegionFields fields = hill_fields();
    change(fields);
    return fields;
  };
  for (const RegionFields& agreeing : {hill_fields(), generated_rough_maps(4.0, 255)}) {
    const SlopeComparison c = compared(agreeing);
    ASSERT_TRUE(c.opposite_y && c.depth_flat);  // (the rough maps' x slopes are too few to tell: none)
    EXPECT_LT(c.opposite_x.value_or(0.0), 0.05);
    EXPECT_LT(*c.opposite_y, 0.05);
    EXPECT_LT(*c.depth_flat, 0.1);
  }
  const SlopeComparison upside_down = compared(changed([](RegionFields& f) {
    for (float& h : f.depth->values) h = -h;
  }));
  ASSERT_TRUE(upside_down.opposite_x && upside_down.opposite_y);
  EXPECT_GT(*upside_down.opposite_x, 0.95);
  EXPECT_GT(*upside_down.opposite_y, 0.95);
  const SlopeComparison green = compared(changed([](RegionFields& f) {
    for (Gradient& g : f.gradient->values) g.y = -g.y;
  }));
  ASSERT_TRUE(green.opposite_x && green.opposite_y);
  EXPECT_LT(*green.opposite_x, 0.05);
  EXPECT_GT(*green.opposite_y, 0.95);
  const SlopeComparison flat = compared(changed([](RegionFields& f) {
    for (float& h : f.depth->values) h /= 64.0f;
  }));
  ASSERT_TRUE(flat.depth_flat);
  EXPECT_GT(*flat.depth_flat, 0.9);
  const SlopeComparison steep = compared(changed([](RegionFields& f) {
    for (float& h : f.depth->values) h *= 100.0f;
  }));
  ASSERT_TRUE(steep.ratio);
  EXPECT_NEAR(*steep.ratio, 0.01, 0.001);
}

// The generator's normals of an 8-bit height image 16 px high: the heights are stored coarser than the normals
// (their rounding through the Sobel filter, 0.008 in slope, is over three times the normals' 0.0023), so the
// normals stay as given, and unfused. Before the hybrid asked whether the depth map explains its normals, it pulled
// them toward the central differences (their disagreement, the finest octave read two ways, is far above
// `noise_slope`).
TEST(HybridMethod, DoesNotFuseNormalsAGeneratorMadeFromItsDepthMap) {
  const RegionFields fields = generated_rough_maps(4.0, 255);
  ASSERT_GT(rms_difference(*fields.gradient, gradient_from_depth(*fields.depth)), HybridParams{}.noise_slope);
  expect_not_fused(fields);
}

// The same relief 4 px high as a 16-bit height image and the generator's 8-bit normal map of it: the heights are
// stored 200 times finer than the normals, so the hybrid takes the generator's reading again from them, without the
// normals' rounding, and smooths only within what is left of it.
TEST(HybridMethod, ReadsAGeneratorsNormalsAgainFromFinerHeights) {
  RegionFields fields = generated_rough_maps(1.0, 65535);
  const GradientField reading = gradient_from_normals(sobel_normals(*fields.depth));  // as a generator, unrounded
  auto largest_inner_difference = [&](const GradientField& g) {
    double largest = 0.0;
    for (int y = 1; y < 63; ++y) {
      for (int x = 1; x < 63; ++x) {
        largest = std::max({largest, std::abs(static_cast<double>(g.at(x, y).x) - reading.at(x, y).x),
                            std::abs(static_cast<double>(g.at(x, y).y) - reading.at(x, y).y)});
      }
    }
    return largest;
  };
  ASSERT_GT(largest_inner_difference(*fields.gradient), 2e-3);  // the normals' 8-bit rounding
  const double normals_rounding = fields.gradient_rounding;
  HybridParams unsmoothed_by_depth;
  unsmoothed_by_depth.far_noise_gain = 0.0;
  prepare_hybrid_fields(unsmoothed_by_depth, fields);
  EXPECT_LT(largest_inner_difference(*fields.gradient), 1e-5);  // measured 6e-8: float against double
  EXPECT_LT(fields.gradient_rounding, 0.01 * normals_rounding);
  EXPECT_GT(fields.gradient_rounding, 0.0);
}

// The step test in bands of rows on threads (a load's) marks what it marks in one band, to the bit: terraces crossing
// every row diagonally over a rolling relief, stored as an 8-bit height image, and the normals a generator makes of it,
// so that steps, smeared steps and smooth relief meet at every band's first and last rows.
TEST(HybridMethod, FindsTheSameStepsInBandsOfRowsAsInOne) {
  DepthField exact(173, 300);
  for (int y = 0; y < exact.height; ++y) {
    for (int x = 0; x < exact.width; ++x) {
      const double terrace = std::floor((x + 2.0 * y) / 23.0);
      exact.at(x, y) =
          static_cast<float>(1.5 * terrace + 3.0 * std::sin(2.0 * std::numbers::pi * (x - 0.7 * y) / 37.0));
    }
  }
  DecodeReport depth_report, normals_report;
  const DepthField depth = stored_depth(exact, 255, &depth_report);
  const GradientField g = gradient_from_normals(stored_normals(sobel_normals(depth), 255, &normals_report));
  const double step = depth_step_of_rounding(height_rounding_of_depth(depth_report.value_step));
  const DiscontinuityField one = find_discontinuities(g, depth, 0.5, step, 1);
  const DiscontinuityField banded = find_discontinuities(g, depth, 0.5, step, 4);
  ASSERT_EQ(row_band_count(exact.height, 4), 4u);  // bands from rows 75, 150 and 225
  ASSERT_EQ(one.values.size(), banded.values.size());
  for (std::size_t i = 0; i < one.values.size(); ++i) ASSERT_EQ(one.values[i], banded.values[i]) << i;
  std::size_t marked = 0;
  for (std::uint8_t mark : one.values) marked += mark;
  EXPECT_GT(marked, one.values.size() / 20);  // steps, and relief that is none
  EXPECT_LT(marked, one.values.size() / 2);
  for (const int first : {75, 150, 225}) {
    for (const int y : {first - 1, first}) {
      int in_row = 0;
      for (int x = 0; x < exact.width; ++x) in_row += one.at(x, y);
      EXPECT_GT(in_row, 0) << "row " << y;
    }
  }
}

// The smoothing in bands of rows on threads gives what one band gives, to the bit: each band smooths the row above its
// first along x itself.
TEST(HybridMethod, SmoothsInBandsOfRowsAsInOne) {
  GradientField g(131, 300);
  std::uint32_t state = 99;
  for (Gradient& s : g.values) {
    state = state * 1664525u + 1013904223u;
    s = {static_cast<float>(state >> 20) / 4096.0f - 0.5f, static_cast<float>((state >> 8) & 0xfff) / 4096.0f - 0.5f};
  }
  expect_bands_agree_with_one([&](unsigned threads) { return binomial_smoothed(g, threads); });
  EXPECT_NE(binomial_smoothed(g, 1).at(60, 150).x, g.at(60, 150).x);  // it did smooth
}

// A region given a depth map and no normal map: its gradient is the heights' central differences, which no
// generator's reading explains better (on a tilted plane every reading agrees exactly), and stays as it is, with the
// rounding of its own storage.
TEST(HybridMethod, KeepsTheGradientOfARegionGivenNoNormalMap) {
  DepthField plane(48, 32);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 48; ++x) plane.at(x, y) = static_cast<float>(0.3 * x + 0.1 * y);
  }
  RegionFields fields;
  DecodeReport report;
  fields.depth = stored_depth(plane, 255, &report);
  fields.depth_rounding = height_rounding_of_depth(report.value_step);
  fields.gradient = gradient_from_depth(*fields.depth);
  fields.gradient_rounding = gradient_rounding_of_depth(report.value_step);
  const double rounding = fields.gradient_rounding;
  prepare_hybrid_fields(HybridParams{}, fields);
  EXPECT_EQ(fields.gradient_rounding, rounding);
}

// A grating of amplitude 0.5 px and period `period` px, crossed along (cx, cy), as exact float maps of size x size:
// the normals at the texel centres and the heights.
RegionFields grating_fields(double period, double cx, double cy, int size) {
  RegionFields fields;
  fields.gradient = GradientField(size, size);
  fields.depth = DepthField(size, size);
  const double k = 2.0 * std::numbers::pi / period, a = 0.5;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) * cx + (y + 0.5) * cy;
      fields.depth->at(x, y) = static_cast<float>(a * std::sin(k * u));
      const double slope = a * k * std::cos(k * u);
      fields.gradient->at(x, y) = {static_cast<float>(cx * slope), static_cast<float>(cy * slope)};
    }
  }
  return fields;
}

// The hybrid's preparation of exact maps that it must not fuse: the normals stay as given.
void expect_exact_normals_kept(const RegionFields& fields) {
  ASSERT_GT(rms_difference(*fields.gradient, gradient_from_depth(*fields.depth)), HybridParams{}.noise_slope);
  const GradientField given = *fields.gradient;
  expect_not_fused(fields);
  RegionFields prepared = fields;
  prepare_hybrid_fields(HybridParams{}, prepared);
  EXPECT_EQ(rms_difference(*prepared.gradient, given), 0.0);
}

// A grating of period 8 px at 37 degrees: central differences of the heights read its slopes a tenth flatter than the
// normals; Simpson's mean of the normals over the same 2 px agrees with them, so nothing is fused and the float
// normals are used as given (before: fused).
TEST(HybridMethod, DoesNotFuseTheExactNormalsOfAFineGrating) {
  expect_exact_normals_kept(grating_fields(8.0, 0.8, 0.6, 64));
}

// A grating of period 3 px, across the rows and at 37 and 45 degrees (periods along the axes from 3 to 5 px): central
// differences read its slope at 0.41 and Simpson's mean of the normals at 0.5 of it along the rows, but the heights'
// band-limited derivative reads it as the normals do, so nothing is fused (before: fused, and the flattened normals
// made a stroke's motor travel 41.5 % off its exact input's where the normals alone made it 34.5 %;
// docs/STABILITY.md). Noise on the same normals is not explained by any reading, and is fused.
TEST(HybridMethod, DoesNotFuseTheExactNormalsOfAGratingOf3PxButTheirNoise) {
  for (const auto& [cx, cy] : {std::pair{1.0, 0.0}, std::pair{0.8, 0.6}, std::pair{std::sqrt(0.5), std::sqrt(0.5)}}) {
    SCOPED_TRACE(cx);
    const RegionFields exact = grating_fields(3.0, cx, cy, 96);
    expect_exact_normals_kept(exact);
    RegionFields noisy = with_gaussian_noise(exact, 0.05, 3);
    prepare_hybrid_fields(HybridParams{}, noisy);
    EXPECT_TRUE(noisy.fused_normals_weight);
  }
}

// A cone of slope 0.3 and radius 28 px on a 64 x 64 region (a map of the suite's `cone`), and the largest change
// the hybrid's preparation makes to its gradient.
double largest_change_to_a_cone(double gradient_rounding) {
  RegionFields fields;
  fields.gradient = GradientField(64, 64);
  fields.gradient_rounding = gradient_rounding;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const double dx = x + 0.5 - 32.0, dy = y + 0.5 - 32.0, r = std::hypot(dx, dy);
      if (r < 28.0) fields.gradient->at(x, y) = {static_cast<float>(-0.3 * dx / r), static_cast<float>(-0.3 * dy / r)};
    }
  }
  const GradientField exact = *fields.gradient;
  prepare_hybrid_fields(HybridParams{}, fields);
  double largest = 0.0;
  for (std::size_t i = 0; i < exact.values.size(); ++i) {
    largest = std::max({largest, std::abs(static_cast<double>(fields.gradient->values[i].x) - exact.values[i].x),
                        std::abs(static_cast<double>(fields.gradient->values[i].y) - exact.values[i].y)});
  }
  return largest;
}

// The band is the rounding the map's storage leaves, no more: a float map's residual from its smoothed self is its
// relief's own curvature, and its relief stays exactly as given (the apex and rim included); the same relief as an
// 8-bit map would give it is smoothed within the band, which noise_slope bounds.
TEST(HybridMethod, SmoothsOnlyWhatTheMapsStorageRounds) {
  EXPECT_EQ(largest_change_to_a_cone(0.0), 0.0);
  const double eight_bit = largest_change_to_a_cone(gradient_rounding_of_normals(2.0 / 255.0));
  EXPECT_GT(eight_bit, 0.0);
  EXPECT_LE(eight_bit, HybridParams{}.noise_slope + 1e-7);
  // A 16-bit map rounds 256 times finer: its band, and what it moves, is far below the 8-bit one's.
  EXPECT_LT(largest_change_to_a_cone(gradient_rounding_of_normals(2.0 / 65535.0)), 0.05 * eight_bit);
}

// `exact` as a normal map of `bits` per component stores it: each unit normal's x and y rounded to the map's codes.
GradientField stored_as_normals(const GradientField& exact, int bits) {
  const double codes = std::ldexp(1.0, bits) - 1.0;
  auto rounded = [codes](double v) { return -1.0 + std::round((v + 1.0) * codes / 2.0) * 2.0 / codes; };
  GradientField out = exact;
  for (Gradient& g : out.values) {
    const double length = std::sqrt(1.0 + g.x * g.x + g.y * g.y);
    const double nx = rounded(g.x / length), ny = rounded(g.y / length), nz = std::sqrt(1.0 - nx * nx - ny * ny);
    g = {static_cast<float>(nx / nz), static_cast<float>(ny / nz)};
  }
  return out;
}

// Smoothing flattens a relief as well as taking out its rounding; on a finely stored map (12 bits) the flattening is
// the larger, and the preparation takes it off again: a broad hill's 12-bit normals come out closer to its exact
// slopes than they were stored (RMS of both slopes over the region 2.04e-4), where the smoothing alone left them
// further (2.15e-4); with the flattening taken off, 1.15e-4.
TEST(HybridMethod, TakesTheSmoothingsFlatteningOffAFinelyStoredMap) {
  RegionFields fields;
  const int size = 128;
  fields.gradient = GradientField(size, size);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double dx = x + 0.5 - 64.0, dy = y + 0.5 - 64.0, s2 = 2.0 * 20.0 * 20.0;
      const double h = 10.0 * std::exp(-(dx * dx + dy * dy) / s2);
      fields.gradient->at(x, y) = {static_cast<float>(-2.0 * dx / s2 * h), static_cast<float>(-2.0 * dy / s2 * h)};
    }
  }
  const GradientField exact = *fields.gradient;
  *fields.gradient = stored_as_normals(exact, 12);
  fields.gradient_rounding = gradient_rounding_of_normals(2.0 / 4095.0);
  const double stored = rms_difference(*fields.gradient, exact);
  prepare_hybrid_fields(HybridParams{}, fields);
  const double prepared = rms_difference(*fields.gradient, exact);
  EXPECT_LT(prepared, 0.8 * stored);
  // What check-config reports: smoothed nearly everywhere, and the flattening taken off at most of those texels.
  EXPECT_GT(fields.smoothed_texels, fields.gradient->values.size() / 2);
  EXPECT_GT(fields.unflattened_texels, fields.smoothed_texels / 2);
  EXPECT_LE(fields.unflattened_texels, fields.smoothed_texels);
}

// A grating at the texel period, aliased to heights alternating by 1 px under flat normals, and a single texel
// sticking out: changes taken back within a texel are no discontinuity. A step whose normals a generator smeared
// over four texels (the Sobel filter across a diagonal step: slopes h/8, 3h/8, 3h/8, h/8) still is one, its
// outer texels marked too (their slopes claim h/8 where the heights are flat), and the flat texels beside them.
TEST(HybridMethod, MarksStepsButNotHeightsThatAlternateOrSpike) {
  RegionFields fields;
  fields.gradient = GradientField(48, 4, Gradient{});
  fields.depth = DepthField(48, 4, 0.0f);
  const float h = 8.0f;
  const float smeared[] = {h / 8, 3 * h / 8, 3 * h / 8, h / 8};
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 16; ++x) fields.depth->at(x, y) = x % 2 == 0 ? 0.0f : 1.0f;  // the alternation
    fields.depth->at(24, y) = 1.0f;                                                  // the spike
    for (int x = 36; x < 48; ++x) fields.depth->at(x, y) = h;                        // the step, between 35 and 36
    for (int i = 0; i < 4; ++i) fields.gradient->at(34 + i, y).x = smeared[i];
  }
  prepare_hybrid_fields(HybridParams{}, fields);
  for (int x = 0; x < 48; ++x) EXPECT_EQ(fields.discontinuity->at(x, 2), x >= 33 && x <= 38 ? 1 : 0) << x;
}

// A steep sinusoid of period 4 px with exact heights and normals at the texel centres, sampled where its slope
// peaks between them: across an edge the height changes by 4.24 px where both texels' slopes say 3.33, which
// the slopes one texel further out explain (the slope peaks between the centres). The same change as a step
// between two level treads is still one.
TEST(HybridMethod, ASmoothReliefNearTheTexelPeriodIsNoDiscontinuity) {
  const double amplitude = 3.0, k = std::numbers::pi / 2.0;  // period 4 px
  RegionFields fields;
  fields.gradient = GradientField(32, 4);
  fields.depth = DepthField(32, 4);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 32; ++x) {
      const double phase = k * (x + 0.5);
      fields.depth->at(x, y) = static_cast<float>(amplitude * std::sin(phase));
      fields.gradient->at(x, y) = {static_cast<float>(amplitude * k * std::cos(phase)), 0.0f};
    }
  }
  prepare_hybrid_fields(HybridParams{.discontinuity_px = 0.5, .noise_slope = 0.0, .far_noise_gain = 0.0}, fields);
  for (std::uint8_t mark : fields.discontinuity->values) EXPECT_EQ(mark, 0);

  RegionFields step;
  step.gradient = GradientField(32, 4, Gradient{});
  step.depth = DepthField(32, 4, 0.0f);
  for (int y = 0; y < 4; ++y) {
    for (int x = 16; x < 32; ++x) step.depth->at(x, y) = static_cast<float>(amplitude * std::sqrt(2.0));
  }
  prepare_hybrid_fields(HybridParams{.discontinuity_px = 0.5, .noise_slope = 0.0, .far_noise_gain = 0.0}, step);
  EXPECT_EQ(step.discontinuity->at(15, 2), 1);
  EXPECT_EQ(step.discontinuity->at(16, 2), 1);
}

// Gratings of amplitude 4 px at about the texel period met at an angle (period 2 px at 45 degrees, 3 px at 30), with
// exact heights and normals at the texel centres: along a row or column both maps alias to changes that neither
// explains and that do not simply alternate (without the test of resolved relief 42 % and 37 % of the texels were
// marked). The slopes beside such an edge change by far more than the heights do unexplained: relief the texels do
// not resolve, where no step is to be found. (The step between level treads of the test above is still marked, and
// so are those beside a generator's smeared normals, two tests up.)
TEST(HybridMethod, AGratingTheTexelsDoNotResolveIsNoDiscontinuity) {
  for (const auto& [period, degrees] : {std::pair{2.0, 45.0}, std::pair{3.0, 30.0}}) {
    const double amplitude = 4.0, k = 2.0 * std::numbers::pi / period, a = degrees * std::numbers::pi / 180.0;
    const double c = std::cos(a), s = std::sin(a);
    RegionFields fields;
    fields.gradient = GradientField(48, 48);
    fields.depth = DepthField(48, 48);
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 48; ++x) {
        const double phase = k * ((x + 0.5) * c + (y + 0.5) * s) + 0.3;
        fields.depth->at(x, y) = static_cast<float>(amplitude * std::sin(phase));
        const double slope = amplitude * k * std::cos(phase);
        fields.gradient->at(x, y) = {static_cast<float>(slope * c), static_cast<float>(slope * s)};
      }
    }
    prepare_hybrid_fields(HybridParams{.discontinuity_px = 0.5, .noise_slope = 0.0, .far_noise_gain = 0.0}, fields);
    int marked = 0;
    for (std::uint8_t mark : fields.discontinuity->values) marked += mark;
    EXPECT_EQ(marked, 0) << "period " << period << " px at " << degrees << " degrees";
  }
}

// A line raised 1 or 2 texels wide in a depth map whose normals are flat: its two edges' unexplained changes are
// opposite and within two texels of each other, a ridge too narrow to be a change of level (the finest octave of a
// rough relief aliases to such pairs, below). A line 3 texels wide is a plateau, and both its edges are steps.
TEST(HybridMethod, ALineOneOrTwoTexelsWideIsNoStepAndAWiderOneIs) {
  for (int width : {1, 2, 3}) {
    RegionFields fields;
    fields.gradient = GradientField(24, 4, Gradient{});
    fields.depth = DepthField(24, 4, 0.0f);
    for (int y = 0; y < 4; ++y) {
      for (int x = 10; x < 10 + width; ++x) fields.depth->at(x, y) = 2.0f;
    }
    prepare_hybrid_fields(HybridParams{.discontinuity_px = 0.5, .noise_slope = 0.0, .far_noise_gain = 0.0}, fields);
    int marked = 0;
    for (int x = 0; x < 24; ++x) marked += fields.discontinuity->at(x, 2);
    EXPECT_EQ(marked, width == 3 ? 4 : 0) << width << " px wide";  // 9, 10 and 12, 13
  }
}

// A rough relief whose finest octave has a period of 4 px (three waves of 0.5 px at 20, 75 and 140 degrees over two
// coarser octaves), its height image stored in 8 bits and its normals made from that by a generator (Sobel), as the
// failure-mode suite's `fbm` at amplitude 8 px: the Sobel filter reads the finest octave at 0.64 of its slope where
// the heights change by 0.9 of it across an edge, so the heights change by more than the normals explain, in pairs
// of opposite sign within two texels, where the slopes beside the edge change by more than twice as much. No step
// is there: with only an opposite change on the next edge taken as taking one back, and the slopes beside an edge
// allowed to change by four times the unexplained change, 1088 of the 8100 inner texels were marked (the region's
// border, where the generator's filter repeats the edge texels, is left out); now 80, with their bands (111 when the
// band was passed on to neighbours sloping against it).
TEST(HybridMethod, TheFinestOctaveOfAGeneratorsRoughMapsIsNoStep) {
  const int n = 96;
  DepthField exact(n, n);
  const double tau = 2.0 * std::numbers::pi;
  struct Wave {
    double period, amplitude, degrees, phase;
  };
  const Wave waves[] = {{32.0, 2.6, 60.0, 0.3}, {16.0, 1.5, 170.0, 1.1}, {8.0, 0.85, 100.0, 2.0},
                        {4.0, 0.5, 20.0, 0.7},  {4.0, 0.5, 75.0, 2.9},   {4.0, 0.5, 140.0, 4.4}};
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      double height = 10.0;
      for (const Wave& w : waves) {
        const double a = w.degrees * std::numbers::pi / 180.0;
        height +=
            w.amplitude * std::sin(tau * ((x + 0.5) * std::cos(a) + (y + 0.5) * std::sin(a)) / w.period + w.phase);
      }
      exact.at(x, y) = static_cast<float>(height);
    }
  }
  RegionFields fields;
  DecodeReport depth_report, normals_report;
  fields.depth = stored_depth(exact, 255, &depth_report);
  fields.depth_rounding = height_rounding_of_depth(depth_report.value_step);
  fields.gradient = gradient_from_normals(stored_normals(sobel_normals(*fields.depth), 255, &normals_report));
  fields.gradient_rounding = gradient_rounding_of_normals(normals_report.value_step);
  prepare_hybrid_fields(HybridParams{}, fields);
  int marked = 0, inner = 0;
  for (int y = 3; y < n - 3; ++y) {
    for (int x = 3; x < n - 3; ++x) {
      marked += fields.discontinuity->at(x, y);
      ++inner;
    }
  }
  EXPECT_LT(marked, inner / 80) << marked << " of " << inner << " inner texels marked";
}

// Regions of every size from 1 x 1 to 7 x 7 px holding a 2 px step under flat normals, across x and then across y:
// the step test reads the edges two either side of each one (along y from a ring of rows), and at every size
// exactly the two texels either side of the step are marked, down to regions one texel across.
TEST(HybridMethod, FindsAStepInRegionsOfEverySmallSize) {
  for (int w = 1; w <= 7; ++w) {
    for (int h = 1; h <= 7; ++h) {
      for (const bool across_x : {true, false}) {
        const int length = across_x ? w : h;
        if (length < 2) continue;
        RegionFields fields;
        fields.gradient = GradientField(w, h, Gradient{});
        fields.depth = DepthField(w, h, 0.0f);
        for (int y = 0; y < h; ++y) {
          for (int x = 0; x < w; ++x) fields.depth->at(x, y) = (across_x ? x : y) >= length / 2 ? 2.0f : 0.0f;
        }
        prepare_hybrid_fields(HybridParams{}, fields);
        for (int y = 0; y < h; ++y) {
          for (int x = 0; x < w; ++x) {
            const int along = across_x ? x : y;
            EXPECT_EQ(fields.discontinuity->at(x, y), along == length / 2 - 1 || along == length / 2 ? 1 : 0)
                << w << " x " << h << (across_x ? " across x" : " across y") << ", texel " << x << ", " << y;
          }
        }
      }
    }
  }
}

// A float depth map may hold values near the float's limit (3e38): every reading of its heights stays finite, and so
// does the prepared gradient (across this cliff of 6e38 the band-limited derivative's sum is 4e38, beyond a float).
TEST(HybridMethod, PreparesFiniteFieldsFromHeightsNearTheFloatLimit) {
  RegionFields fields;
  fields.gradient = GradientField(40, 40, Gradient{0.1f, -0.2f});
  fields.depth = DepthField(40, 40);
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) fields.depth->at(x, y) = x < 20 ? 3.0e38f : -3.0e38f;
  }
  fields.gradient->at(20, 20) = {2.0f, 0.0f};  // not the heights' reading: the normals are compared, and fused
  prepare_hybrid_fields(HybridParams{}, fields);
  for (const Gradient& g : fields.gradient->values) {
    ASSERT_TRUE(std::isfinite(g.x) && std::isfinite(g.y));
    ASSERT_LE(std::max(std::abs(g.x), std::abs(g.y)), kMaxSlope);
  }
}

TEST(HybridMethod, NeverGivesNanOrLeavesItsBounds) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RegionFields fields;
  fields.gradient = GradientField(40, 40);
  fields.depth = DepthField(40, 40);
  for (Gradient& g : fields.gradient->values) g = {static_cast<float>(50.0 * u(rng)), static_cast<float>(1e5 * u(rng))};
  for (float& h : fields.depth->values) h = static_cast<float>(1e4 * u(rng));
  const auto method = std::make_shared<HybridMethod>(HybridParams{});
  const Scene scene = one_region(std::move(fields), {10, 10, 40, 40}, method);
  CursorState cursor = cursor_at({30.0, 30.0});
  for (int i = 0; i < 20000; ++i) {
    const FrameResult r = advance(scene, cursor, {7.0 * u(rng), 7.0 * u(rng)});
    ASSERT_TRUE(std::isfinite(r.display.x) && std::isfinite(r.display.y));
    ASSERT_GE(r.cd_min, method->cd_lower_bound());
    ASSERT_LE(r.cd_max, method->cd_upper_bound());
    if (std::abs(cursor.position.x - 30.0) > 25.0 || std::abs(cursor.position.y - 30.0) > 25.0)
      cursor = cursor_at({30.0, 30.0});
  }
}

TEST(HybridMethod, SceneFileNamesItWithItsTableAndANormalMapAlone) {
  const std::string region = "[[region]]\nwidth = 4\nheight = 4\nnormal_map = \"n.png\"\nmethod = \"hybrid\"\n";
  const SceneSpec spec = parse_scene_text(region + "[region.hybrid]\ndiscontinuity_px = 2\nnoise_slope = 0\n", "h.toml",
                                          builtin_methods());
  ASSERT_EQ(spec.regions.size(), 1u);
  EXPECT_EQ(spec.regions[0].method, "hybrid");
  EXPECT_THROW(parse_scene_text(region + "[region.hybrid]\nnoise_slope = -1\n", "h.toml", builtin_methods()),
               ConfigError);
}

// A target's scene file as `pseudohaptic targets` writes it (normal and depth maps), its method made the hybrid;
// `drop` removes that line (e.g. the depth map) from the region.
SceneSpec hybrid_target_scene(const std::filesystem::path& dir, const TargetSpec& target, const std::string& drop,
                              const std::string& append = "") {
  const std::filesystem::path file = write_target_files(dir, {target}).front();
  std::ifstream in(file);
  std::ostringstream text;
  std::string line;
  while (std::getline(in, line)) {
    if (!drop.empty() && line.rfind(drop, 0) == 0) continue;
    if (line == "method = \"curvature\"") line = "method = \"hybrid\"";
    text << line << "\n";
  }
  text << append;  // after the region's table: a table of its own (the file has one region, last)
  return parse_scene_text(text.str(), file, builtin_methods());
}

TEST(HybridMethod, LoadsFromASceneFileWithBothMapsOrTheNormalMapAlone) {
  const TargetSpec target = all_targets()[6];  // bump-gaussian-h1-r100: its rim steps by about 1 px
  ScratchDir dir;
  const Scene both = load_scene(hybrid_target_scene(dir.path(), target, ""));
  const RegionFields& fields = both.regions()[0].fields;
  EXPECT_EQ(both.regions()[0].method->name(), "hybrid");
  ASSERT_TRUE(fields.gradient && fields.depth && fields.discontinuity);
  // The targets' 16-bit normal map: the rounding its codes leave reaches the method (its smoothing band).
  EXPECT_DOUBLE_EQ(fields.gradient_rounding, gradient_rounding_of_normals(2.0 / 65535.0));
  int marked = 0;
  for (std::uint8_t mark : fields.discontinuity->values) marked += mark;
  EXPECT_GT(marked, 0);
  const Scene normals_only = load_scene(hybrid_target_scene(dir.path(), target, "depth_map"));
  const RegionFields& alone = normals_only.regions()[0].fields;
  ASSERT_TRUE(alone.gradient && alone.discontinuity);
  EXPECT_FALSE(alone.depth);
  for (std::uint8_t mark : alone.discontinuity->values) EXPECT_EQ(mark, 0);
}

// With effects that read the normals only (isophote wells, materials from the normals), the hybrid still gets the
// region's depth map and finds the same steps: what the effects read joins what the method reads (before, the join
// dropped that the method reads the heights where given).
TEST(HybridMethod, KeepsItsDepthMapBesideEffectsThatReadTheNormals) {
  const TargetSpec target = all_targets()[6];
  ScratchDir dir;
  const Scene plain = load_scene(hybrid_target_scene(dir.path(), target, ""));
  for (const std::string effect :
       {"[region.wells]\npattern = \"isophotes\"\n", "[region.materials]\nsource = \"normals\"\n"}) {
    const Scene with_effect = load_scene(hybrid_target_scene(dir.path(), target, "", effect));
    const RegionFields& fields = with_effect.regions()[0].fields;
    EXPECT_EQ(with_effect.regions()[0].effects.size(), 1u) << effect;
    ASSERT_TRUE(fields.depth && fields.discontinuity) << effect;
    EXPECT_EQ(fields.discontinuity->values, plain.regions()[0].fields.discontinuity->values) << effect;
  }
}

}  // namespace
}  // namespace ph
