// The hybrid of the curvature and depth methods that the curvature paper proposes for its method's two failure
// modes (docs/METHODS.md, "Hybrid"): where the height changes across a texel edge by more than the normals
// explain (a discontinuity, which a normal map cannot show), the depth method's C/D; elsewhere the curvature
// method's, on normals read again from the heights where a generator made them from heights stored finer, fused
// with the depth map's slopes where they are noisier than it, and smoothed where their differences are within the
// map's noise, more so further from the viewer. Everything is derived once at load
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
  // are first pulled toward them (method_hybrid.cpp, fuse_with_depth_gradient). 0: the normals as given (no
  // smoothing, no fusion, no reading again from the heights).
  double noise_slope = 0.01;
  // How much wider that band is at the region's lowest height than at its highest (the paper: smooth more
  // further from the viewer); 0: the same everywhere.
  double far_noise_gain = 1.0;
};

std::string validate(const HybridParams& params);

// Reads a generator's normals again from heights stored finer than they are (and lowers `fields.gradient_rounding` to
// what is left), marks the discontinuities (and the flat texels beside a step whose normals a generator smeared),
// pulls noisy normals toward the depth map's slopes where the two disagree by noise-like amounts (not at a step), then
// smooths `fields.gradient` within the noise band, as HybridMethod::prepare does (exposed for tests). Without a depth
// field no texel is a discontinuity, nothing is read again or fused and the band is the same everywhere.
void prepare_hybrid_fields(const HybridParams& params, RegionFields& fields);

// Two passes of the binomial kernel [1 2 1] / 4 along x and y, the border texels repeated (a Gaussian of about 1 px):
// the hybrid's smoothing, in bands of rows on `threads` threads (0: one per core, at most kMaxRowBandThreads; bands of
// kMinRowBandRows rows at least), the same values as in one band.
GradientField binomial_smoothed(const GradientField& g, unsigned threads = 0);

// Marks both texels of every edge across which the height in `d` changes by more than `threshold` beyond what the
// normals `g` explain (all of it between level treads, where the change exceeds 1.5 `depth_step`, one step of the depth
// map's storage), keeps it changed (no opposite change beside it takes it back) and lies in relief the texels resolve:
// the hybrid's step test (docs/METHODS.md, "Hybrid"). Worked out in bands of rows on `threads` threads (0: one per
// core, at most kMaxRowBandThreads; bands of kMinRowBandRows rows at least), the same marks as in one band.
DiscontinuityField find_discontinuities(const GradientField& g, const DepthField& d, double threshold,
                                        double depth_step, unsigned threads = 0);

