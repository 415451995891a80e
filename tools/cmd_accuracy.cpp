// `pseudohaptic accuracy OUTDIR [--small]`: speed against accuracy of every variant of the engine
// (docs/SPEED_VS_ACCURACY.md), from one binary, as CSV for tools/charts.py.
//
// Variants: method (curvature, depth, hybrid) x storage x engine options (core/engine/engine_options.hpp: every
// traversal with every sampling it accepts, direction_lut with 8 and 16 directions), and traversal = "auto" at the
// budgets kAutoBudgetsPx (label auto0.25, auto2, auto8; f32 storage): each shape gets what choose_variant picks.
// Storage is how a user's map reaches the engine, built from the exact target in memory and decoded through the
// loader's own path (core/engine/decode.hpp):
//   f32  the exact field rasterised at texel centres (target_gradient_field / target_depth_field);
//   n16, n8  a 16- / 8-bit normal map: codes round((n + 1) / 2 * cmax), decode_normals, then the loader's own
//            gradient_from_normals (core/engine/field.hpp: g = -n_xy / n_z, walls clamped);
//   d16, d8  a 16- / 8-bit depth map: codes of (h / relief + 1) / 2, decode_depth; the curvature method takes
//            central differences of it (gradient_from_depth), as the loader does for a depth-only region.
//   The depth method reads heights, so it has f32, d16 and d8 only.
// Ground truth: core/lab/ground_truth.hpp (exact continuous C/D, adaptive Gauss-Kronrod, 1e-9 px), per method; for
// the hybrid, which reads heights only where a depth map is given, one with them (f32, d16, d8) and one without
// (n16, n8).
//
// Shapes: the 24 targets of the curvature paper and the 9 interrogation surfaces of core/lab/surfaces.hpp at 256 px
// (a square relief, flat outside it; its "radius" for the strokes and the walks is half its size).
// Strokes (fixed, seeded): for each shape, directions 0, 30, 45, 90, 150, 250 degrees, motor px per frame 0.5, 2,
// 8, 30, without and with hand jitter (each frame's motor vector turned by N(0, 10 deg) and scaled by
// 1 + N(0, 0.2) clipped to [0.3, 2]). A stroke starts radius + 30 px before the target's centre, offset sideways
// by a seeded U(-0.3, 0.3) x radius, and lasts 2 x radius + 60 px of motor travel (without jitter).
// --small: 3 targets and 1 surface (simple-saddle), 2 directions, speeds 2 and 8.
//
// Metrics, per variant:
//   cd_err_rms, cd_err_max  relative C/D error along the strokes. Each step the engine reports (StepObserver)
//       applies its C/D to a display segment: from its entry point (the frame's start for a frame's first step)
//       to the next step's entry in the same frame or the frame's end, clipped to the step's region. The error is
//       (cd_engine - cd_truth) / cd_truth with cd_truth = truth_cd at the segment's midpoint for the frame's
//       direction; RMS weighted by segment length, max over steps with a segment longer than 1e-6 px. Only steps
//       inside a region count (the flat outside is exact in every variant). The max is dominated by the rims,
//       where a texel straddles a step of the C/D field: an error of the order of the jump is unavoidable there.
//   end_err_rms_px, end_err_max_px  distance between the engine's cursor and the truth's after each stroke
//       (truth: truth_advance frame by frame with the same motor vectors); RMS and max over strokes.
//   drift_px  a long random walk (full: 4 targets and 1 surface x 25 000 frames; --small: 1 x 1 500) of a seeded
//   virtual hand:
//       heading turning by N(0, 0.25 rad) a frame, speed log-normal around 3 px per frame (0.2 to 30), steered
//       back toward the target when the *true* cursor is beyond radius + 20 px. The walk is cut into windows of
//       100 frames; the engine starts each window at the truth's position and replays the same motor vectors.
//       drift_px = RMS over all windows of the distance between the engine's and the truth's cursor at the
//       window's end. (Over a whole walk the two part ways chaotically - a cursor a little off slides down the
//       other side of a bump - so the end-to-end distance measures nothing but that; windows measure the drift.)
//   ns_per_frame_median, ns_per_frame_p99  the walks' windows replayed without an observer (each from the truth's
//       position, 100 frames a batch) timed with steady_clock, repeated for at least 0.25 s (--small 0.02 s); per-frame
//       time of each batch, median and 99th percentile over the batches.
//   ns_per_step  total replay time / total FrameResult::steps (texel or unit steps inside regions).
//   bytes_per_texel  Scene::bytes() / region area (fields and direction tables).
//   precompute_ms  mean over the shapes of building a region's fields from the in-memory source (decoding for
//       the 8/16-bit maps; rasterising for f32) plus Scene::set_options (direction tables); no file I/O.
// fig5_traces.csv: f32 fields, exact traversal, nearest sampling, default parameters; a stroke along the texel
// row through the centre (y = size / 2 + 0.5), motor 1 px per frame; one row per step, x = segment midpoint.
// fig2_grid.csv: curvature_cd with a1 = a2 = cos(alpha) and theta1 - theta2 = delta-beta over cos(alpha) in
// [-1, 1] (the paper's two panels: > 0 downhill, < 0 uphill) and delta-beta in [-2, 2] degrees (the paper's range).
#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/engine/decode.hpp"
#include "core/engine/engine_options.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"
#include "core/engine/variant_choice.hpp"
#include "core/lab/cd_profile.hpp"
#include "core/lab/ground_truth.hpp"
#include "core/lab/map_storage.hpp"
#include "core/lab/surfaces.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/csv_file.hpp"
#include "tools/measured.hpp"
#include "tools/output_folder.hpp"

