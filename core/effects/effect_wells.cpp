#include "core/effects/effect_wells.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/engine/fast_math.hpp"

namespace ph {

namespace {

// "" when lo <= v <= hi (NaN fails), else "wells <name> must be in [lo, hi] (got v)": the value too, since a bound
// may follow from another key (snap_px's from radius_px, snap_fraction's from min_gain).
std::string check_range(const char* name, double v, double lo, double hi) {
  if (v >= lo && v <= hi) return {};
  std::ostringstream s;
  s << "wells " << name << " must be in [" << lo << ", " << hi << "] (got " << v << ")";
  return s.str();
}

std::string validate_isophotes(const IsophoteParams& p) {
  const LightVector& l = p.light;
  const double len = light_length(l);
  if (!(std::isfinite(len) && len > 0.0)) return "wells isophote light must be a finite, non-zero vector";
  if (auto e = check_range("isophote cos_alpha", p.cos_alpha, -1.0, 1.0); !e.empty()) return e;
  if (!(std::isfinite(p.tol) && p.tol >= 0.0)) return "wells isophote tolerance must be a finite number >= 0";
  return {};
}

std::string validate_contours(const ContourParams& p) {
  if (p.count < 0 || p.count > kMaxContourLevels) return "wells contour count must be in [0, 4096]";
  if (p.levels.size() > static_cast<std::size_t>(kMaxContourLevels)) return "wells contour levels: at most 4096";
  for (double level : p.levels) {
    if (!std::isfinite(level)) return "wells contour levels must be finite";
  }
  if (!(std::isfinite(p.tol) && p.tol >= 0.0)) return "wells contour tolerance must be a finite number >= 0";
  return {};
}

// The falloff of the pull: 1 at the pattern, 0 at R, flat at both ends (smoothstep reversed).
double falloff(double s) { return 1.0 - s * s * (3.0 - 2.0 * s); }

}  // namespace

std::string validate(const WellsParams& p) {
  if (p.pattern != WellPattern::isophotes && p.pattern != WellPattern::contours) {
    return "wells pattern must be isophotes or contours";
  }
  if (auto e = validate_isophotes(p.isophotes); !e.empty()) return e;
  if (auto e = validate_contours(p.contours); !e.empty()) return e;
  if (auto e = check_range("radius_px", p.radius_px, kWellsMinRadiusPx, kWellsMaxRadiusPx); !e.empty()) return e;
  if (auto e = check_range("strength", p.strength, 0.0, kWellsMaxStrength); !e.empty()) return e;
  if (auto e = check_range("max_gain", p.max_gain, 1.0, kWellsMaxGainLimit); !e.empty()) return e;
  if (auto e = check_range("min_gain", p.min_gain, kWellsMinGainLimit, 1.0); !e.empty()) return e;
  if (auto e = check_range("snap_px", p.snap_px, 0.0, p.radius_px); !e.empty()) return e;
  // At most half of min_gain: a push straight away then still keeps min_gain / 2 of its travel.
  if (auto e = check_range("snap_fraction", p.snap_fraction, 0.0, p.min_gain / 2.0); !e.empty()) return e;
  return {};
}

FieldNeeds wells_needs(const WellsParams& params) {
  return {.gradient = params.pattern == WellPattern::isophotes, .depth = params.pattern == WellPattern::contours};
}

WellsEffect::WellsEffect(PatternField field, const WellsParams& params)
    : field_(std::move(field)), params_(params), min_gain_(params.min_gain), max_gain_(params.max_gain) {
  if (const std::string e = validate(params); !e.empty()) throw std::invalid_argument(e);
  if (params.snap_px > 0.0) {
    min_gain_ -= params.snap_fraction;
    max_gain_ += params.snap_fraction;
  }
}

Vec2 WellsEffect::apply(const EffectInput& in, EffectState& /*state*/) const {
  const std::optional<NearestPattern> nearest = field_.nearest(in.local);
  if (!nearest) return in.motor;
  // From the cursor, not its texel's centre: near the pattern the direction depends on where in the
  // texel the cursor is. (A position on the texel's far edge reads as its near edge: off by one px.)
  const double fx = in.position.x - std::floor(in.position.x);
  const double fy = in.position.y - std::floor(in.position.y);
  const double vx = nearest->dx + 0.5 - fx;
  const double vy = nearest->dy + 0.5 - fy;
  const double d = fast_length(vx, vy);
  // On the pattern the direction toward it is meaningless; beyond R the well does nothing.
  if (d < kWellsOnPatternPx || d >= params_.radius_px) return in.motor;
  const Vec2 u{vx / d, vy / d};
  const double len = fast_length(in.motor.x, in.motor.y);
  const double c = (in.motor.x / len) * u.x + (in.motor.y / len) * u.y;
  const double g =
      std::clamp(1.0 + params_.strength * c * falloff(d / params_.radius_px), params_.min_gain, params_.max_gain);
  Vec2 out = in.motor * g;
  if (d <= params_.snap_px) {
    // Toward the pattern texel's centre, never past it; bounded by the hand's own travel this frame.
    out = out + u * std::min(params_.snap_fraction * len, d);
  }
  return out;
}

EffectPtr make_wells_effect(const RegionFields& fields, std::int32_t width, std::int32_t height,
                            const WellsParams& params) {
  if (const std::string e = validate(params); !e.empty()) throw std::invalid_argument(e);
  // One more texel than R: the cursor can be up to 0.71 px from its texel's centre.
  const auto radius = static_cast<float>(params.radius_px + 1.0);
  if (params.pattern == WellPattern::isophotes) {
    if (!fields.gradient || fields.gradient->width != width || fields.gradient->height != height) {
      throw std::invalid_argument("isophote wells need the region's gradient field");
    }
    return std::make_shared<WellsEffect>(isophote_field(*fields.gradient, params.isophotes, radius), params);
  }
  if (!fields.depth || fields.depth->width != width || fields.depth->height != height) {
    throw std::invalid_argument("contour wells need the region's depth field (a depth map)");
  }
  return std::make_shared<WellsEffect>(contour_field(*fields.depth, params.contours, radius), params);
}

}  // namespace ph
