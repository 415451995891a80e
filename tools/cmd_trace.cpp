// `pseudohaptic trace`: the data behind the paper's Fig. 5, one CSV row per texel step.
#include <fmt/core.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config/field_loader.hpp"
#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/stroke.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/csv_cell.hpp"
#include "tools/csv_file.hpp"
#include "tools/finite_check.hpp"
#include "tools/map_flags.hpp"
#include "tools/number_tuple.hpp"
#include "tools/same_path.hpp"
#include "tools/stroke_fits.hpp"

namespace ph::tools {

namespace {

struct TraceOptions {
  std::string scene_file, normal_map, depth_map, target;
  MapFlags maps;  // how to decode --normal-map and --depth-map
  std::string method;
  std::optional<double> kmax_prime, kmin_prime, delta_beta_sign, gain, depth_kmax, depth_kmin;
  std::vector<double> kmax_limits, kmin_limits, from, to;
  std::optional<double> step, speed;
  double rate = 125.0;
  bool rate_given = false;  // --rate on the command line (it has a default)
  std::string output = "-";
};

// A method's flags on the command line and what was given with each ("" where not given): the messages of its
// validate() name the scene file's keys, and the user typed flags.
using GivenFlags = std::vector<std::pair<const char*, std::string>>;
std::string text_of(const std::optional<double>& v) { return v ? fmt::format("{:g}", *v) : ""; }
std::string text_of(const std::vector<double>& v) { return v.empty() ? "" : fmt::format("{:g}", fmt::join(v, ",")); }
GivenFlags curvature_flags(const TraceOptions& o) {
  return {{"--kmax-prime", text_of(o.kmax_prime)},
          {"--kmin-prime", text_of(o.kmin_prime)},
          {"--kmax-limits", text_of(o.kmax_limits)},
          {"--kmin-limits", text_of(o.kmin_limits)},
          {"--delta-beta-sign", text_of(o.delta_beta_sign)}};
}
GivenFlags depth_flags(const TraceOptions& o) {
  return {
      {"--gain", text_of(o.gain)}, {"--depth-kmax", text_of(o.depth_kmax)}, {"--depth-kmin", text_of(o.depth_kmin)}};
}
// " (given: --depth-kmax 0.5)", or "" where none of them was given.
std::string given_flags(const GivenFlags& flags) {
  std::string given;
  for (const auto& [flag, value] : flags) {
    if (!value.empty()) given += fmt::format("{}{} {}", given.empty() ? "" : ", ", flag, value);
  }
  return given.empty() ? "" : " (given: " + given + ")";
}

// The options that change a region's method, applied to every region of the traced scene.
void apply_overrides(const TraceOptions& o, RegionSpec& r) {
  if (!o.method.empty()) r.method = o.method;
  CurvatureParams& curvature = method_params<CurvatureMethod>(r);
  if (o.kmax_prime) curvature.kmax_prime = *o.kmax_prime;
  if (o.kmin_prime) curvature.kmin_prime = *o.kmin_prime;
  if (o.delta_beta_sign) curvature.delta_beta_sign = *o.delta_beta_sign;
  if (o.kmax_limits.size() == 2)
    std::tie(curvature.kmax_lo, curvature.kmax_hi) = std::pair(o.kmax_limits[0], o.kmax_limits[1]);
  if (o.kmin_limits.size() == 2)
    std::tie(curvature.kmin_lo, curvature.kmin_hi) = std::pair(o.kmin_limits[0], o.kmin_limits[1]);
  DepthParams& depth = method_params<DepthMethod>(r);
  if (o.gain) depth.gain = *o.gain;
  if (o.depth_kmax) depth.kmax = *o.depth_kmax;
  if (o.depth_kmin) depth.kmin = *o.depth_kmin;
  if (auto e = validate(curvature); !e.empty())
    throw std::invalid_argument("curvature method: " + e + given_flags(curvature_flags(o)));
  if (auto e = validate(depth); !e.empty())
    throw std::invalid_argument("depth method: " + e + given_flags(depth_flags(o)));
}

// A one-region scene at (0, 0) covering the given image(s) at their own size. Loaded here rather than through a
// scene file's loader, so that a bad map reads "FILE: what went wrong", with no scene file line to name.
Scene scene_from_maps(const TraceOptions& o, std::vector<std::string>& warnings) {
  RegionSpec r;
  r.name = "trace";
  if (!o.normal_map.empty()) r.sources.normal_map = o.normal_map;
  if (!o.depth_map.empty()) r.sources.depth_map = o.depth_map;
  const ImageSize size = read_image_size(!o.normal_map.empty() ? o.normal_map : o.depth_map);
  r.rect = {0, 0, size.width, size.height};
  apply_map_flags(o.maps, r.sources);
  r.method = o.depth_map.empty() || !o.normal_map.empty() ? CurvatureMethod::kName : DepthMethod::kName;
  apply_overrides(o, r);
  Region region;
  region.name = r.name;
  region.rect = r.rect;
  region.method = make_method(r);
  FieldLoadReport report;
  region.fields = load_region_fields(r.sources, r.rect.w, r.rect.h, region.method->needs(), report);
  for (std::string& note : map_notes(r.sources, report, r.rect.w, r.rect.h)) warnings.push_back(std::move(note));
  std::vector<Region> regions;
  regions.push_back(std::move(region));
  Scene scene(std::move(regions));
  // The maps' scales as the method found them when it prepared the fields (the hybrid does, in the scene).
  const std::optional<ReliefScale> scale = relief_scale(r, scene.regions().front().fields);
  if (scale && scale->mismatched()) warnings.push_back(scale->warning());
  return scene;
}

// A target built in memory from its exact analytic fields (no files).
Scene scene_from_target(const TraceOptions& o) {
  for (const TargetSpec& t : all_targets()) {
    if (t.name() != o.target) continue;
    RegionSpec r;
    apply_overrides(o, r);
    Region region;
    region.name = t.name();
    region.rect = {0, 0, t.size, t.size};
    region.method = make_method(r);
    region.fields = target_fields(t, region.method->needs());
    std::vector<Region> regions;
    regions.push_back(std::move(region));
    return Scene(std::move(regions));
  }
  throw std::invalid_argument(fmt::format("no target named '{}' (see `pseudohaptic targets`)", o.target));
}

// The trace would replace a file it reads: refused before anything is read or written, as `replay` refuses it.
void check_output_is_no_input(const TraceOptions& o) {
  for (const auto& [flag, input] : {std::pair<const char*, const std::string&>{"--scene", o.scene_file},
                                    {"--normal-map", o.normal_map},
                                    {"--depth-map", o.depth_map}}) {
    if (!input.empty() && same_path(input, o.output))
      throw std::invalid_argument(
          fmt::format("-o {} is the file {} reads: write the trace to another file", o.output, flag));
  }
}

// As check_output_is_no_input, for the maps the scene file names, once it is read and before they are.
void check_output_is_no_map(const std::string& output, const SceneSpec& spec) {
  for (const RegionSpec& r : spec.regions) {
    for (const auto& [key, map] :
         {std::pair{"normal_map", r.sources.normal_map}, std::pair{"depth_map", r.sources.depth_map}}) {
      if (map && same_path(map->string(), output))
        throw std::invalid_argument(fmt::format("-o {} is the {} of region '{}' of {}: write the trace to another file",
                                                output, key, r.name, spec.file.string()));
    }
  }
}

// The scene to trace; `warnings` gets a line per map with invalid texels (repaired) or stretched out of proportion.
Scene build_scene(const TraceOptions& o, std::vector<std::string>& warnings) {
  const int sources = !o.scene_file.empty() + !o.target.empty() + (!o.normal_map.empty() || !o.depth_map.empty());
  if (sources != 1) throw std::invalid_argument("give exactly one of --scene, --target, or --normal-map/--depth-map");
  // A decoding flag beside a scene file or a target would change nothing: said rather than ignored.
  if (const std::vector<std::string> given = given_map_flags(o.maps);
      !given.empty() && o.normal_map.empty() && o.depth_map.empty()) {
    throw std::invalid_argument(fmt::format(
        "{} applies to --normal-map/--depth-map only ({})", given.front(),
        o.target.empty() ? "a scene file sets it per region" : "a target's fields are exact, with no map to decode"));
  }
  if (!o.target.empty()) return scene_from_target(o);
  if (o.scene_file.empty()) {
    check_map_flags_have_their_map(o.maps, !o.normal_map.empty(), !o.depth_map.empty());
    return scene_from_maps(o, warnings);
  }
  SceneSpec spec = parse_scene_file(o.scene_file);
  if (spec.regions.empty()) throw std::invalid_argument(fmt::format("{}: the scene has no region", spec.file.string()));
  check_output_is_no_map(o.output, spec);
  for (RegionSpec& r : spec.regions) apply_overrides(o, r);
  SceneLoadReport report;
  Scene scene = load_scene(spec, &report);
  for (std::string& warning : load_warnings(spec, report, scene)) warnings.push_back(std::move(warning));
  return scene;
}

// A method's option that no traced region's method reads would change nothing: said rather than ignored, as a
// decoding flag beside a scene file is. (The hybrid method runs its parents with their default parameters.)
void check_method_options_are_used(const TraceOptions& o, const Scene& scene) {
  std::vector<std::string> used;
  for (const Region& region : scene.regions()) {
    const std::string name(region.method->name());
    if (std::find(used.begin(), used.end(), name) == used.end()) used.push_back(name);
  }
  const auto uses = [&](std::string_view method) { return std::find(used.begin(), used.end(), method) != used.end(); };
  for (const auto& [method, flags] :
       {std::pair{CurvatureMethod::kName, curvature_flags(o)}, std::pair{DepthMethod::kName, depth_flags(o)}}) {
    if (uses(method)) continue;
    for (const auto& [flag, value] : flags) {
      if (value.empty()) continue;
      std::string methods;
      for (const std::string& name : used) methods += (methods.empty() ? "" : ", ") + name;
      throw std::invalid_argument(fmt::format(
          "{} is an option of the {} method, which no region traced uses (they use {}{}): give "
          "--method {} to trace with it",
          flag, method, methods,
          uses(HybridMethod::kName) ? "; the hybrid method runs it with its default parameters" : "", method));
    }
  }
  if (o.rate_given && !o.speed)
    throw std::invalid_argument("--rate applies to --speed only (the step is speed / rate)");
}

Vec2 point(const std::vector<double>& v, Vec2 fallback) { return v.size() == 2 ? Vec2{v[0], v[1]} : fallback; }

// The stroke's options, each named in its error (the stroke itself would only say that it has no length).
void check_stroke_options(const TraceOptions& o) {
  if (o.step && o.speed) throw std::invalid_argument("give --step or --speed, not both");
  for (const auto& [name, v] : {std::pair<const char*, const std::vector<double>&>{"--from", o.from}, {"--to", o.to}}) {
    if (!std::all_of(v.begin(), v.end(), [](double c) { return std::isfinite(c); }))
      throw std::invalid_argument(fmt::format("{}: X and Y must be finite numbers", name));
    // The cursor model never leaves the world's bounds: a point past them would be moved in silence.
    if (!std::all_of(v.begin(), v.end(), [](double c) { return std::abs(c) <= kWorldLimitPx; }))
      throw std::invalid_argument(fmt::format("{}: X and Y must be within ±{:g} px", name, kWorldLimitPx));
  }
}

// A finite number, or nothing (an empty cell). Zero is written 0, whatever its sign: a flat texel's cos alpha
// comes out of the arithmetic as -0 (a = -t / sqrt(1 + t^2) with t = +0).
void append_number(fmt::memory_buffer& out, double v) {
  if (std::isfinite(v)) fmt::format_to(std::back_inserter(out), "{:.6g}", v == 0.0 ? 0.0 : v);
}

// The stroke across the scene (by default the first region's width at its middle height), checked: its options
// each by name, then by the stroke itself, run for no frame (a stroke of no length), so that the output is opened
// only for a stroke that runs.
StrokeSpec checked_stroke(const TraceOptions& o, const Scene& scene) {
  check_stroke_options(o);
  const Rect first = scene.regions().front().rect;
  StrokeSpec stroke;
  const double mid_y = first.y + first.h / 2.0;
  stroke.from = point(o.from, {static_cast<double>(first.x), mid_y});
  stroke.to = point(o.to, {static_cast<double>(first.x + first.w), mid_y});
  stroke.motor_step_px = o.step ? *o.step : o.speed ? *o.speed / o.rate : 1.0;
  if (o.speed) stroke.rate_hz = o.rate;  // the frames' times, for a material's damping
  // Said before a CSV of millions of rows.
  check_stroke_fits(stroke, o.speed ? "--speed or a smaller --rate" : "--step");
  StrokeSpec no_frame = stroke;
  no_frame.max_frames = 0;
  run_stroke(scene, no_frame);
  return stroke;
}

int run_trace(const TraceOptions& o) {
  check_output_is_no_input(o);
  std::vector<std::string> warnings;
  const Scene scene = build_scene(o, warnings);
  for (const std::string& w : warnings) fmt::print(stderr, "pseudohaptic: warning: {}\n", w);
  check_method_options_are_used(o, scene);
  const StrokeSpec stroke = checked_stroke(o, scene);
  bool met_a_region = false;

  CsvFile file(o.output);
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out),
                 "frame,x,y,texel_x,texel_y,cos_alpha,delta_beta_deg,kmax,kmin,dh,cd,region\n");
  auto flush = [&] {
    file.write({out.data(), out.size()});
    out.clear();
  };
  // One row per texel step, and for the texel the stroke starts in. A frame that ends exactly on a texel's edge
  // enters the next texel at the start of the following frame, where the step is not marked as entered: a change of
  // texel since the last row is a step too.
  std::optional<Texel> last_row;
  const StrokeResult result = run_stroke(scene, stroke, [&](std::size_t frame, const StepRecord& s) {
    met_a_region = met_a_region || s.region != nullptr;
    const bool new_texel = !last_row || last_row->x != s.texel.x || last_row->y != s.texel.y;
    if (!s.entered && frame != 0 && !new_texel) return;
    last_row = s.texel;
    fmt::format_to(std::back_inserter(out), "{},{:.6f},{:.6f},{},{},", frame, s.entry.x, s.entry.y, s.texel.x,
                   s.texel.y);
    for (double v : {s.detail.cos_alpha, s.detail.delta_beta_deg, s.detail.kmax, s.detail.kmin, s.detail.dh}) {
      append_number(out, v);
      out.push_back(',');
    }
    fmt::format_to(std::back_inserter(out), "{:.6g},{}\n", s.cd, s.region != nullptr ? csv_cell(s.region->name) : "");
    if (out.size() > (1 << 16)) flush();
  });
  flush();
  // A stroke stopped short is a failed run: its file is left as it was (what is written through has had it already).
  const bool left_as_it_was = !result.reached && file.staged();
  if (!left_as_it_was) file.close();
  fmt::print(stderr, "{} frames, cursor ended at ({:.3f}, {:.3f}), C/D range [{:.4g}, {:.4g}]{}\n", result.frames,
             result.end.position.x, result.end.position.y, result.cd_min, result.cd_max,
             result.reached ? "" : " (stopped before the end point)");
  if (!met_a_region) {
    const Region& first = scene.regions().front();
    fmt::print(stderr,
               "pseudohaptic: warning: the stroke from ({:g}, {:g}) to ({:g}, {:g}) crosses no region of the scene, so "
               "its C/D is 1 throughout ({} '{}' covers ({}, {}) to ({}, {}))\n",
               stroke.from.x, stroke.from.y, stroke.to.x, stroke.to.y,
               scene.regions().size() == 1 ? "its region" : "its first region", first.name, first.rect.x, first.rect.y,
               first.rect.x + first.rect.w, first.rect.y + first.rect.h);
  }
  if (!result.reached) {
    fmt::print(stderr,
               "pseudohaptic: error: the stroke stopped after {} frames, the most a stroke may take, before its end "
               "point ({}): give a larger {}\n",
               result.frames,
               left_as_it_was ? o.output + " is left as it was" : std::string("the output holds it so far"),
               o.speed ? "--speed" : "--step");
    return 1;
  }
  return 0;
}

}  // namespace