namespace ph::tools {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct AccuracyOptions {
  std::string outdir;
  bool small = false;
};

enum class Storage { f32, n16, n8, d16, d8 };

const char* name_of(Storage s) {
  switch (s) {
    case Storage::f32:
      return "f32";
    case Storage::n16:
      return "n16";
    case Storage::n8:
      return "n8";
    case Storage::d16:
      return "d16";
    case Storage::d8:
      return "d8";
  }
  return "?";
}

// Storage variants per method: adding one is one entry here and one case in build_fields. A method that reads
// heights has no normal-map storage (a normal map has none).
std::vector<Storage> storages_for(const Method& method) {
  if (!method.needs().depth) return {Storage::f32, Storage::n16, Storage::n8, Storage::d16, Storage::d8};
  return {Storage::f32, Storage::d16, Storage::d8};
}

// Engine variants: every traversal x sampling the engine accepts (a new enum value is picked up here).
std::vector<EngineOptions> engine_variants() {
  std::vector<EngineOptions> out;
  for (Traversal t : kAllTraversals) {
    for (Sampling s : kAllSamplings) {
      for (int n : t == Traversal::direction_lut ? std::vector<int>{8, 16} : std::vector<int>{16}) {
        const EngineOptions o{t, s, n};
        if (validate(o).empty()) out.push_back(o);
      }
    }
  }
  return out;
}

std::string traversal_label(const EngineOptions& o) {
  std::string label(name_of(o.traversal));
  if (o.traversal == Traversal::direction_lut) label += std::to_string(o.lut_directions);
  return label;
}

// One relief the strokes cross: a target of the curvature paper or an interrogation surface, with what the
// accuracy run needs of either.
struct Shape {
  std::variant<TargetSpec, SurfaceSpec> spec;

