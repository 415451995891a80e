#include "core/effects/effect_materials.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/effects/curvature_field.hpp"
#include "core/engine/fast_math.hpp"

namespace ph {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Far beyond any hand (1e6 px/s is a screen width in 2 ms): only keeps the damping arithmetic finite.
constexpr double kMaxSpeedPxPerS = 1.0e6;
// A stick-slip frame skips whole periods at once, so its phase loop runs a few times; this only guards it.
constexpr int kMaxPhaseChanges = 16;

// The friction materials as one phase machine: stuck for `breakaway` motor px at stuck_cd, then slipping at
// slip_cd for `slip` motor px (infinite for plain friction), then stuck again.
struct Phases {
  double stuck_cd, breakaway, slip_cd, slip, rest_us;
};

Phases phases_of(const FrictionParams& p) { return {p.stuck_cd, p.breakaway_px, p.slip_cd, kInf, p.rest_ms * 1e3}; }
Phases phases_of(const StickSlipParams& p) {
  return {p.stuck_cd, p.breakaway_px, p.slip_cd, p.slip_px, p.rest_ms * 1e3};
}

// Microseconds from the previous moving frame to this one, or -1 when unknown: no time on either, or a time that
// is not later (a replay that jumped back, or two frames at one time). Never negative otherwise, never NaN.
double gap_us(TimeUs time, TimeUs last) {
  if (time == kNoTime || last == kNoTime) return -1.0;
  const double gap = static_cast<double>(time) - static_cast<double>(last);  // in double: no overflow
  return gap > 0.0 ? gap : -1.0;
}

double damping_cd(const DampingParams& p, double length, double gap) {
  const double interval_s = gap > 0.0 ? gap * 1e-6 : p.fallback_interval_ms * 1e-3;
  if (!(interval_s > 0.0)) return 1.0;  // speed unknown and no fallback: no damping
  const double speed = std::min(length / interval_s, kMaxSpeedPxPerS);
  return std::clamp(1.0 + p.k * speed, 1.0, p.cd_max);
}

// Walks `length` motor px through the phases from the state's phase; returns the display length it gives.
double walk_phases(const Phases& p, EffectState& state, double length) {
  double display = 0.0;
  for (int changes = 0; length > 0.0; ++changes) {
    const double cd = state.stuck ? p.stuck_cd : p.slip_cd;
    if (changes >= kMaxPhaseChanges) return display + length / cd;
    if (state.stuck && state.travel_px == 0.0 && p.slip < kInf) {
      // At the start of a period: whole periods at once, so a long frame costs no more than a short one.
      const double period = p.breakaway + p.slip;
      const double periods = std::floor(length / period);
      if (periods > 0.0) {
        display += periods * (p.breakaway / p.stuck_cd + p.slip / p.slip_cd);
        length = std::max(length - periods * period, 0.0);
        continue;
      }
    }
    const double left = std::max((state.stuck ? p.breakaway : p.slip) - state.travel_px, 0.0);
    if (length < left) {
      display += length / cd;
      state.travel_px += length;
      return display;
    }
    display += left / cd;
    length -= left;
    state.stuck = !state.stuck;
    state.travel_px = 0.0;
  }
  return display;
}

template <typename T>
bool within(T v, T lo, T hi) {
  return v >= lo && v <= hi;  // false for NaN
}

// Appends "name = v is outside [lo, hi]" to the message when v is.
class Checker {
 public:
  void range(const char* name, double v, double lo, double hi) {
    if (!message_.empty() || within(v, lo, hi)) return;
    std::ostringstream s;
    s << name << " = " << v << " is outside [" << lo << ", " << hi << "]";
    message_ = s.str();
  }
  void fail(const std::string& message) {
    if (message_.empty()) message_ = message;
  }
  std::string message() const { return message_; }

 private:
  std::string message_;
};

}  // namespace

const char* material_name(Material m) {
  switch (m) {
    case Material::none:
      return "none";
    case Material::damping:
      return "damping";
    case Material::friction:
      return "friction";
    case Material::stick_slip:
      return "stick_slip";
  }
  return "unknown";
}

