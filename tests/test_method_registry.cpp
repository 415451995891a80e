// A method added from outside the library, the way a new method is added: a class with kName, kParamKeys,
// Params, parse_params and sample_exact, and a registry entry. The scene file, a stroke (what trace runs), the
// direction tables and the ground truth then take it with no other change. The method reads normals and heights
// together (the whole width of TexelSample): its C/D is weight x the curvature method's + (1 - weight) x the
// depth method's, each with its default parameters, so that weight 1 and 0 must give those methods exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/ground_truth.hpp"
#include "core/lab/stroke.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

class BlendMethod final : public Method {
 public:
  struct Params {
    double weight = 0.5;  // of the curvature method's C/D; the rest is the depth method's
  };
  static constexpr std::string_view kName = "blend";
  static constexpr std::array<std::string_view, 1> kParamKeys = {"weight"};
  static Params parse_params(const ParamReader& reader) {
    Params p;
    if (const auto w = reader.number("weight")) p.weight = *w;
    if (!(p.weight >= 0.0 && p.weight <= 1.0)) reader.reject("weight", "must be between 0 and 1");
    return p;
  }

  explicit BlendMethod(const Params& p) : weight_(p.weight) {}

  std::string_view name() const override { return kName; }
  FieldNeeds needs() const override { return {.gradient = true, .depth = true}; }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 m) const override {
    return join(curvature_.sample(fields, local, m), depth_.sample(fields, local, m));
  }
  TexelSample sample_exact(const SurfacePoint& point, Vec2 m) const override {
    return join(curvature_.sample_exact(point, m), depth_.sample_exact(point, m));
  }
  double cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const override {
    const double c = curvature_.cd(from, to, step_px, detail);
    const double d = depth_.cd({from.v4, from.v5}, {to.v4, to.v5}, step_px, nullptr);
    return weight_ * c + (1.0 - weight_) * d;
  }
  double cd_lower_bound() const override {
    return weight_ * curvature_.cd_lower_bound() + (1.0 - weight_) * depth_.cd_lower_bound();
  }
  double cd_upper_bound() const override {
    return weight_ * curvature_.cd_upper_bound() + (1.0 - weight_) * depth_.cd_upper_bound();
  }

 private:
  static TexelSample join(const TexelSample& a, const TexelSample& b) { return {a.v0, a.v1, a.v2, a.v3, b.v0, b.v1}; }

  double weight_;
  CurvatureMethod curvature_{CurvatureParams{}};
  DepthMethod depth_{DepthParams{}};
};