  bool is_target() const { return std::holds_alternative<TargetSpec>(spec); }
  std::string name() const {
    return std::visit([](const auto& s) { return s.name(); }, spec);
  }
  std::int32_t size() const {
    return std::visit([](const auto& s) { return s.size; }, spec);
  }
  double radius() const { return is_target() ? std::get<TargetSpec>(spec).radius : size() / 2.0; }
  double relief_px() const {
    return is_target() ? std::get<TargetSpec>(spec).relief_px : std::get<SurfaceSpec>(spec).relief_px();
  }
  GradientField gradient_field() const {
    return is_target() ? target_gradient_field(std::get<TargetSpec>(spec))
                       : surface_gradient_field(std::get<SurfaceSpec>(spec));
  }
  DepthField depth_field() const {
    return is_target() ? target_depth_field(std::get<TargetSpec>(spec))
                       : surface_depth_field(std::get<SurfaceSpec>(spec));
  }
  NormalImage normal_image() const {
    return is_target() ? target_normal_image(std::get<TargetSpec>(spec))
                       : surface_normal_image(std::get<SurfaceSpec>(spec));
  }
  std::unique_ptr<AnalyticSurface> surface() const {
    return is_target() ? make_target_surface(std::get<TargetSpec>(spec))
                       : make_interrogation_surface(std::get<SurfaceSpec>(spec));
  }
};

// The unorm values a depth map of the shape holds: codes of (h / relief + 1) / 2.
std::vector<double> depth_values(const Shape& shape) {
  const DepthField depth = shape.depth_field();
  std::vector<double> v(depth.values.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = (depth.values[i] / shape.relief_px() + 1.0) / 2.0;
  return v;
}

// What the user's file would be, before the timed decoding.
struct Source {
  RawImage image;
};

Source make_source(const Shape& shape, Storage storage) {
  const std::int32_t size = shape.size();
  switch (storage) {
    case Storage::f32:
      return {};
    case Storage::n16:
    case Storage::n8:
      return {encode_normal_map(shape.normal_image(), storage == Storage::n16 ? 65535 : 255)};
    case Storage::d16:
    case Storage::d8:
      return {quantised_image(size, size, 1, depth_values(shape), storage == Storage::d16 ? 65535 : 255)};
  }
  return {};
}

// The fields a method with `needs` reads, from one storage.
RegionFields build_fields(const Shape& shape, FieldNeeds needs, Storage storage, const Source& source) {
  RegionFields fields;
  DecodeReport report;
  switch (storage) {
    case Storage::f32:
      if (needs.gradient) fields.gradient = shape.gradient_field();
      if (needs.reads_depth(true)) fields.depth = shape.depth_field();
      break;
    case Storage::n16:
    case Storage::n8:
      fields.gradient = gradient_from_normals(decode_normals(source.image, {}, report));
      fields.gradient_rounding = gradient_rounding_of_normals(report.value_step);
      break;
    case Storage::d16:
    case Storage::d8: {
      DepthField depth = decode_depth(source.image, {0.5, 2.0 * shape.relief_px()}, report);
      if (needs.gradient) {
        fields.gradient = gradient_from_depth(depth);
        fields.gradient_rounding = gradient_rounding_of_depth(report.value_step);
      }
      if (needs.reads_depth(true)) {
        fields.depth = std::move(depth);
        fields.depth_rounding = height_rounding_of_depth(report.value_step);
      }
      break;
    }
  }
  return fields;
}

Scene make_scene(const Shape& shape, const MethodPtr& method, RegionFields fields) {
  Region region;
  region.name = shape.name();
  region.rect = {0, 0, shape.size(), shape.size()};
  region.fields = std::move(fields);
  region.method = method;
  std::vector<Region> regions;
  regions.push_back(std::move(region));
  return Scene(std::move(regions));
}

// A sequence of frames on one shape.
struct Path {
  std::size_t target = 0;  // index into the run's shapes
  Vec2 start;
  std::vector<Vec2> motors;
};

struct Config {
  std::vector<Shape> targets;  // the targets first, then the interrogation surfaces
  std::vector<double> directions_deg, speeds;
  std::vector<std::size_t> walk_targets;
  std::size_t walk_frames = 0;
  double timing_s = 0.0;
};

Config make_config(bool small) {
  Config c;
  const std::vector<TargetSpec> all = all_targets();
  constexpr std::int32_t kSurfaceSize = 256;
  if (small) {
    for (std::size_t i : {3u, 6u, 21u})
      c.targets.push_back({all[i]});  // bump-linear-h1-r200, bump-gaussian-h1-r100, hole-polynomial-h0.25-r200
    c.targets.push_back({SurfaceSpec{SurfaceKind::simple_saddle, kSurfaceSize}});
    c.directions_deg = {0.0, 30.0};
    c.speeds = {2.0, 8.0};
    c.walk_targets = {1};
    c.walk_frames = 1500;
    c.timing_s = 0.02;
  } else {
    for (const TargetSpec& t : all) c.targets.push_back({t});
    for (const SurfaceSpec& s : all_surfaces(kSurfaceSize)) c.targets.push_back({s});
    c.directions_deg = {0.0, 30.0, 45.0, 90.0, 150.0, 250.0};
    c.speeds = {0.5, 2.0, 8.0, 30.0};
    // Four targets and the simple saddle (the 24 targets, then the plane, ..., the saddle at 24 + 7).
    c.walk_targets = {3, 6, 11, 16, all.size() + 7};
    c.walk_frames = 25'000;
    c.timing_s = 0.25;
  }
  return c;
}

std::vector<Path> make_strokes(const Config& c) {
  std::mt19937_64 rng(20120601);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-0.3, 0.3);
  std::vector<Path> strokes;
  for (std::size_t t = 0; t < c.targets.size(); ++t) {
    const Shape& shape = c.targets[t];
    const Vec2 centre{shape.size() / 2.0, shape.size() / 2.0};
    const double radius = shape.radius();
    for (double deg : c.directions_deg) {
      const double a = deg * std::numbers::pi / 180.0;
      const Vec2 m{std::cos(a), std::sin(a)};
      const Vec2 side{-m.y, m.x};
      for (double speed : c.speeds) {
        for (bool jitter : {false, true}) {
          Path p;
          p.target = t;
          p.start = centre - m * (radius + 30.0) + side * (uniform(rng) * radius);
          const auto frames = static_cast<std::size_t>(std::ceil((2.0 * radius + 60.0) / speed));
          for (std::size_t f = 0; f < frames; ++f) {
            if (!jitter) {
              p.motors.push_back(m * speed);
              continue;
            }
            const double turn = gauss(rng) * 10.0 * std::numbers::pi / 180.0;
            const double scale = std::clamp(1.0 + 0.2 * gauss(rng), 0.3, 2.0);
            const Vec2 mj{m.x * std::cos(turn) - m.y * std::sin(turn), m.x * std::sin(turn) + m.y * std::cos(turn)};
            p.motors.push_back(mj * (speed * scale));
          }
          strokes.push_back(std::move(p));
        }
      }
    }
  }
  return strokes;
}

constexpr std::size_t kDriftWindow = 100;  // frames between the resets of the drift measure

// The virtual hand's walk, steered by the true cursor; returns the path and the truth's position at every
// multiple of kDriftWindow frames (the first one the start).
Path make_walk(const Config& c, std::size_t target, const TruthModel& model, std::uint64_t seed,
               std::vector<Vec2>& truth_marks) {
  const Shape& shape = c.targets[target];
  const Vec2 centre{shape.size() / 2.0, shape.size() / 2.0};
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Path p;
  p.target = target;
  p.start = centre + Vec2{0.37, -0.21};
  Vec2 truth = p.start;
  double heading = 0.0;
  truth_marks.assign(1, truth);
  for (std::size_t f = 0; f < c.walk_frames; ++f) {
    heading += 0.25 * gauss(rng);
    const Vec2 to_centre = centre - truth;
    if (length(to_centre) > shape.radius() + 20.0) heading = std::atan2(to_centre.y, to_centre.x) + 0.3 * gauss(rng);
    const double speed = std::clamp(3.0 * std::exp(0.8 * gauss(rng)), 0.2, 30.0);
    const Vec2 motor{speed * std::cos(heading), speed * std::sin(heading)};
    p.motors.push_back(motor);
    truth = truth_advance(model, truth, motor);
    if ((f + 1) % kDriftWindow == 0) truth_marks.push_back(truth);
  }
  return p;
}

Vec2 truth_end_of(const TruthModel& model, const Path& path) {
  Vec2 p = path.start;
  for (const Vec2& motor : path.motors) p = truth_advance(model, p, motor);
  return p;
}

// Collects a frame's steps for the C/D error.
class StepLog final : public StepObserver {
 public:
  void on_step(const StepRecord& step) override { steps.push_back(step); }
  std::vector<StepRecord> steps;
};

// Adds the frame's steps to the C/D error (definition at the top of the file).
void score_frame(const TruthModel& model, const std::vector<StepRecord>& steps, Vec2 start, Vec2 end, Vec2 m,
                 CdError& err, const std::function<void(double x, double cd, double truth)>& trace = {}) {
  const Vec2 span = end - start;
  for (const CdSegment& g : cd_segments(steps, start, m, span.x * m.x + span.y * m.y)) {
    const Vec2 mid = start + m * (0.5 * (g.s0 + g.s1));
    const double truth = truth_cd(model, mid, m);
    err.add((g.cd - truth) / truth, g.s1 - g.s0);
    if (trace) trace(mid.x, g.cd, truth);
  }
}

struct VariantRow {
  std::string variant, method, traversal, storage, sampling;
  double ns_median = 0, ns_p99 = 0, ns_step = 0, bytes_texel = 0, precompute_ms = 0;
  double cd_rms = 0, cd_max = 0, end_rms = 0, end_max = 0, drift = 0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(q * (v.size() - 1) + 0.5)));
  return v[i];
}

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// What every variant is measured on: the shapes, their exact surfaces, the strokes and the engine variants.
struct Workload {
  Config config;
  std::vector<Path> strokes;
  std::vector<std::unique_ptr<AnalyticSurface>> surfaces;  // one per shape
  std::vector<EngineOptions> engines;
};