Run add_trace_command(CLI::App& app) {
  auto o = std::make_shared<TraceOptions>();
  app.description(
      "Move the cursor along a straight stroke across a texture and write CSV, one row per texel step,\n"
      "with these columns in this order:\n"
      "frame,x,y,texel_x,texel_y,cos_alpha,delta_beta_deg,kmax,kmin,dh,cd,region\n"
      "(x, y: where the cursor entered the texel, screen px; cos_alpha, delta_beta_deg, kmax, kmin: curvature\n"
      "method; dh: depth method, the height change in px between the two heights its C/D is taken from\n"
      "(C/D = 1 + gain * dh / their distance in px, within [1/kmin, kmax]); empty where the other method\n"
      "gave the step; cd: the method's C/D, which materials and wells scale per frame on top).\n"
      "The last frame is shortened so that the cursor's travel along the stroke ends at --to. A summary\n"
      "(its C/D range with the effects), and a warning per map with invalid texels (repaired) or\n"
      "stretched out of proportion to its region, go to standard error.");
  auto* src = app.add_option_group("texture", "What to trace across (exactly one)");
  src->add_option("--scene", o->scene_file, "Scene file (TOML); the stroke defaults to the first region")
      ->check(non_empty_path());
  src->add_option("--target", o->target, "One of the 24 targets by name (e.g. bump-gaussian-h1-r200), exact fields")
      ->check(CLI::Validator(
          [](std::string& name) -> std::string {
            return name.empty() ? "is empty: give a target's name (see `pseudohaptic targets`)" : std::string();
          },
          ""));
  src->add_option("--normal-map", o->normal_map, "Normal map image (PNG, TIFF, EXR); region at (0,0), image size")
      ->check(non_empty_path());
  src->add_option("--depth-map", o->depth_map, "Depth map image (one channel); with --normal-map too, both are used")
      ->check(non_empty_path());
  add_map_flags(app, o->maps);
  std::vector<std::string> methods;
  const MethodRegistry registry = builtin_methods();
  for (const auto& entry : registry.entries()) {
    if (entry->name != FlatMethod::kName) methods.push_back(entry->name);  // a flat trace shows nothing
  }
  app.add_option(
         "--method", o->method,
         "C/D method for every region (default: the scene's; for maps, curvature, or depth for a depth map alone)")
      ->check(CLI::IsMember(methods));
  app.add_option("--kmax-prime", o->kmax_prime, "Curvature: k'max, largest C/D when delta-beta = 0 (default 4)");
  app.add_option("--kmin-prime", o->kmin_prime, "Curvature: k'min, 1 / smallest C/D when delta-beta = 0 (default 1.5)");
  add_number_tuple(app, "--kmax-limits", o->kmax_limits, "LO,HI", "Curvature: limits of kmax (default 1,30)",
                   {finite_number()});
  add_number_tuple(app, "--kmin-limits", o->kmin_limits, "LO,HI", "Curvature: limits of kmin (default 1,5)",
                   {finite_number()});
  app.add_option("--delta-beta-sign", o->delta_beta_sign,
                 "Curvature: 1 = Eq. 1 as printed (default), -1 = the paper's prose reading");
  app.add_option("--gain", o->gain, "Depth: C/D change per px of height change per px (default 3)");
  app.add_option("--depth-kmax", o->depth_kmax, "Depth: largest C/D (default 4)");
  app.add_option("--depth-kmin", o->depth_kmin, "Depth: 1 / smallest C/D (default 1.5)");
  add_number_tuple(app, "--from", o->from, "X,Y", "Start of the stroke, screen px (default: left edge, middle height)");
  add_number_tuple(app, "--to", o->to, "X,Y", "End of the stroke (default: right edge, middle height)");
  app.add_option("--step", o->step, "Motor travel per frame, px at C/D 1 (default 1)")->check(positive_number());
  app.add_option("--speed", o->speed, "Hand speed, px/s at C/D 1; the step is speed / rate")->check(positive_number());
  app.add_option("--rate", o->rate, "Frames per second with --speed")
      ->check(positive_number())
      ->each([o](const std::string&) { o->rate_given = true; })
      ->capture_default_str();
  app.add_option("-o,--output", o->output, "CSV file, - for standard output")
      ->check(non_empty_path())
      ->capture_default_str();
  return [o] { return run_trace(*o); };
}

}  // namespace ph::tools
