// Curvature-based C/D ratio of Argelaguet et al. 2012, Eq. 1-3 (docs/METHODS.md, "Projection into the
// plane of motion" and "Curvature-based C/D").
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/engine/fast_math.hpp"
#include "core/engine/field_sampling.hpp"
#include "core/engine/method.hpp"
#include "core/engine/method_registry.hpp"
#include "core/engine/pair_math.hpp"

namespace ph {

struct CurvatureParams {
  double kmax_prime = 4.0;  // k'max: largest C/D (uphill) when delta-beta = 0
  double kmin_prime = 1.5;  // k'min: 1 / smallest C/D (downhill) when delta-beta = 0
  double kmax_lo = 1.0, kmax_hi = 30.0;
  double kmin_lo = 1.0, kmin_hi = 5.0;
  double delta_beta_sign = 1.0;  // +1: Eq. 1 as printed (= theta1 - theta2); -1: the paper's prose reading
};

// Empty when valid; otherwise what is wrong, naming the parameter.
std::string validate(const CurvatureParams& params);

// n''_x (docs/METHODS.md, "Projection into the plane of motion") for a unit normal and a unit direction:
// s / sqrt(s^2 + n_z^2).
double projected_normal_x(Normal n, Vec2 direction);

// Slope angle along a direction, positive uphill: atan(g . m).
double slope_angle(Gradient g, Vec2 direction);

// Eq. 1-3 from the two projected values a1 = n''_x(p1), a2 = n''_x(p2) and the difference of the slope angles
// theta1 - theta2, theta = asin(-a) (passed to avoid recomputing acos). detail may be null.
PH_ALWAYS_INLINE inline double curvature_cd_of_change(const CurvatureParams& p, double a1, double a2,
                                                      double theta1_minus_theta2, StepDetail* detail) {
  // Eq. 1: cos(alpha) is the mean of the projected normals; delta-beta = acos(a1) - acos(a2) = theta1 - theta2.
  const double cos_alpha = 0.5 * (a1 + a2);
  // One product on the step's chain: the sign is exactly +-1, so this is (sign * change) * 180/pi to the bit.
  const double delta_beta = theta1_minus_theta2 * (p.delta_beta_sign * (180.0 / std::numbers::pi));
  // Eq. 3 with the limits that keep Eq. 2 meaningful (k >= 1); each worked out only where Eq. 2 reads it.
  auto kmax = [&] { return std::clamp(p.kmax_prime * (1.0 + delta_beta), p.kmax_lo, p.kmax_hi); };
  auto kmin = [&] { return std::clamp(p.kmin_prime * (1.0 - delta_beta), p.kmin_lo, p.kmin_hi); };
  // Eq. 2: cos(alpha) < 0 is uphill (the projected normal leans against the motion).
  double cd = 1.0;
  if (cos_alpha > 0.0) {
    cd = 1.0 - cos_alpha * (1.0 - 1.0 / kmin());
  } else if (cos_alpha < 0.0) {
    cd = 1.0 - cos_alpha * (kmax() - 1.0);
  }
  if (detail != nullptr) *detail = {cos_alpha, delta_beta, kmax(), kmin(), std::numeric_limits<double>::quiet_NaN()};
  return cd;
}

// The same from the two slope angles theta1, theta2.
inline double curvature_cd(const CurvatureParams& p, double a1, double theta1, double a2, double theta2,
                           StepDetail* detail) {
  return curvature_cd_of_change(p, a1, a2, theta1 - theta2, detail);
}

// atan(t1) - atan(t2) with one arctangent: atan((t1 - t2) / (1 + t1 t2)), plus or minus pi where the denominator
// is negative (slopes of opposite sign, both steeper than 45 degrees: an apex or a gully), to fast_atan's
// accuracy. Equal slopes give exactly 0.
PH_ALWAYS_INLINE inline double slope_angle_change(double t1, double t2) {
  const double num = t1 - t2, den = 1.0 + t1 * t2;
  if (den > 0.0) [[likely]]
    return fast_atan(num / den);
  if (den < 0.0) return fast_atan(num / den) + std::copysign(std::numbers::pi, num);
  return std::copysign(std::numbers::pi / 2, num);
}

class CurvatureMethod final : public Method {
 public:
  using Params = CurvatureParams;
  static constexpr std::string_view kName = "curvature";
  static constexpr std::array<std::string_view, 5> kParamKeys = {"kmax_prime", "kmin_prime", "kmax_limits",
                                                                 "kmin_limits", "delta_beta_sign"};
  // The [region.curvature] table; each value is checked where it is written.
  static CurvatureParams parse_params(const ParamReader& reader);