Workload make_workload(bool small) {
  Workload w;
  w.config = make_config(small);
  w.strokes = make_strokes(w.config);
  for (const Shape& shape : w.config.targets) w.surfaces.push_back(shape.surface());
  w.engines = engine_variants();
  return w;
}

// The truth for one method: where each stroke ends, and the walks with the truth's cursor every kDriftWindow
// frames (the walks are steered by the true cursor, so they depend on the method).
struct MethodTruth {
  bool depth_given = true;  // TruthModel::depth_given
  std::vector<Vec2> stroke_ends;
  std::vector<Path> walks;
  std::vector<std::vector<Vec2>> walk_marks;
};

TruthModel model_of(const Workload& w, std::size_t target, const Method& method, bool depth_given) {
  return TruthModel{w.surfaces[target].get(), &method, depth_given};
}

MethodTruth compute_truth(const Workload& w, const Method& method, bool depth_given) {
  MethodTruth truth;
  truth.depth_given = depth_given;
  for (const Path& p : w.strokes) {
    truth.stroke_ends.push_back(truth_end_of(model_of(w, p.target, method, depth_given), p));
  }
  for (std::size_t target : w.config.walk_targets) {
    truth.walk_marks.emplace_back();
    truth.walks.push_back(
        make_walk(w.config, target, model_of(w, target, method, depth_given), 1000 + target, truth.walk_marks.back()));
  }
  return truth;
}