std::optional<Material> parse_material(std::string_view name) {
  for (Material m : {Material::none, Material::damping, Material::friction, Material::stick_slip}) {
    if (name == material_name(m)) return m;
  }
  return std::nullopt;
}

const char* class_source_name(ClassSource s) {
  switch (s) {
    case ClassSource::automatic:
      return "auto";
    case ClassSource::normals:
      return "normals";
    case ClassSource::depth:
      return "depth";
  }
  return "unknown";
}

std::optional<ClassSource> parse_class_source(std::string_view name) {
  for (ClassSource s : {ClassSource::automatic, ClassSource::normals, ClassSource::depth}) {
    if (name == class_source_name(s)) return s;
  }
  return std::nullopt;
}

std::string validate(const MaterialsParams& p) {
  Checker c;
  if (!within(static_cast<int>(p.source), 0, 2)) c.fail("source must be auto, normals or depth");
  if (p.filter_radius != 0 && !within(p.filter_radius, 1, 64)) {
    c.fail("filter_radius = " + std::to_string(p.filter_radius) + " is outside 0 (default) or [1, 64]");
  }
  if (p.planar_curvedness) c.range("planar_curvedness", *p.planar_curvedness, 0.0, 1.0);
  if (p.parabolic_ratio) c.range("parabolic_ratio", *p.parabolic_ratio, 0.0, 1.0);
  for (Material m : p.materials) {
    if (!within(static_cast<int>(m), 0, 3)) c.fail("materials must be none, damping, friction or stick_slip");
  }
  c.range("damping.k", p.damping.k, 0.0, 1.0);
  c.range("damping.cd_max", p.damping.cd_max, 1.0, 20.0);
  c.range("damping.fallback_interval_ms", p.damping.fallback_interval_ms, 0.0, 100.0);
  c.range("friction.stuck_cd", p.friction.stuck_cd, 1.0, 20.0);
  c.range("friction.breakaway_px", p.friction.breakaway_px, 0.1, 500.0);
  c.range("friction.slip_cd", p.friction.slip_cd, 1.0, 20.0);
  c.range("friction.rest_ms", p.friction.rest_ms, 1.0, 10000.0);
  c.range("stick_slip.stuck_cd", p.stick_slip.stuck_cd, 1.0, 20.0);
  c.range("stick_slip.breakaway_px", p.stick_slip.breakaway_px, 0.1, 500.0);
  c.range("stick_slip.slip_cd", p.stick_slip.slip_cd, 1.0, 20.0);
  c.range("stick_slip.slip_px", p.stick_slip.slip_px, 0.1, 500.0);
  c.range("stick_slip.rest_ms", p.stick_slip.rest_ms, 1.0, 10000.0);
  return c.message();
}

FieldNeeds materials_needs(const MaterialsParams& params, bool has_normals, bool has_depth) {
  switch (params.source) {
    case ClassSource::normals:
      return {true, false};
    case ClassSource::depth:
      return {false, true};
    case ClassSource::automatic:
      break;
  }
  if (has_normals || !has_depth) return {true, false};  // with neither, say what is preferred
  return {false, true};
}

MaterialsEffect::MaterialsEffect(Grid<std::uint8_t> classes, const MaterialsParams& params)
    : classes_(std::move(classes)), params_(params) {
  if (const std::string error = validate(params); !error.empty()) throw std::invalid_argument("materials: " + error);
  classes_.values.shrink_to_fit();
  // The C/D range over the materials in use: every frame's C/D is a weighted harmonic mean of these.
  cd_low_ = kInf;
  cd_high_ = -kInf;
  auto include = [&](double lo, double hi) {
    cd_low_ = std::min(cd_low_, lo);
    cd_high_ = std::max(cd_high_, hi);
  };
  for (Material m : params_.materials) {
    switch (m) {
      case Material::none:
        include(1.0, 1.0);
        break;
      case Material::damping:
        include(1.0, params_.damping.cd_max);
        break;
      case Material::friction:
        include(std::min(params_.friction.stuck_cd, params_.friction.slip_cd),
                std::max(params_.friction.stuck_cd, params_.friction.slip_cd));
        break;
      case Material::stick_slip:
        include(std::min(params_.stick_slip.stuck_cd, params_.stick_slip.slip_cd),
                std::max(params_.stick_slip.stuck_cd, params_.stick_slip.slip_cd));
        break;
    }
  }
}

