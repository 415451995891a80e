// Depth-based C/D ratio of Lécuyer et al. 2004, as the curvature paper describes it (docs/METHODS.md,
// "Depth-based C/D").
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "core/engine/fast_math.hpp"
#include "core/engine/field_sampling.hpp"
#include "core/engine/method.hpp"
#include "core/engine/method_registry.hpp"

namespace ph {

struct DepthParams {
  double gain = 3.0;  // C/D change per px of height change per px travelled
  double kmax = 4.0;  // largest C/D
  double kmin = 1.5;  // 1 / smallest C/D
};

std::string validate(const DepthParams& params);

// CD = clamp(1 + gain * dh / step, lowest, kmax), `lowest` the smallest C/D, 1 / kmin (a method divides once, not on
// every step). detail may be null.
PH_ALWAYS_INLINE inline double depth_cd(const DepthParams& p, double lowest, double h1, double h2, double step_px,
                                        StepDetail* detail) {
  const double dh = h2 - h1;
  const double slope = step_px > 0.0 ? dh / step_px : 0.0;
  double cd = std::clamp(1.0 + p.gain * slope, lowest, p.kmax);
  // Only for non-finite heights, which scenes never hold: between two finite bounds only NaN stays not finite.
  if (std::isnan(cd)) cd = 1.0;
  if (detail != nullptr) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    *detail = {nan, nan, nan, nan, dh};
  }
  return cd;
}

// The same with 1 / kmin worked out here.
PH_ALWAYS_INLINE inline double depth_cd(const DepthParams& p, double h1, double h2, double step_px,
                                        StepDetail* detail) {
  return depth_cd(p, 1.0 / p.kmin, h1, h2, step_px, detail);
}

class DepthMethod final : public Method {
 public:
  using Params = DepthParams;
  static constexpr std::string_view kName = "depth";
  static constexpr std::array<std::string_view, 3> kParamKeys = {"gain", "kmax", "kmin"};
  // The [region.depth] table; each value is checked where it is written.
  static DepthParams parse_params(const ParamReader& reader);

  explicit DepthMethod(const DepthParams& params);  // throws std::invalid_argument if invalid

  std::string_view name() const override { return kName; }
  FieldNeeds needs() const override { return {.gradient = false, .depth = true}; }
  // Inline: the traversal calls these directly on the final class (core/engine/traversal.cpp).
  //
  // The nearest reading of a texel for motion along `direction` m (Leg below): its height (v0) and the height change
  // per px along the motion (v1), from upwind differences: m_x times the change from the neighbour the
  // motion comes from along x, plus m_y times the change from the one along y (|m_x| (h - h[x - sx]) +
  // |m_y| (h - h[y - sy]), s the sign of m's component). It is exact on a plane, in any direction. The
  // neighbour a texel walk came from is always a 4-neighbour, so pairing the two texels instead would see,
  // on a diagonal, the height change per axis step and not per px along the motion (a mean slope of
  // (h_x + h_y)/2 instead of (h_x + h_y)/sqrt 2 at 45 degrees). Where a neighbour needed lies outside the
  // region, v1 is kNoBehind and cd() falls back to the texel the walk came from, which keeps the step at a
  // region's border.
  // What the nearest reading needs of one straight leg of the walk, worked out once per leg: the walk
  // then reads each texel with a few loads, two subtractions and two products.
  class Leg {
   public:
    Leg(const RegionFields* fields, Vec2 direction)
        : field_(fields != nullptr && fields->depth ? &*fields->depth : nullptr),
          ox_(-sign_of(direction.x)),
          oy_(-sign_of(direction.y)),
          row_(field_ != nullptr ? static_cast<std::ptrdiff_t>(oy_) * field_->width : 0),
          wx_(std::abs(direction.x)),
          wy_(std::abs(direction.y)),
          ahead_(field_ != nullptr ? bytes_ahead(direction, field_->width, sizeof(float)) : 0) {}

    // Where the texel lies in the field, for sample(FieldTexel).
    FieldTexel at(Texel local) const {
      return field_ != nullptr ? field_texel(local, field_->width, field_->height, ox_, oy_) : FieldTexel{};
    }
    PH_ALWAYS_INLINE TexelSample sample(Texel local) const { return sample(at(local)); }
    PH_ALWAYS_INLINE TexelSample sample(FieldTexel at) const {
      if (field_ == nullptr) return {0.0, kNoBehind};
      const float* texel = &field_->values[at.index];
      prefetch_ahead(texel, ahead_);
      const double here = *texel;
      if (!at.behind_inside) [[unlikely]]
        return {here, kNoBehind};
      // Differences first: a constant field gives exactly 0, so a flat region stays exactly C/D 1.
      return {here, wx_ * (here - texel[ox_]) + wy_ * (here - texel[row_])};
    }

   private:
    const DepthField* field_;
    std::int32_t ox_, oy_;  // offsets to the upwind neighbours; 0 along an axis the motion does not move along
    std::ptrdiff_t row_;    // offset to the upwind neighbour along y
    double wx_, wy_;        // |m_x|, |m_y|
    std::ptrdiff_t ahead_;  // bytes to the texel the walk reaches kRowsAhead rows ahead (prefetch_ahead)
  };
  Leg leg(const RegionFields* fields, Vec2 direction) const { return Leg(fields, direction); }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 direction) const override {
    return Leg(fields, direction).sample(local);
  }
  // The height interpolated at `at` (Sampling::bilinear); the walk pairs it with the previous sample point.
  TexelSample sample_at(const RegionFields* fields, Texel /*local*/, Vec2 at, Vec2 /*direction*/) const override {
    if (fields == nullptr || !fields->depth) return {0.0, kNoBehind};
    return {bilinear(*fields->depth, at), kNoBehind};
  }
  // The exact height at a point; cd() pairs it with the point the ground truth puts 1 px behind.
  TexelSample sample_exact(const SurfacePoint& point, Vec2 /*direction*/) const override {
    return {point.height, kNoBehind};
  }
  // Whether cd(from, to, ...) reads `from`: only where `to` has no upwind change of its own.
  static bool reads_from(const TexelSample& to) { return std::isnan(to.v1); }
  double cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const override {
    if (std::isnan(to.v1)) return depth_cd(params_, lowest_, from.v0, to.v0, step_px, detail);
    return depth_cd(params_, lowest_, 0.0, to.v1, 1.0, detail);  // the change along 1 px of the motion
  }
  double cd_lower_bound() const override { return lowest_; }
  double cd_upper_bound() const override { return params_.kmax; }
  const DepthParams& params() const { return params_; }

 private:
  // v1 of a sample whose upwind neighbours are not all in the region (a marker, never a height change:
  // heights are finite).
  static constexpr double kNoBehind = std::numeric_limits<double>::quiet_NaN();

  DepthParams params_;
  double lowest_;  // 1 / kmin, the smallest C/D
};

}  // namespace ph