// One scene per shape with the fields of one storage; build_ms: the mean time to build a shape's fields.
struct StorageScenes {
  std::vector<Scene> scenes;
  double build_ms = 0.0;
  bool depth_given = true;  // whether every region was given a depth map (a normal-map storage gives none)
};

StorageScenes build_scenes(const Workload& w, const MethodPtr& method, Storage storage) {
  StorageScenes out;
  for (const Shape& shape : w.config.targets) {
    const Source source = make_source(shape, storage);
    const Clock::time_point t0 = Clock::now();
    RegionFields fields = build_fields(shape, method->needs(), storage, source);
    out.build_ms += ms_since(t0);
    out.depth_given = out.depth_given && fields.depth.has_value();
    out.scenes.push_back(make_scene(shape, method, std::move(fields)));
  }
  out.build_ms /= static_cast<double>(w.config.targets.size());
  return out;
}

// Selects each scene's engine variant, as `choose` gives it for the scene's region (timed with the
// precomputation); fills the row's precompute time and bytes per texel.
void select_engines(StorageScenes& s, const std::function<EngineOptions(const Region&)>& choose, VariantRow& row) {
  double options_ms = 0.0;
  std::size_t bytes = 0;
  std::int64_t area = 0;
  for (Scene& scene : s.scenes) {
    const Clock::time_point t0 = Clock::now();
    scene.set_options(choose(scene.regions().front()));
    options_ms += ms_since(t0);
    bytes += scene.bytes();
    area += scene.regions().front().rect.area();
  }
  row.precompute_ms = s.build_ms + options_ms / static_cast<double>(s.scenes.size());
  row.bytes_texel = static_cast<double>(bytes) / static_cast<double>(area);
}

// The C/D error along the strokes and the strokes' end errors.
void measure_strokes(const Workload& w, const MethodTruth& truth, const std::vector<Scene>& scenes,
                     const Method& method, VariantRow& row) {
  CdError cd_err;
  double end_sum2 = 0.0, end_max = 0.0;
  StepLog log;
  for (std::size_t i = 0; i < w.strokes.size(); ++i) {
    const Path& p = w.strokes[i];
    const TruthModel model = model_of(w, p.target, method, truth.depth_given);
    CursorState cursor = cursor_at(p.start);
    for (const Vec2& motor : p.motors) {
      log.steps.clear();
      const Vec2 start = cursor.position;
      advance(scenes[p.target], cursor, motor, &log);
      score_frame(model, log.steps, start, cursor.position, motor * (1.0 / length(motor)), cd_err);
    }
    const double e = length(cursor.position - truth.stroke_ends[i]);
    end_sum2 += e * e;
    end_max = std::max(end_max, e);
  }
  row.cd_rms = cd_err.rms();
  row.cd_max = cd_err.max;
  row.end_rms = std::sqrt(end_sum2 / static_cast<double>(w.strokes.size()));
  row.end_max = end_max;
}