Vec2 MaterialsEffect::apply(const EffectInput& in, EffectState& state) const {
  CurvatureClass cls = CurvatureClass::planar;
  if (in.local.x >= 0 && in.local.y >= 0 && in.local.x < classes_.width && in.local.y < classes_.height) {
    const std::uint8_t v = classes_.at(in.local.x, in.local.y);
    if (v <= static_cast<std::uint8_t>(CurvatureClass::hyperbolic)) cls = static_cast<CurvatureClass>(v);
  }
  const double gap = gap_us(in.time, state.last_motion);
  state.last_motion = in.time;
  const double length = fast_length(in.motor.x, in.motor.y);
  const Material material = params_.material(cls);
  if (material == Material::none || material == Material::damping || !(length > 0.0) || !std::isfinite(length)) {
    // Off the friction materials the next friction texel is a fresh contact: it sticks first.
    state.stuck = true;
    state.travel_px = 0.0;
    if (material != Material::damping || !(length > 0.0) || !std::isfinite(length)) return in.motor;
    const double cd = damping_cd(params_.damping, length, gap);
    return cd == 1.0 ? in.motor : Vec2{in.motor.x / cd, in.motor.y / cd};
  }
  const Phases phases = material == Material::friction ? phases_of(params_.friction) : phases_of(params_.stick_slip);
  if (gap >= phases.rest_us) {
    state.stuck = true;  // the hand rested: static friction holds it again
    state.travel_px = 0.0;
  }
  const double display = walk_phases(phases, state, length);
  // display / length is a weighted harmonic mean of the phases' 1/C/D; clamp away the rounding.
  const double cd = std::clamp(length / display, cd_low_, cd_high_);
  return {in.motor.x / cd, in.motor.y / cd};
}

Grid<std::uint8_t> materials_class_map(const RegionFields& fields, std::int32_t width, std::int32_t height,
                                       const MaterialsParams& params, int bit_depth) {
  if (const std::string error = validate(params); !error.empty()) throw std::invalid_argument("materials: " + error);
  const FieldNeeds needs = materials_needs(params, fields.gradient.has_value(), fields.depth.has_value());
  const bool from_depth = needs.depth;
  auto fits = [&](const auto& grid) {
    return grid && grid->width == width && grid->height == height &&
           grid->values.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  };
  if (from_depth ? !fits(fields.depth) : !fits(fields.gradient)) {
    throw std::invalid_argument(std::string("materials: the classes need ") +
                                (from_depth ? "a depth field" : "normals") + " matching the region's size");
  }
  const DerivativeFilter filter = params.filter_radius > 0 ? DerivativeFilter{params.filter_radius}
                                                           : DerivativeFilter::recommended(from_depth, bit_depth);
  ClassTolerances tolerances = ClassTolerances::recommended(bit_depth);
  if (params.planar_curvedness) tolerances.planar_curvedness = *params.planar_curvedness;
  if (params.parabolic_ratio) tolerances.parabolic_ratio = *params.parabolic_ratio;
  return from_depth ? class_map_from_depth(*fields.depth, filter, tolerances)
                    : class_map_from_gradient(*fields.gradient, filter, tolerances);
}

EffectPtr make_materials_effect(const RegionFields& fields, std::int32_t width, std::int32_t height,
                                const MaterialsParams& params, int bit_depth) {
  return std::make_shared<MaterialsEffect>(materials_class_map(fields, width, height, params, bit_depth), params);
}

}  // namespace ph
