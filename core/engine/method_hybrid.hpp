// The hybrid of the curvature and depth methods that the curvature paper proposes for its method's two failure
// modes (docs/METHODS.md, "Hybrid"): where the height changes across a texel edge by more than the normals
// explain (a discontinuity, which a normal map cannot show), the depth method's C/D; elsewhere the curvature
// method's, on normals fused with the depth map's slopes where they are noisier than it, and smoothed where their
// differences are within the map's noise, more so further from the viewer. Everything is derived once at load
// (prepare); a step costs the curvature method's plus one byte read.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "core/engine/method.hpp"
#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_registry.hpp"

namespace ph {

struct HybridParams {
  // Height change across a texel edge, beyond what the normals on its two sides explain, that makes the edge a
  // discontinuity (px).
  double discontinuity_px = 0.5;
  // A texel's gradient is replaced by the smoothed one where they differ by at most this (per component, px
  // per px; less where the map shows less noise, as a float map does): about one code of an 8-bit normal map at
  // a flat texel (2/255 = 0.0078). Normals that disagree with the depth map's slopes by more noise than this
  // are first pulled toward them (method_hybrid.cpp, fuse_with_depth_gradient). 0: no smoothing and no fusion.
  double noise_slope = 0.01;
  // How much wider that band is at the region's lowest height than at its highest (the paper: smooth more
  // further from the viewer); 0: the same everywhere.
  double far_noise_gain = 1.0;
};

std::string validate(const HybridParams& params);

// Marks the discontinuities (and the flat texels beside a step whose normals a generator smeared), pulls noisy normals
// toward the depth map's slopes where the two disagree by noise-like amounts (not at a step), then smooths
// `fields.gradient` within the noise band, as HybridMethod::prepare does (exposed for tests). Without a depth field no
// texel is a discontinuity, nothing is fused and the band is the same everywhere.
void prepare_hybrid_fields(const HybridParams& params, RegionFields& fields);

class HybridMethod final : public Method {
 public:
  using Params = HybridParams;
  static constexpr std::string_view kName = "hybrid";
  static constexpr std::array<std::string_view, 3> kParamKeys = {"discontinuity_px", "noise_slope", "far_noise_gain"};
  static HybridParams parse_params(const ParamReader& reader);

  explicit HybridMethod(const HybridParams& params);  // throws std::invalid_argument if invalid

  std::string_view name() const override { return kName; }
  // Heights where a depth map is given (a normal map alone: no discontinuity can be found, since heights
  // integrated from the normals would be explained by them everywhere).
  FieldNeeds needs() const override { return {.gradient = true, .depth = false, .depth_if_given = true}; }
  void prepare(RegionFields& fields) const override;

  // Curvature's sample (v0-v3) of the smoothed normals; on a discontinuity texel, depth's (v4, v5) with v2 =
  // kDepthStep. Like its parents, what a straight leg of the walk needs is worked out once per leg: the
  // parents' legs and where the discontinuity marks are. Inline: the traversal calls these directly on the
  // final class.
  class Leg {
   public:
    Leg(const RegionFields* fields, Vec2 m)
        : curvature_(fields, m),
          depth_(fields, m),
          marks_(fields != nullptr && fields->discontinuity && fields->depth ? &*fields->discontinuity : nullptr) {}

    // The curvature reading's: every field of the region has its size, and the neighbours behind are the same.
    PH_ALWAYS_INLINE TexelSample sample(Texel local) const { return sample(curvature_.at(local)); }
    // Every field of a region has the region's size, so one index serves the marks, the depths and the gradients.
    PH_ALWAYS_INLINE TexelSample sample(FieldTexel at) const {
      if (marks_ != nullptr && marks_->values[at.index]) [[unlikely]] {
        const TexelSample d = depth_.sample(at);
        if (!std::isnan(d.v1)) return {0.0, 0.0, kDepthStep, 0.0, d.v0, d.v1};
      }
      return curvature_.sample(at);
    }

   private:
    CurvatureMethod::Leg curvature_;
    DepthMethod::Leg depth_;
    const DiscontinuityField* marks_;  // null: no depth field, so no texel is a discontinuity
  };
  Leg leg(const RegionFields* fields, Vec2 m) const { return Leg(fields, m); }
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 m) const override {
    return Leg(fields, m).sample(local);
  }
  // Bilinear sampling: curvature's interpolated sample, and on a discontinuity texel depth's reading as above (its
  // v0 and v1 flat, so that the next texel, which pairs with this sample, does not pair with a step's smeared normals).
  TexelSample sample_at(const RegionFields* fields, Texel local, Vec2 at, Vec2 m) const override {
    if (fields != nullptr && fields->discontinuity && fields->depth && marked(*fields->discontinuity, local)) {
      const TexelSample d = depth_.sample(fields, local, m);
      if (!std::isnan(d.v1)) return {0.0, 0.0, kDepthStep, 0.0, d.v0, d.v1};
    }
    return curvature_.sample_at(fields, local, at, m);
  }
  // The analytic surfaces of the ground truth are continuous: the curvature method's exact sample.
  TexelSample sample_exact(const SurfacePoint& point, Vec2 m) const override {
    return curvature_.sample_exact(point, m);
  }
  // Whether cd(from, to, ...) reads `from`: as the curvature method, never on a discontinuity texel.
  static bool reads_from(const TexelSample& to) { return to.v2 != kDepthStep && CurvatureMethod::reads_from(to); }
#if defined(__GNUC__)
  [[gnu::always_inline]]
#endif
  double
  cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const override {
    if (to.v2 == kDepthStep) [[unlikely]]
      return depth_cd(depth_.params(), 0.0, to.v5, 1.0, detail);
    return curvature_.cd(from, to, step_px, detail);
  }
  double cd_lower_bound() const override { return std::min(curvature_.cd_lower_bound(), depth_.cd_lower_bound()); }
  double cd_upper_bound() const override { return std::max(curvature_.cd_upper_bound(), depth_.cd_upper_bound()); }
  const HybridParams& params() const { return params_; }

 private:
  static bool marked(const DiscontinuityField& marks, Texel t) {
    return t.x >= 0 && t.y >= 0 && t.x < marks.width && t.y < marks.height && marks.at(t.x, t.y) != 0;
  }

  // v2 of a discontinuity texel's sample (curvature's v2 is finite or NaN, never infinite).
  static constexpr double kDepthStep = std::numeric_limits<double>::infinity();

  HybridParams params_;
  CurvatureMethod curvature_{CurvatureParams{}};
  DepthMethod depth_{DepthParams{}};
};

}  // namespace ph