// RMS over the walks' windows of the distance to the truth at the window's end.
double measure_drift(const MethodTruth& truth, const std::vector<Scene>& scenes) {
  double drift2 = 0.0;
  std::size_t windows = 0;
  for (std::size_t w = 0; w < truth.walks.size(); ++w) {
    const std::vector<Vec2>& marks = truth.walk_marks[w];
    for (std::size_t k = 0; k + 1 < marks.size(); ++k) {
      CursorState cursor = cursor_at(marks[k]);
      for (std::size_t f = k * kDriftWindow; f < (k + 1) * kDriftWindow; ++f) {
        advance(scenes[truth.walks[w].target], cursor, truth.walks[w].motors[f]);
      }
      const double e = length(cursor.position - marks[k + 1]);
      drift2 += e * e;
      ++windows;
    }
  }
  return windows > 0 ? std::sqrt(drift2 / static_cast<double>(windows)) : 0.0;
}

// Speed from replaying the walks without an observer, one batch per drift window started at the truth's
// position: a replay from the walk's start alone would part from the truth and spend its time on the flat
// outside.
void measure_speed(const MethodTruth& truth, const std::vector<Scene>& scenes, double timing_s, VariantRow& row) {
  std::vector<double> per_frame;
  double total_ns = 0.0;
  std::uint64_t total_steps = 0;
  const Clock::time_point t_timing = Clock::now();
  do {
    for (std::size_t w = 0; w < truth.walks.size(); ++w) {
      const Scene& scene = scenes[truth.walks[w].target];
      const std::vector<Vec2>& marks = truth.walk_marks[w];
      for (std::size_t k = 0; k + 1 < marks.size(); ++k) {
        CursorState cursor = cursor_at(marks[k]);
        std::uint64_t steps = 0;
        const Clock::time_point t0 = Clock::now();
        for (std::size_t f = k * kDriftWindow; f < (k + 1) * kDriftWindow; ++f) {
          steps += advance(scene, cursor, truth.walks[w].motors[f]).steps;
        }
        const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
        per_frame.push_back(ns / static_cast<double>(kDriftWindow));
        total_ns += ns;
        total_steps += steps;
      }
    }
  } while (ms_since(t_timing) < timing_s * 1000.0);
  row.ns_median = percentile(per_frame, 0.5);
  row.ns_p99 = percentile(per_frame, 0.99);
  row.ns_step = total_steps > 0 ? total_ns / static_cast<double>(total_steps) : 0.0;
}

// One row: every scene on what `choose` gives for its region, labelled with `traversal` and `sampling`.
VariantRow measure_row(const Workload& w, const MethodTruth& truth, const MethodPtr& method, Storage storage,
                       StorageScenes& scenes, std::string traversal, Sampling sampling,
                       const std::function<EngineOptions(const Region&)>& choose) {
  VariantRow row;
  row.method = std::string(method->name());
  row.traversal = std::move(traversal);
  row.storage = name_of(storage);
  row.sampling = std::string(name_of(sampling));
  row.variant = fmt::format("{}/{}/{}/{}", row.method, row.traversal, row.storage, row.sampling);
  select_engines(scenes, choose, row);
  measure_strokes(w, truth, scenes.scenes, *method, row);
  row.drift = measure_drift(truth, scenes.scenes);
  measure_speed(truth, scenes.scenes, w.config.timing_s, row);
  return row;
}

VariantRow measure_variant(const Workload& w, const MethodTruth& truth, const MethodPtr& method, Storage storage,
                           StorageScenes& scenes, const EngineOptions& engine) {
  return measure_row(w, truth, method, storage, scenes, traversal_label(engine), engine.sampling,
                     [&engine](const Region&) { return engine; });
}