// How the normals' slopes `g` compare with the depth map's, `from_depth` its central differences. A slope along an
// axis is resolved where it exceeds `floor` and changes along the axis by a second difference within a fifth of it (no
// kink, no relief near the texel period).
// - ratio: the median of the normal's slope over the difference, over the slopes along each axis that both resolve,
//   of one sign, where neither the texel nor its two neighbours on that axis is in `marks` (a step, where the two
//   disagree by design). 1 where the two maps hold the relief at one scale (within a few per cent; a generator's
//   smoothing of the finest detail makes it a little less); a depth map whose `relief_px` is not the normal map's
//   scale shows as its ratio. Where the marks leave fewer than 100, over the marked ones too: at a scale so far off
//   that nearly every texel reads as a step.
// - opposite_x, opposite_y, depth_flat: the shares SlopeComparison describes, marks or not (a sign or a scale that is
//   wrong makes every texel a step).
// Read on every k-th row of a region over 2^17 texels; each figure is empty where it rests on fewer than 100 slopes.
SlopeComparison compare_slopes_with_depth(const GradientField& g, const GradientField& from_depth,
                                          const DiscontinuityField& marks, double floor);

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
          marks_(fields != nullptr && fields->discontinuity && fields->depth ? &*fields->discontinuity : nullptr),
          heights_(fields != nullptr && fields->depth && fields->gradient ? fields : nullptr) {}

    // The curvature reading's: every field of the region has its size, and the neighbours behind are the same.
    FieldTexel at(Texel local) const { return curvature_.at(local); }
    // The region's fields where a texel's height can be read (both a depth and a gradient field), else null.
    const RegionFields* heights() const { return heights_; }
    PH_ALWAYS_INLINE TexelSample sample(Texel local) const { return sample(at(local)); }
    // Every field of a region has the region's size, so one index serves the marks, the depths and the gradients.
    PH_ALWAYS_INLINE TexelSample sample(FieldTexel at) const {
      if (marks_ != nullptr && marks_->values[at.index]) [[unlikely]] {
        const TexelSample d = depth_.sample(at);
        if (!std::isnan(d.v1)) return {0.0, 0.0, kDepthStep, 0.0, d.v0, d.v1};
      }
      TexelSample s = curvature_.sample(at);
      if (CurvatureMethod::reads_from(s)) [[unlikely]]  // a region's border: cd() looks for a step across it
        with_height(s, heights_, at.index);
      return s;
    }

   private:
    CurvatureMethod::Leg curvature_;
    DepthMethod::Leg depth_;
    const DiscontinuityField* marks_;  // null: no depth field, so no texel is a discontinuity
    const RegionFields* heights_;      // null: no depth field, so no step at the region's border can be found
  };
  Leg leg(const RegionFields* fields, Vec2 m) const { return Leg(fields, m); }
  // Here, and where the walk reads the texel it came from in another region, the sample carries the height (v4) and
  // the steepest slope (v5) there: with_height. Outside every region it carries none: the desktop has no depth map.
  TexelSample sample(const RegionFields* fields, Texel local, Vec2 m) const override {
    const Leg leg(fields, m);
    const FieldTexel at = leg.at(local);
    TexelSample s = leg.sample(at);
    if (fields == nullptr) return without_height(s);
    // A mark carries its own height, and the leg gave a texel at the region's border its height already.
    if (s.v2 == kDepthStep || CurvatureMethod::reads_from(s)) return s;
    with_height(s, leg.heights(), at.index);
    return s;
  }
  // Bilinear sampling: curvature's interpolated sample, and on a discontinuity texel depth's reading as above (its
  // v0 and v1 flat, so that the next texel, which pairs with this sample, does not pair with a step's smeared normals).
  // The walk pairs every sample with the one before it, so each carries its texel's height, and one whose neighbour
  // behind lies inside the region says so (v3 = kInsideRegion): cd() looks for a step between regions only where the
  // walk enters one, as with the nearest reading.
  TexelSample sample_at(const RegionFields* fields, Texel local, Vec2 at, Vec2 m) const override {
    if (fields != nullptr && fields->discontinuity && fields->depth && marked(*fields->discontinuity, local)) {
      const TexelSample d = depth_.sample(fields, local, m);
      if (!std::isnan(d.v1)) return {0.0, 0.0, kDepthStep, 0.0, d.v0, d.v1};
    }
    TexelSample s = curvature_.sample_at(fields, local, at, m);
    if (fields == nullptr || !fields->depth || !fields->gradient) return without_height(s);
    const FieldTexel texel =
        field_texel(local, fields->gradient->width, fields->gradient->height, -sign_of(m.x), -sign_of(m.y));
    with_height(s, fields, texel.index);
    if (texel.behind_inside) s.v3 = kInsideRegion;
    return s;
  }
  // The exact sample: where the surface steps between the point 1 px behind and this one by more than
  // `discontinuity_px` beyond what its slopes explain, depth's reading of the step (the height change over the pair),
  // as on a discontinuity texel; elsewhere the curvature method's exact sample.
  TexelSample sample_exact(const SurfacePoint& point, Vec2 m) const override {
    if (beyond(std::abs(point.unexplained_rise), params_.discontinuity_px, std::abs(point.height))) {
      return {0.0, 0.0, kDepthStep, 0.0, point.height, point.rise};
    }
    return without_height(curvature_.sample_exact(point, m));
  }
  // Whether cd(from, to, ...) reads `from`: as the curvature method, never on a discontinuity texel.
  static bool reads_from(const TexelSample& to) { return to.v2 != kDepthStep && CurvatureMethod::reads_from(to); }
