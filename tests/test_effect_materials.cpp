// Curvature classes as materials (core/effect_materials.hpp): scripted, timed frame streams through
// advance() and the pipeline on regions whose class is known, and a no-trap property test over random scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "core/effect_materials.hpp"
#include "core/effect_wells.hpp"
#include "core/method_flat.hpp"
#include "core/pipeline.hpp"
#include "core/scene.hpp"
#include "core/surfaces.hpp"
#include "core/traversal.hpp"

namespace ph {
namespace {

constexpr TimeUs kFrameUs = 8000;  // a 125 Hz mouse

Region effect_region(Rect rect, EffectPtr effect) {
  Region region;
  region.name = "materials";
  region.rect = rect;
  region.method = std::make_shared<FlatMethod>();
  if (effect) region.effects.push_back(std::move(effect));
  return region;
}

std::shared_ptr<const MaterialsEffect> uniform_effect(std::int32_t size, CurvatureClass cls,
                                                      const MaterialsParams& params = {}) {
  return std::make_shared<MaterialsEffect>(Grid<std::uint8_t>(size, size, static_cast<std::uint8_t>(cls)), params);
}

// A region holding an analytic surface's exact normals, its classes computed as the loader would.
struct SurfaceRegion {
  Scene scene;
  std::shared_ptr<const MaterialsEffect> effect;
};

SurfaceRegion surface_region(SurfaceKind kind, const MaterialsParams& params = {}, Rect rect = {100, 100, 128, 128}) {
  RegionFields fields;
  fields.gradient = surface_gradient_field({kind, rect.w});
  auto effect =
      std::static_pointer_cast<const MaterialsEffect>(make_materials_effect(fields, rect.w, rect.h, params, 16));
  return {Scene({effect_region(rect, effect)}), effect};
}

double share_of(const Grid<std::uint8_t>& classes, CurvatureClass cls) {
  const auto n = std::count(classes.values.begin(), classes.values.end(), static_cast<std::uint8_t>(cls));
  return static_cast<double>(n) / static_cast<double>(classes.values.size());
}

// Display length of one frame of `px` along +x at time t.
double step(const Scene& scene, CursorState& cursor, double px, TimeUs t) {
  return advance(scene, cursor, {px, 0.0}, t).display.x;
}

TEST(MaterialsParams, DefaultsAreValidAndEveryBoundIsChecked) {
  EXPECT_EQ(validate(MaterialsParams{}), "");
  auto message = [](auto change) {
    MaterialsParams p;
    change(p);
    return validate(p);
  };
  EXPECT_NE(message([](MaterialsParams& p) { p.friction.stuck_cd = 21.0; }).find("friction.stuck_cd"),
            std::string::npos);
  EXPECT_NE(message([](MaterialsParams& p) { p.stick_slip.slip_px = 0.0; }).find("stick_slip.slip_px"),
            std::string::npos);
  EXPECT_NE(message([](MaterialsParams& p) { p.damping.k = std::nan(""); }).find("damping.k"), std::string::npos);
  EXPECT_NE(message([](MaterialsParams& p) { p.damping.cd_max = 0.5; }).find("[1, 20]"), std::string::npos);
  EXPECT_NE(message([](MaterialsParams& p) { p.filter_radius = 65; }).find("filter_radius"), std::string::npos);
  EXPECT_NE(message([](MaterialsParams& p) { p.parabolic_ratio = 2.0; }).find("parabolic_ratio"), std::string::npos);
  EXPECT_NE(message([](MaterialsParams& p) { p.friction.rest_ms = 0.0; }).find("friction.rest_ms"), std::string::npos);
  EXPECT_EQ(message([](MaterialsParams& p) { p.filter_radius = 16; }), "");
  EXPECT_THROW(uniform_effect(4, CurvatureClass::planar,
                              [] {
                                MaterialsParams p;
                                p.damping.fallback_interval_ms = -1.0;
                                return p;
                              }()),
               std::invalid_argument);
}

TEST(MaterialsParams, NamesRoundTrip) {
  for (Material m : {Material::none, Material::damping, Material::friction, Material::stick_slip}) {
    EXPECT_EQ(parse_material(material_name(m)), m);
  }
  for (ClassSource s : {ClassSource::automatic, ClassSource::normals, ClassSource::depth}) {
    EXPECT_EQ(parse_class_source(class_source_name(s)), s);
  }
  EXPECT_FALSE(parse_material("velvet"));
}

TEST(MaterialsNeeds, NormalsWhenPresentElseDepthUnlessForced) {
  MaterialsParams p;
  EXPECT_TRUE(materials_needs(p, true, true).gradient);
  EXPECT_FALSE(materials_needs(p, true, true).depth);
  EXPECT_TRUE(materials_needs(p, false, true).depth);
  EXPECT_FALSE(materials_needs(p, false, true).gradient);
  p.source = ClassSource::depth;
  EXPECT_TRUE(materials_needs(p, true, true).depth);
  EXPECT_FALSE(materials_needs(p, true, true).gradient);
  p.source = ClassSource::normals;
  EXPECT_TRUE(materials_needs(p, false, true).gradient);
}

TEST(MaterialsClassMap, TheTestSurfacesGetTheirClassFromNormalsAndFromDepth) {
  for (SurfaceKind kind :
       {SurfaceKind::plane, SurfaceKind::cylinder, SurfaceKind::sphere, SurfaceKind::simple_saddle}) {
    const SurfaceSpec spec{kind, 128};
    RegionFields fields;
    fields.gradient = surface_gradient_field(spec);
    fields.depth = surface_depth_field(spec);
    MaterialsParams p;
    const auto from_normals = make_materials_effect(fields, 128, 128, p, 16);
    p.source = ClassSource::depth;
    const auto from_depth = make_materials_effect(fields, 128, 128, p, 16);
    for (const auto& effect : {from_normals, from_depth}) {
      const auto& m = static_cast<const MaterialsEffect&>(*effect);
      EXPECT_GE(share_of(m.classes(), surface_class(kind)), 0.99) << spec.name();
      EXPECT_EQ(m.bytes(), std::size_t{128} * 128) << "one byte per texel";
    }
  }
}

TEST(MaterialsClassMap, AMissingOrMisfitFieldThrows) {
  RegionFields fields;
  EXPECT_THROW(make_materials_effect(fields, 8, 8, {}, 16), std::invalid_argument);
  fields.gradient = GradientField(8, 8);
  EXPECT_THROW(make_materials_effect(fields, 8, 9, {}, 16), std::invalid_argument);
  MaterialsParams p;
  p.source = ClassSource::depth;
  EXPECT_THROW(make_materials_effect(fields, 8, 8, p, 16), std::invalid_argument);
  EXPECT_NO_THROW(make_materials_effect(fields, 8, 8, {}, 8));
}

TEST(MaterialsFriction, SticksCreepsBreaksAwaySlipsAndReSticksAfterARest) {
  const SurfaceRegion r = surface_region(SurfaceKind::sphere);  // elliptic: friction
  const FrictionParams f;
  ASSERT_EQ(f.breakaway_px, 10.0);
  CursorState cursor = cursor_at({130.5, 164.5});
  TimeUs t = 1'000'000;
  // Stuck: 1 px frames creep at 1 / stuck_cd, for breakaway_px of motor travel.
  for (int i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(step(r.scene, cursor, 1.0, t += kFrameUs), 1.0 / f.stuck_cd) << i;
  EXPECT_TRUE(cursor.effects[0].stuck);
  // The frame that crosses the breakaway distance: 1 px stuck, then 2 px slipping at slip_cd.
  EXPECT_DOUBLE_EQ(step(r.scene, cursor, 3.0, t += kFrameUs), 1.0 / f.stuck_cd + 2.0 / f.slip_cd);
  EXPECT_FALSE(cursor.effects[0].stuck);
  // Continuous motion keeps it slipping, with the exact motor displacement (slip_cd 1).
  const auto just_under_rest = static_cast<TimeUs>(f.rest_ms * 1000) - 1;
  for (int i = 0; i < 200; ++i) {
    const double x = i % 2 == 0 ? 0.25 : -0.25;  // back and forth: stays on the sphere
    EXPECT_EQ(step(r.scene, cursor, x, t += just_under_rest), x) << i;
  }
  // A rest of rest_ms (event times): stuck again.
  t += static_cast<TimeUs>(f.rest_ms * 1000);
  EXPECT_DOUBLE_EQ(step(r.scene, cursor, 1.0, t), 1.0 / f.stuck_cd);
  EXPECT_TRUE(cursor.effects[0].stuck);
}

// Wells layered on friction, in the scene file's order (materials, then wells). Each effect keeps its own
// state, so friction runs the script of SticksCreepsBreaksAwaySlipsAndReSticksAfterARest exactly as alone,
// and the wells pull what friction hands on exactly as they would alone.
TEST(MaterialsWithWells, FrictionSticksBreaksAwayAndReSticksAsAloneAndTheWellsPullAsAlone) {
  constexpr std::int32_t kSide = 200;
  RegionFields fields;
  fields.depth = DepthField(kSide, kSide);
  for (std::int32_t y = 0; y < kSide; ++y) {
    for (std::int32_t x = 0; x < kSide; ++x) fields.depth->at(x, y) = static_cast<float>(x) + 0.5f;  // h = x
  }
  WellsParams w;
  w.pattern = WellPattern::contours;
  w.contours.levels = {100.0};  // the line x = 100: within the radius, +x is toward it
  w.radius_px = 100.0;
  const EffectPtr wells = make_wells_effect(fields, kSide, kSide, w);
  Region region = effect_region({0, 0, kSide, kSide}, uniform_effect(kSide, CurvatureClass::elliptic));
  region.effects.push_back(wells);
  const Scene scene({region});
  const FrictionParams f;
  CursorState cursor = cursor_at({20.5, 100.5});
  int pulled = 0;
  // One frame of `px` along x where friction alone displays `friction_px`: the display is the wells' pull of that.
  auto frame = [&](double px, TimeUs t, double friction_px) {
    const Vec2 from_friction{std::copysign(friction_px, px), 0.0};
    EffectState stateless;
    const Vec2 want = wells->apply({from_friction, t, cursor.position, cursor.texel}, stateless);
    pulled += !(want == from_friction);
    const Vec2 got = advance(scene, cursor, {px, 0.0}, t).display;
    EXPECT_NEAR(got.x, want.x, 1e-12 * std::abs(want.x)) << px << " at " << t;
    EXPECT_NEAR(got.y, want.y, 1e-12 * std::abs(want.x)) << px << " at " << t;
  };
  TimeUs t = 1'000'000;
  for (int i = 0; i < 9; ++i) frame(1.0, t += kFrameUs, 1.0 / f.stuck_cd);
  EXPECT_TRUE(cursor.effects[0].stuck);
  frame(3.0, t += kFrameUs, 1.0 / f.stuck_cd + 2.0 / f.slip_cd);
  EXPECT_FALSE(cursor.effects[0].stuck) << "broke away";
  const auto just_under_rest = static_cast<TimeUs>(f.rest_ms * 1000) - 1;
  for (int i = 0; i < 200; ++i) frame(i % 2 == 0 ? 0.25 : -0.25, t += just_under_rest, 0.25 / f.slip_cd);
  EXPECT_FALSE(cursor.effects[0].stuck);
  t += static_cast<TimeUs>(f.rest_ms * 1000);
  frame(1.0, t, 1.0 / f.stuck_cd);
  EXPECT_TRUE(cursor.effects[0].stuck) << "stuck again after a rest";
  EXPECT_EQ(cursor.effects[0].owner, scene.regions()[0].effects[0].get());
  EXPECT_EQ(cursor.effects[1].owner, wells.get());
  EXPECT_EQ(pulled, 211) << "the wells pulled every frame; the cursor ended at x = " << cursor.position.x;
}

TEST(MaterialsFriction, BreakawayDoesNotDependOnTheFrameSize) {
  FrictionParams f;
  for (double frame : {0.1, 0.7, 2.5, 10.0, 40.0}) {
    const auto effect = uniform_effect(400, CurvatureClass::elliptic);
    const Scene scene({effect_region({0, 0, 400, 400}, effect)});
    CursorState cursor = cursor_at({10.5, 200.5});
    double motor = 0.0, display = 0.0;
    TimeUs t = 0;
    while (motor < 60.0 - 1e-9) {
      display += step(scene, cursor, frame, t += kFrameUs);
      motor += frame;
    }
    EXPECT_NEAR(display, f.breakaway_px / f.stuck_cd + (motor - f.breakaway_px) / f.slip_cd, 1e-9) << frame;
  }
}

TEST(MaterialsStickSlip, AlternatesStickAndSlipWithTheDocumentedPeriod) {
  const SurfaceRegion r = surface_region(SurfaceKind::simple_saddle);  // hyperbolic: stick-slip
  const StickSlipParams s;
  const double frame = 0.5;
  const int stuck_frames = static_cast<int>(s.breakaway_px / frame);  // 6
  const int slip_frames = static_cast<int>(s.slip_px / frame);        // 12
  CursorState cursor = cursor_at({150.5, 164.5});
  TimeUs t = 0;
  for (int period = 0; period < 4; ++period) {
    for (int i = 0; i < stuck_frames; ++i) {
      EXPECT_DOUBLE_EQ(step(r.scene, cursor, frame, t += kFrameUs), frame / s.stuck_cd) << period << " stick " << i;
    }
    for (int i = 0; i < slip_frames; ++i) {
      EXPECT_DOUBLE_EQ(step(r.scene, cursor, frame, t += kFrameUs), frame / s.slip_cd) << period << " slip " << i;
    }
  }
  // One long frame of whole periods moves as far as the frames above did.
  cursor = cursor_at({130.5, 164.5});
  const double period = s.breakaway_px + s.slip_px;
  EXPECT_DOUBLE_EQ(step(r.scene, cursor, 3 * period, t += 10 * kFrameUs),
                   3 * (s.breakaway_px / s.stuck_cd + s.slip_px / s.slip_cd));
}

TEST(MaterialsDamping, CdGrowsWithHandSpeedAndIsCapped) {
  const SurfaceRegion r = surface_region(SurfaceKind::cylinder);  // parabolic: damping
  const DampingParams d;
  CursorState cursor = cursor_at({150.5, 164.5});
  TimeUs t = 0;
  step(r.scene, cursor, 0.5, t);  // the first frame has no previous one: the fallback interval
  double last_cd = 1.0;
  for (double px : {0.5, 1.0, 2.0, 4.0, 6.0}) {
    const double x = cursor.position.x > 164.0 ? -px : px;
    const FrameResult result = advance(r.scene, cursor, {x, 0.0}, t += kFrameUs);
    const double speed = px / (kFrameUs * 1e-6);
    EXPECT_NEAR(result.cd_max, std::min(1.0 + d.k * speed, d.cd_max), 1e-12) << px;
    EXPECT_GT(result.cd_max, last_cd);
    last_cd = result.cd_max;
  }
  for (double px : {8.0, 20.0, 40.0}) {
    const double x = cursor.position.x > 164.0 ? -px : px;
    EXPECT_NEAR(advance(r.scene, cursor, {x, 0.0}, t += kFrameUs).cd_max, d.cd_max, 1e-12) << "capped";
  }
  // Slower hands, longer intervals: less damping.
  const double slow = advance(r.scene, cursor, {-2.0, 0.0}, t += 4 * kFrameUs).cd_max;
  EXPECT_NEAR(slow, 1.0 + d.k * 2.0 / (4 * kFrameUs * 1e-6), 1e-12);
}

TEST(MaterialsDamping, UnknownSpeedUsesTheFallbackIntervalAndNeverGoesNegative) {
  MaterialsParams p;
  const auto effect = uniform_effect(200, CurvatureClass::parabolic, p);
  const Scene scene({effect_region({0, 0, 200, 200}, effect)});
  CursorState cursor = cursor_at({100.5, 100.5});
  // No time (a trace): the fallback interval.
  EXPECT_NEAR(advance(scene, cursor, {2.0, 0.0}).cd_max, 1.0 + p.damping.k * 2.0 / 0.008, 1e-12);
  // Time going back (a replay jump) and a repeated time: the fallback too, never a negative or NaN speed.
  advance(scene, cursor, {1.0, 0.0}, TimeUs{5'000'000});
  EXPECT_NEAR(advance(scene, cursor, {-2.0, 0.0}, TimeUs{1'000}).cd_max, 1.0 + p.damping.k * 2.0 / 0.008, 1e-12);
  EXPECT_NEAR(advance(scene, cursor, {2.0, 0.0}, TimeUs{1'000}).cd_max, 1.0 + p.damping.k * 2.0 / 0.008, 1e-12);
  // Without a fallback: no damping when the speed is unknown.
  p.damping.fallback_interval_ms = 0.0;
  const Scene plain({effect_region({0, 0, 200, 200}, uniform_effect(200, CurvatureClass::parabolic, p))});
  cursor = cursor_at({100.5, 100.5});
  EXPECT_EQ(advance(plain, cursor, {2.0, 0.5}).display, (Vec2{2.0, 0.5}));
}

TEST(MaterialsPlanar, IsBitExactlyTheIdentity) {
  const SurfaceRegion r = surface_region(SurfaceKind::plane);
  ASSERT_EQ(share_of(r.effect->classes(), CurvatureClass::planar), 1.0);
  const Scene bare({effect_region({100, 100, 128, 128}, nullptr)});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-3.0, 3.0);
  CursorState a = cursor_at({164.3, 164.7}), b = a;
  TimeUs t = 0;
  for (int i = 0; i < 500; ++i) {
    Vec2 m{d(rng), d(rng)};
    if (!r.scene.regions()[0].rect.contains(texel_at(a.position + m * 4.0))) m = m * -1.0;
    const FrameResult with = advance(r.scene, a, m, t += kFrameUs);
    const FrameResult without = advance(bare, b, m, t);
    ASSERT_EQ(with.display, m) << i;
    ASSERT_EQ(a.position, b.position) << i;
    ASSERT_EQ(with.cd_max, without.cd_max);
  }
}

// A region of every class in blocks, so frames cross between materials.
Grid<std::uint8_t> random_classes(std::mt19937& rng, std::int32_t w, std::int32_t h) {
  const std::int32_t block = std::uniform_int_distribution<std::int32_t>(1, 16)(rng);
  std::uniform_int_distribution<int> cls(0, 3);
  Grid<std::uint8_t> g(w, h);
  std::vector<std::uint8_t> blocks(static_cast<std::size_t>((w / block + 1) * (h / block + 1)));
  for (auto& b : blocks) b = static_cast<std::uint8_t>(cls(rng));
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x)
      g.at(x, y) = blocks[static_cast<std::size_t>((y / block) * (w / block + 1) + x / block)];
  }
  return g;
}

TEST(Materials, TheSameStreamTwiceGivesBitIdenticalPositions) {
  std::mt19937 rng(11);
  const auto effect = std::make_shared<MaterialsEffect>(random_classes(rng, 300, 300), MaterialsParams{});
  const Scene scene({effect_region({0, 0, 300, 300}, effect)});
  std::uniform_real_distribution<double> d(-4.0, 4.0);
  std::uniform_int_distribution<TimeUs> dt(1000, 150'000);
  std::vector<std::pair<Vec2, TimeUs>> stream;
  TimeUs t = 0;
  for (int i = 0; i < 3000; ++i) stream.push_back({{d(rng), d(rng)}, t += dt(rng)});
  auto run = [&] {
    std::vector<Vec2> out;
    CursorState cursor = cursor_at({150.5, 150.5});
    for (const auto& [m, time] : stream) {
      advance(scene, cursor, m, time);
      out.push_back(cursor.position);
    }
    return out;
  };
  const std::vector<Vec2> first = run();
  EXPECT_EQ(first, run());
}

MaterialsParams random_params(std::mt19937& rng) {
  auto u = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  MaterialsParams p;
  for (Material& m : p.materials) m = static_cast<Material>(std::uniform_int_distribution<int>(0, 3)(rng));
  p.damping = {u(0.0, 1.0), u(1.0, 20.0), u(0.0, 100.0)};
  p.friction = {u(1.0, 20.0), u(0.1, 500.0), u(1.0, 20.0), u(1.0, 10000.0)};
  p.stick_slip = {u(1.0, 20.0), u(0.1, 500.0), u(1.0, 20.0), u(0.1, 500.0), u(1.0, 10000.0)};
  return p;
}

// No trap: a sustained push in any direction leaves the region within diagonal x the largest C/D of motor
// travel (plus the frame that crosses the edge), whatever the materials, frame sizes and times.
TEST(Materials, ASustainedPushAlwaysLeavesTheRegionInBoundedTravel) {
  std::mt19937 rng(2024);
  auto u = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  long frames = 0, slowed = 0;
  double worst = 0.0;  // motor travel to leave, relative to the bound
  for (int scene_index = 0; scene_index < 2000; ++scene_index) {
    const MaterialsParams params = random_params(rng);
    ASSERT_EQ(validate(params), "");
    const Rect rect{static_cast<std::int32_t>(u(0, 500)), static_cast<std::int32_t>(u(0, 500)),
                    static_cast<std::int32_t>(u(4, 160)), static_cast<std::int32_t>(u(4, 160))};
    const auto effect = std::make_shared<MaterialsEffect>(random_classes(rng, rect.w, rect.h), params);
    const Scene scene({effect_region(rect, effect)});
    const double cd_low = 1.0 / effect->max_gain(), cd_high = 1.0 / effect->min_gain();
    ASSERT_GE(cd_low, 1.0);
    ASSERT_LE(cd_high, 20.0);
    const double angle = u(0.0, 2.0 * std::numbers::pi);
    const Vec2 dir{std::cos(angle), std::sin(angle)};
    CursorState cursor = cursor_at({rect.x + u(0.0, rect.w), rect.y + u(0.0, rect.h)});
    const int timing = scene_index % 4;  // 0, 1: increasing times; 2: no time; 3: times that jump back too
    TimeUs t = 1'000'000'000;
    const double diagonal = std::hypot(rect.w, rect.h);
    const double bound = (diagonal + 2.0) * cd_high + 50.0;
    double motor = 0.0;
    while (rect.contains(cursor.texel)) {
      ASSERT_LE(motor, bound) << "trapped in scene " << scene_index;
      const double size = std::exp(u(std::log(0.1), std::log(50.0)));
      const Vec2 m = dir * size;
      t += static_cast<TimeUs>(u(1000.0, 50000.0));
      if (timing == 3 && u(0, 1) < 0.1) t -= static_cast<TimeUs>(u(0.0, 1e6));
      const TimeUs time = timing == 2 ? kNoTime : t;
      // The effect keeps its promise itself (advance() would quietly ignore it otherwise).
      EffectState probe = cursor.effects[0];
      if (probe.owner != effect.get()) probe = EffectState{true, 0.0, kNoTime, effect.get()};
      const Vec2 out = effect->apply({m, time, cursor.position, scene.regions()[0].local(cursor.texel)}, probe);
      ASSERT_TRUE(is_finite(out));
      const double gain = length(out) / length(m);
      ASSERT_GE(gain, effect->min_gain() * (1 - 1e-12)) << scene_index;
      ASSERT_LE(gain, effect->max_gain() * (1 + 1e-12)) << scene_index;

      const FrameResult result = advance(scene, cursor, m, time);
      motor += size;
      ASSERT_TRUE(is_finite(cursor.position));
      ASSERT_TRUE(std::isfinite(cursor.effects[0].travel_px) && cursor.effects[0].travel_px >= 0.0);
      ASSERT_NEAR(length(result.display), size * gain, 1e-9 * size) << "the effect acted as probed";
      ASSERT_GE(result.cd_min, cd_low * (1 - 1e-9)) << scene_index;
      ASSERT_LE(result.cd_max, cd_high * (1 + 1e-9)) << scene_index;
      ++frames;
      slowed += result.cd_max > 1.0;
    }
    worst = std::max(worst, motor / bound);
  }
  // The materials did act: most frames were slowed, and some pushes needed a good part of the bound.
  EXPECT_GT(static_cast<double>(slowed) / static_cast<double>(frames), 0.5);
  EXPECT_GT(worst, 0.1);
  std::printf("no-trap: %ld frames, %.2f slowed, worst travel %.3f of the bound\n", frames,
              static_cast<double>(slowed) / static_cast<double>(frames), worst);
}

TEST(Materials, ThePipelineUsesTheEventTimesOfRealFrames) {
  auto effect = uniform_effect(400, CurvatureClass::elliptic);
  auto scene = std::make_shared<const Scene>(std::vector<Region>{effect_region({0, 0, 400, 400}, effect)});
  PipelineConfig config;
  config.desktop = {0, 0, 400, 400};
  config.start = Vec2{50.5, 200.5};
  Pipeline pipeline(scene, config);
  auto frame = [&](TimeUs t, std::int32_t dx) {
    Frame in;
    in.events = {{t, ev::kRel, ev::kRelX, dx}, {t, ev::kSyn, ev::kSynReport, 0}};
    const Frame out = pipeline.process(in);
    std::int32_t emitted = 0;
    for (const InputEvent& e : out.events) {
      if (e.type == ev::kRel && e.code == ev::kRelX) emitted += e.value;
    }
    return emitted;
  };
  const FrictionParams f;
  TimeUs t = 0;
  int stuck_out = 0;
  for (int i = 0; i < 12; ++i) stuck_out += frame(t += kFrameUs, 1);  // 12 counts: 10 stuck, 2 slipping
  EXPECT_NEAR(stuck_out, f.breakaway_px / f.stuck_cd + 2.0, 1.0);
  EXPECT_FALSE(pipeline.cursor().effects[0].stuck);
  int slip_out = 0;
  for (int i = 0; i < 20; ++i) slip_out += frame(t += kFrameUs, 1);
  EXPECT_EQ(slip_out, 20);
  EXPECT_EQ(pipeline.cursor().effects[0].last_motion, t);
  // A pause of rest_ms between two events: stuck again.
  t += static_cast<TimeUs>(f.rest_ms * 1000);
  frame(t, 1);
  EXPECT_TRUE(pipeline.cursor().effects[0].stuck);
  int after_rest = 0;
  for (int i = 0; i < 5; ++i) after_rest += frame(t += kFrameUs, 1);
  EXPECT_LE(after_rest, 2);
}

}  // namespace
}  // namespace ph