// traversal = "auto" at a budget (accuracy_px): each shape's scene gets the variant choose_variant picks for its
// region, as the scene file's loader does; the row is the mix over the shapes.
VariantRow measure_auto(const Workload& w, const MethodTruth& truth, const MethodPtr& method, Storage storage,
                        StorageScenes& scenes, double budget_px) {
  std::size_t chose_exact = 0;
  VariantRow row = measure_row(w, truth, method, storage, scenes, fmt::format("auto{:g}", budget_px),
                               EngineOptions{}.sampling, [&](const Region& region) {
                                 const EngineOptions chosen = choose_variant(region, {budget_px}).options;
                                 chose_exact += chosen.traversal == Traversal::exact ? 1 : 0;
                                 return chosen;
                               });
  const std::size_t shapes = scenes.scenes.size();
  fmt::print(stderr, "accuracy: {:<44} {}\n", row.variant,
             chose_exact == shapes ? fmt::format("exact on all {} shapes", shapes)
             : chose_exact == 0
                 ? fmt::format("frame_midpoint on all {} shapes", shapes)
                 : fmt::format("exact on {} of {} shapes, frame_midpoint on the rest", chose_exact, shapes));
  return row;
}

// The budgets auto is measured at: the default (VariantBudget), then looser ones that let it choose
// frame_midpoint on more shapes.
constexpr double kAutoBudgetsPx[] = {0.25, 2.0, 8.0};

// The rows measure_all makes: every engine variant on each storage of each method, and auto at each budget on f32.
std::size_t rows_to_measure(const Workload& w, const std::vector<MethodPtr>& methods) {
  std::size_t n = 0;
  for (const MethodPtr& method : methods) {
    for (Storage storage : storages_for(*method))
      n += w.engines.size() + (storage == Storage::f32 ? std::size(kAutoBudgetsPx) : 0);
  }
  return n;
}

// Every variant of every method: method x storage x (engine variants, auto at each budget).
std::vector<VariantRow> measure_all(const Workload& w, const std::vector<MethodPtr>& methods) {
  std::vector<VariantRow> rows;
  const std::size_t total = rows_to_measure(w, methods);
  for (const MethodPtr& method : methods) {
    // A method that reads heights only where a depth map is given has a truth with them and one without.
    std::optional<MethodTruth> truths[2];  // [0]: without a depth map
    for (Storage storage : storages_for(*method)) {
      StorageScenes scenes = build_scenes(w, method, storage);
      const bool depth_given = !method->needs().depth_if_given || scenes.depth_given;
      std::optional<MethodTruth>& truth = truths[depth_given ? 1 : 0];
      if (!truth) {
        const Clock::time_point t_truth = Clock::now();
        fmt::print(stderr, "accuracy: {} ground truth{}...\n", method->name(),
                   depth_given ? "" : " without a depth map");
        truth = compute_truth(w, *method, depth_given);
        fmt::print(stderr, "accuracy: {} ground truth{} in {:.1f} s\n", method->name(),
                   depth_given ? "" : " without a depth map", ms_since(t_truth) / 1000.0);
      }
      auto report = [&rows, total](VariantRow row) {
        fmt::print(stderr, "accuracy: [{}/{}] {:<44} end rms {:.3g} px, C/D rms {:.3g}, {:.0f} ns/frame\n",
                   rows.size() + 1, total, row.variant, row.end_rms, row.cd_rms, row.ns_median);
        rows.push_back(std::move(row));
      };
      for (const EngineOptions& engine : w.engines) report(measure_variant(w, *truth, method, storage, scenes, engine));
      if (storage != Storage::f32) continue;  // auto on exact fields only: a point per budget, not a cloud
      for (double budget : kAutoBudgetsPx) report(measure_auto(w, *truth, method, storage, scenes, budget));
    }
  }
  return rows;
}

// Each writer writes a file of the folder's OutputSet (tools/output_folder.hpp): in place, the set stages them.
void write_variants(const fs::path& path, const std::vector<VariantRow>& rows) {
  CsvFile f(path, false);
  f.print(
      "variant,method,traversal,storage,sampling,ns_per_frame_median,ns_per_frame_p99,ns_per_step,"
      "bytes_per_texel,precompute_ms,cd_err_rms,cd_err_max,end_err_rms_px,end_err_max_px,drift_px\n");
  for (const VariantRow& r : rows) {
    f.print("{},{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", r.variant,
            r.method, r.traversal, r.storage, r.sampling, r.ns_median, r.ns_p99, r.ns_step, r.bytes_texel,
            r.precompute_ms, r.cd_rms, r.cd_max, r.end_rms, r.end_max, r.drift);
  }
  f.close();
}