  explicit CurvatureMethod(const CurvatureParams& params);  // throws std::invalid_argument if invalid

  std::string_view name() const override { return kName; }
  FieldNeeds needs() const override { return {.gradient = true, .depth = false}; }
  // Inline: the traversal calls these directly on the final class (core/engine/traversal.cpp).
  //
  // The nearest reading of a texel for motion along m is a pair of projected normals 1 px apart along the
  // motion: the texel's own and that of the point 1 px behind its centre, the gradient there interpolated
  // bilinearly from the texel and its neighbours behind along x, along y and diagonally (weights from |m_x|
  // and |m_y|). Pairing a texel with the 4-neighbour the walk came from instead alternates, on a diagonal,
  // between an x and a y neighbour, and the C/D swings texel by texel on a smooth surface (docs/METHODS.md,
  // "Which two normals"). The sample: v0 = a and v1 = t (the slope along m) of the texel, v2 = a behind and
  // v3 = theta behind - theta here. Where a neighbour needed lies outside the region, v2 is kNoBehind and
  // cd() pairs the texel the walk came from, which keeps the step at a region's border.
  // What the nearest reading needs of one straight leg of the walk, worked out once per leg (the offsets
  // to the neighbours behind and the bilinear weights of the point 1 px behind): the walk then reads each
  // texel with four gradient loads and the arithmetic of the slopes.
  class Leg {
   public:
    Leg(const RegionFields* fields, Vec2 m)
        : field_(fields != nullptr && fields->gradient ? &*fields->gradient : nullptr),
          m_(m),
          mx_(splat(m.x)),
          my_(splat(m.y)),
          ox_(-sign_of(m.x)),
          oy_(-sign_of(m.y)),
          row_(field_ != nullptr ? static_cast<std::ptrdiff_t>(oy_) * field_->width : 0),
          w_x_(std::abs(m.x) * (1.0 - std::abs(m.y))),
          w_y_((1.0 - std::abs(m.x)) * std::abs(m.y)),
          w_xy_(std::abs(m.x) * std::abs(m.y)),
          ahead_(field_ != nullptr ? bytes_ahead(m, field_->width, sizeof(Gradient)) : 0) {}

    // Where the texel lies in the field, for sample(FieldTexel).
    FieldTexel at(Texel local) const {
      return field_ != nullptr ? field_texel(local, field_->width, field_->height, ox_, oy_) : FieldTexel{};
    }
    PH_ALWAYS_INLINE TexelSample sample(Texel local) const { return sample(at(local)); }
    PH_ALWAYS_INLINE TexelSample sample(FieldTexel at) const {
      if (field_ == nullptr) return {0.0, 0.0, 0.0, 0.0};
      const Gradient* texel = &field_->values[at.index];
      prefetch_ahead(texel, ahead_);
      if (!at.behind_inside) [[unlikely]] {
        const double t = slope_along(texel[0], m_);
        return {projected(t), t, kNoBehind, kNoBehind};
      }
      // The four slopes two at a time: the texel's and its x-neighbour's, the y-neighbour's and the diagonal's.
      const Double2 here_x = slopes_along(texel, texel + ox_, mx_, my_);
      const Double2 y_diagonal = slopes_along(texel + row_, texel + row_ + ox_, mx_, my_);
      const double t = here_x[0];
      // Differences first: a constant field gives exactly t behind, so a plane keeps delta-beta exactly 0.
      const double tb = t + w_x_ * (here_x[1] - t) + w_y_ * (y_diagonal[0] - t) + w_xy_ * (y_diagonal[1] - t);
      // Both projections at once: one square root and one division for the two.
      const Double2 slopes{t, tb};
      const Double2 a = -slopes / sqrt2(kOnes + slopes * slopes);
      return {a[0], t, a[1], slope_angle_change(tb, t)};
    }