#if defined(__GNUC__)
  [[gnu::always_inline]]
#endif
  double
  cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const override {
    if (to.v2 == kDepthStep) [[unlikely]]
      return depth_cd(depth_.params(), depth_.cd_lower_bound(), 0.0, to.v5, 1.0, detail);
    if (CurvatureMethod::reads_from(to) && to.v3 != kInsideRegion && step_between(from, to)) [[unlikely]]
      return depth_cd(depth_.params(), depth_.cd_lower_bound(), from.v4, to.v4, 1.0, detail);
    return curvature_.cd(from, to, step_px, detail);
  }
  double cd_lower_bound() const override { return std::min(curvature_.cd_lower_bound(), depth_.cd_lower_bound()); }
  double cd_upper_bound() const override { return std::max(curvature_.cd_upper_bound(), depth_.cd_upper_bound()); }
  const HybridParams& params() const { return params_; }

 private:
  // A sample of a texel with a height (`fields` has a depth field: null otherwise) carries it in v4 and its steepest
  // slope, max(|g_x|, |g_y|), in v5; one without has v5 NaN. At a region's border the walk pairs a texel with the
  // one it came from, in another region or outside every region.
  static void with_height(TexelSample& s, const RegionFields* fields, std::size_t index) {
    if (fields == nullptr) {
      s.v5 = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    const Gradient g = fields->gradient->values[index];
    s.v4 = fields->depth->values[index];
    s.v5 = std::max(std::abs(static_cast<double>(g.x)), std::abs(static_cast<double>(g.y)));
  }
  static TexelSample without_height(TexelSample s) {
    s.v5 = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  // Whether the height changes between two texels on either side of a region's border by more than
  // `discontinuity_px` beyond the steepest slope either side's normals show: a step the normals cannot show (a region
  // raised above the region it overlaps), where the depth method's C/D is taken. The walk crosses a border along x
  // or y, and the gradient's component along that axis is at most the steepest one.
  bool step_between(const TexelSample& from, const TexelSample& to) const {
    if (!(to.v5 >= 0.0)) return false;  // (NaN: no height here)
    const double from_slope = from.v2 == kDepthStep ? std::abs(from.v5) : from.v5;
    if (!(from_slope >= 0.0)) return false;
    return beyond(std::abs(to.v4 - from.v4), std::max(from_slope, to.v5) + params_.discontinuity_px,
                  std::max(std::abs(from.v4), std::abs(to.v4)));
  }
  // Whether `change` exceeds `bound` by more than the float rounding of heights of magnitude `height` (a depth field's
  // heights are floats): a change equal to the bound is none, whichever arithmetic made it, so that the walk on stored
  // heights and the exact input on the surface's decide alike there (two regions overlapping by exactly
  // `discontinuity_px` are seamless to both).
  static bool beyond(double change, double bound, double height) {
    constexpr double kFloatRounding = 4.0 * std::numeric_limits<float>::epsilon();
    return change > bound + kFloatRounding * std::max(1.0, height);
  }
  static bool marked(const DiscontinuityField& marks, Texel t) {
    return t.x >= 0 && t.y >= 0 && t.x < marks.width && t.y < marks.height && marks.at(t.x, t.y) != 0;
  }

  // v2 of a discontinuity texel's sample (curvature's v2 is finite or NaN, never infinite).
  static constexpr double kDepthStep = std::numeric_limits<double>::infinity();
  // v3 of a bilinear sample whose texel's neighbour behind lies in the same region (the curvature method's bilinear
  // reading leaves v3 unread unless infinite).
  static constexpr double kInsideRegion = 0.0;

  HybridParams params_;
  CurvatureMethod curvature_{CurvatureParams{}};
  DepthMethod depth_{DepthParams{}};
};

}  // namespace ph