MethodRegistry with_blend() {
  MethodRegistry methods = builtin_methods();
  methods.add(method_entry<BlendMethod>());
  return methods;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A target's scene file (both maps) with its method replaced by `method` and `extra` appended to the region.
SceneSpec target_scene(const fs::path& dir, const TargetSpec& target, const std::string& method,
                       const std::string& extra, const MethodRegistry& methods) {
  const fs::path file = write_target_files(dir, {target}).front();
  std::string text = read_text(file);
  const std::string written = "method = \"curvature\"";
  text.replace(text.find(written), written.size(), "method = \"" + method + "\"");
  return parse_scene_text(text + extra, file, methods);
}

std::string error_of(const std::string& text, const MethodRegistry& methods) {
  try {
    parse_scene_text(text, "blend.toml", methods);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MethodRegistry, AddsAMethodByItsEntryOnly) {
  MethodRegistry methods = with_blend();
  EXPECT_EQ(methods.names(), "curvature, depth, none, hybrid, blend");
  EXPECT_THROW(methods.add(method_entry<BlendMethod>()), std::invalid_argument);
  const MethodPtr blend = make_default_method(methods, "blend");
  EXPECT_EQ(blend->name(), "blend");
  EXPECT_EQ(blend->tag(), nullptr);  // not in core/engine/methods.hpp's list: reached through virtual calls
  EXPECT_THROW(make_default_method(methods, "nope"), std::invalid_argument);
}

TEST(MethodRegistry, SceneFileReadsTheNewMethodAndItsTable) {
  const MethodRegistry methods = with_blend();
  const std::string region = "[[region]]\nwidth = 4\nheight = 4\ndepth_map = \"d.png\"\nmethod = \"blend\"\n";
  const SceneSpec spec = parse_scene_text(region + "[region.blend]\nweight = 0.25\n", "blend.toml", methods);
  ASSERT_EQ(spec.regions.size(), 1u);
  EXPECT_EQ(spec.regions[0].method, "blend");
  EXPECT_EQ(method_params<BlendMethod>(spec.regions[0]).weight, 0.25);
  EXPECT_EQ(method_params<CurvatureMethod>(spec.regions[0]).kmax_prime, CurvatureParams{}.kmax_prime);
  const MethodPtr made = make_method(spec.regions[0], methods);
  EXPECT_EQ(made->name(), "blend");
  EXPECT_DOUBLE_EQ(made->cd_upper_bound(), 0.25 * 30.0 + 0.75 * 4.0);

  // Its keys and values are checked where they are written; the built-in registry does not know it.
  const std::string unknown = error_of(region + "[region.blend]\nweigth = 1\n", methods);
  EXPECT_NE(unknown.find("blend.toml:7: region[0].blend.weigth: unknown key: did you mean 'weight'? (allowed: weight)"),
            std::string::npos)
      << unknown;
  const std::string range = error_of(region + "[region.blend]\nweight = 2\n", methods);
  EXPECT_NE(range.find("blend.toml:7: region[0].blend.weight: must be between 0 and 1"), std::string::npos) << range;
  const std::string nodepth =
      error_of("[[region]]\nwidth = 4\nheight = 4\nnormal_map = \"n.png\"\nmethod = \"blend\"\n", methods);
  EXPECT_NE(nodepth.find("the blend method needs a depth_map"), std::string::npos) << nodepth;
  const std::string builtin = error_of(region, builtin_methods());
  EXPECT_NE(builtin.find("unknown method 'blend' (allowed: curvature, depth, none, hybrid)"), std::string::npos)
      << builtin;
}

// A stroke across the centre row, as trace runs it: the C/D of every texel step, in order (the frames' first
// segments, which re-enter no texel, left out: where frames end depends on the C/D).
std::vector<double> stroke_cds(const Scene& scene, std::int32_t size) {
  StrokeSpec stroke;
  stroke.from = {0.0, size / 2.0 + 0.5};
  stroke.to = {static_cast<double>(size), size / 2.0 + 0.5};
  stroke.motor_step_px = 3.0;
  std::vector<double> cds;
  run_stroke(scene, stroke, [&](std::size_t, const StepRecord& step) {
    if (step.entered) cds.push_back(step.cd);
  });
  return cds;
}

TEST(MethodRegistry, LoadedSceneWalksAsTheMethodsItBlends) {
  const MethodRegistry methods = with_blend();
  const TargetSpec target = all_targets()[6];  // bump-gaussian-h1-r100
  ScratchDir dir;
  const Scene curvature = load_scene(target_scene(dir.path(), target, "curvature", "", methods));
  const Scene depth = load_scene(target_scene(dir.path(), target, "depth", "", methods));
  const Scene all_curvature =
      load_scene(target_scene(dir.path(), target, "blend", "[region.blend]\nweight = 1\n", methods));
  const Scene all_depth =
      load_scene(target_scene(dir.path(), target, "blend", "[region.blend]\nweight = 0\n", methods));
  const Scene half = load_scene(target_scene(dir.path(), target, "blend", "", methods));
  // It reads both maps.
  EXPECT_TRUE(half.regions()[0].fields.gradient);
  EXPECT_TRUE(half.regions()[0].fields.depth);

  const std::vector<double> c = stroke_cds(curvature, target.size), d = stroke_cds(depth, target.size);
  EXPECT_EQ(stroke_cds(all_curvature, target.size), c);
  EXPECT_EQ(stroke_cds(all_depth, target.size), d);
  const std::vector<double> h = stroke_cds(half, target.size);
  ASSERT_EQ(h.size(), c.size());  // the walk visits the same texels; only the C/D differs
  bool between = true, differs = false;
  for (std::size_t i = 0; i < h.size(); ++i) {
    between = between && h[i] >= std::min(c[i], d[i]) - 1e-12 && h[i] <= std::max(c[i], d[i]) + 1e-12;
    differs = differs || h[i] != c[i];
  }
  EXPECT_TRUE(between);
  EXPECT_TRUE(differs);

  // The direction tables are built for it too.
  Scene table = load_scene(target_scene(dir.path(), target, "blend", "", methods));
  table.set_options({Traversal::direction_lut, Sampling::nearest, 16});
  EXPECT_NE(table.direction_lut(0), nullptr);
}

TEST(MethodRegistry, GroundTruthTakesTheNewMethod) {
  const TargetSpec target = all_targets()[6];
  const auto surface = make_target_surface(target);
  const CurvatureMethod curvature{CurvatureParams{}};
  const DepthMethod depth{DepthParams{}};
  const BlendMethod all_curvature{{1.0}}, all_depth{{0.0}}, half{{0.5}};
  const Vec2 m{std::cos(0.4), std::sin(0.4)};
  for (const Vec2 p : {Vec2{180.5, 240.25}, Vec2{250.0, 250.0}, Vec2{20.0, 30.0}}) {
    const double c = truth_cd({surface.get(), &curvature}, p, m), d = truth_cd({surface.get(), &depth}, p, m);
    EXPECT_EQ(truth_cd({surface.get(), &all_curvature}, p, m), c);
    EXPECT_EQ(truth_cd({surface.get(), &all_depth}, p, m), d);
    EXPECT_EQ(truth_cd({surface.get(), &half}, p, m), 0.5 * c + 0.5 * d);
  }
  // And its walk stays as close to its truth as the built-in methods' do (test_ground_truth.cpp).
  Region region;
  region.name = target.name();
  region.rect = {0, 0, target.size, target.size};
  region.fields.gradient = target_gradient_field(target);
  region.fields.depth = target_depth_field(target);
  region.method = std::make_shared<const BlendMethod>(BlendMethod::Params{0.5});
  std::vector<Region> regions;
  regions.push_back(std::move(region));
  const Scene scene(std::move(regions));
  const Vec2 start{20.0, target.size / 2.0 + 0.5};
  CursorState cursor = cursor_at(start);
  Vec2 truth = start;
  for (int frame = 0; frame < 460; ++frame) {
    advance(scene, cursor, {1.0, 0.0});
    truth = truth_advance({surface.get(), &half}, truth, {1.0, 0.0});
  }
  EXPECT_GT(std::abs(truth.x - start.x - 460.0), 1.0);  // the relief changed the travel
  EXPECT_LT(length(cursor.position - truth), 2.0);
}

}  // namespace
}  // namespace ph