// Fig. 5: the default variant's C/D along the centre row of each target, with the truth.
void write_fig5(const fs::path& path, const Workload& w, const std::vector<MethodPtr>& methods) {
  CsvFile f(path, false);
  f.print("target,method,x,cd,cd_truth\n");
  for (std::size_t t = 0; t < w.config.targets.size(); ++t) {
    const Shape& shape = w.config.targets[t];
    if (!shape.is_target()) continue;  // the paper's figure is of its targets
    const std::int32_t size = shape.size();
    for (const MethodPtr& method : methods) {
      const Scene scene = make_scene(shape, method, build_fields(shape, method->needs(), Storage::f32, {}));
      const TruthModel model = model_of(w, t, *method, true);  // f32 fields: the depth map given
      CursorState cursor = cursor_at({0.0, size / 2.0 + 0.5});
      CdError unused;
      StepLog log;
      while (cursor.position.x < size) {
        log.steps.clear();
        const Vec2 start = cursor.position;
        advance(scene, cursor, {1.0, 0.0}, &log);
        score_frame(model, log.steps, start, cursor.position, {1.0, 0.0}, unused,
                    [&](double x, double cd, double truth) {
                      f.print("{},{},{:.4f},{:.6g},{:.6g}\n", shape.name(), method->name(), x, cd, truth);
                    });
      }
    }
  }
  f.close();
}

// Fig. 2: the curvature method's formula over the paper's plane of cos(alpha) and delta-beta.
void write_fig2(const fs::path& path) {
  CsvFile f(path, false);
  f.print("cos_alpha,delta_beta_deg,cd\n");
  const CurvatureParams params{};
  for (int i = 0; i <= 40; ++i) {
    const double cos_alpha = -1.0 + i / 20.0;
    for (int j = 0; j <= 40; ++j) {
      const double delta_beta_deg = -2.0 + j / 10.0;
      const double theta1 = delta_beta_deg * std::numbers::pi / 180.0;
      f.print("{:.4g},{:.4g},{:.6g}\n", cos_alpha, delta_beta_deg,
              curvature_cd(params, cos_alpha, theta1, cos_alpha, 0.0, nullptr));
    }
  }
  f.close();
}

int run_accuracy(const AccuracyOptions& o) {
  const Clock::time_point t_start = Clock::now();
  const fs::path outdir(o.outdir);
  prepare_output_folder(outdir, {"variants.csv", "fig5_traces.csv", "fig2_grid.csv"});
  const Workload workload = make_workload(o.small);
  const std::vector<MethodPtr> methods = measured_methods();
  fmt::print(stderr,
             "accuracy: {} shapes, {} strokes, {} engine variants: {} rows (methods x storages x variants, "
             "and auto)\n",
             workload.config.targets.size(), workload.strokes.size(), workload.engines.size(),
             rows_to_measure(workload, methods));
  const std::vector<VariantRow> rows = measure_all(workload, methods);
  // Replaced as a set: an interrupted run leaves the three files of the last one, not some of each.
  OutputSet files(outdir);
  write_variants(files.stage("variants.csv"), rows);
  write_fig5(files.stage("fig5_traces.csv"), workload, methods);
  write_fig2(files.stage("fig2_grid.csv"));
  files.commit();
  fmt::print("wrote {} variants to {} in {:.1f} s\n", rows.size(), outdir.string(), ms_since(t_start) / 1000.0);
  return 0;
}

}  // namespace

Run add_accuracy_command(CLI::App& app) {
  auto o = std::make_shared<AccuracyOptions>();
  app.description(
      "Measure accuracy against the exact ground truth and speed of every engine variant (method x storage x\n"
      "traversal x sampling, and traversal = \"auto\" at accuracy_px 0.25, 2 and 8) over seeded strokes and\n"
      "random walks across the 24 targets and the 9 interrogation surfaces; write\n"
      "OUTDIR/variants.csv, OUTDIR/fig5_traces.csv and OUTDIR/fig2_grid.csv for tools/charts.py.");
  app.add_option("OUTDIR", o->outdir, "Folder for the CSV files (created if needed)")
      ->required()
      ->check(non_empty_path());
  app.add_flag("--small", o->small, "A handful of strokes and a short walk (seconds; for CI)");
  return [o] { return run_accuracy(*o); };
}

}  // namespace ph::tools