   private:
    const GradientField* field_;
    Vec2 m_;
    Double2 mx_, my_;          // m.x and m.y in both lanes (slopes_along)
    std::int32_t ox_, oy_;     // offsets to the neighbours behind; 0 along an axis the motion does not move along
    std::ptrdiff_t row_;       // offset to the neighbour behind along y
    double w_x_, w_y_, w_xy_;  // bilinear weights of the neighbours behind along x, along y, diagonally
    std::ptrdiff_t ahead_;     // bytes to the texel the walk reaches kRowsAhead rows ahead (prefetch_ahead)
  };
  Leg leg(const RegionFields* fields, Vec2 m) const { return Leg(fields, m); }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 m) const override {
    return Leg(fields, m).sample(local);
  }
  // The same from the gradient interpolated at `at` (Sampling::bilinear); the walk pairs it with the previous
  // sample point.
  TexelSample sample_at(const RegionFields* fields, Texel /*local*/, Vec2 at, Vec2 m) const override {
    if (fields == nullptr || !fields->gradient) return {0.0, 0.0, 0.0, 0.0};
    const Vec2 g = bilinear(*fields->gradient, at);
    const double t = g.x * m.x + g.y * m.y;
    return {projected(t), t, kNoBehind, kNoBehind};
  }
  // The same from the exact gradient; cd() pairs it with the point the ground truth puts 1 px behind, with the
  // exact atan (the ground truth must not share fast_atan), which v3 = kExactAngles asks for.
  TexelSample sample_exact(const SurfacePoint& point, Vec2 m) const override {
    const double t = point.gradient.x * m.x + point.gradient.y * m.y;
    return {projected(t), t, kNoBehind, kExactAngles};
  }
  // Whether cd(from, to, ...) reads `from`: only where `to` has no point behind of its own.
  static bool reads_from(const TexelSample& to) { return std::isnan(to.v2); }
#if defined(__GNUC__)
  [[gnu::always_inline]]  // once per texel step in the walk, like sample()
#endif
  double
  cd(const TexelSample& from, const TexelSample& to, double /*step_px*/, StepDetail* detail) const override {
    if (!std::isnan(to.v2)) [[likely]]
      return curvature_cd_of_change(params_, to.v2, to.v0, to.v3, detail);
    // The pair of the texel the walk came from and this one (a region's border, bilinear sampling, the truth).
    const double change =
        std::isinf(to.v3) ? std::atan(from.v1) - std::atan(to.v1) : slope_angle_change(from.v1, to.v1);
    return curvature_cd_of_change(params_, from.v0, to.v0, change, detail);
  }
  double cd_lower_bound() const override { return 1.0 / params_.kmin_hi; }
  double cd_upper_bound() const override { return params_.kmax_hi; }
  const CurvatureParams& params() const { return params_; }

 private:
  // v2 of a sample with no point behind of its own (a marker, never a projected normal: those are finite).
  static constexpr double kNoBehind = std::numeric_limits<double>::quiet_NaN();

  // v3 of a sample_exact(): cd() takes the angles with the exact atan.
  static constexpr double kExactAngles = std::numeric_limits<double>::infinity();

  PH_ALWAYS_INLINE static double slope_along(Gradient g, Vec2 m) {
    return static_cast<double>(g.x) * m.x + static_cast<double>(g.y) * m.y;
  }
  // n''_x of the slope t along the motion (docs/METHODS.md, "Projection into the plane of motion").
  PH_ALWAYS_INLINE static double projected(double t) { return -t / std::sqrt(1.0 + t * t); }

  CurvatureParams params_;
};

}  // namespace ph
