// One small interface for every way of turning a texel step into a C/D ratio. The traversal knows
// nothing else about a method, so new methods plug in without touching it (docs/DESIGN.md, "One file per method").
#pragma once

#include <memory>
#include <string_view>

#include "core/engine/field.hpp"
#include "core/engine/geometry.hpp"

namespace ph {

// The largest C/D factor a method's parameters may set, either way (kmax, and kmin for 1 / the smallest C/D): a
// hundredfold slowdown already stops the cursor like a wall, and beyond it a misplaced exponent (1e300) made the
// cursor never cross a region, or jump across the screen on one count.
inline constexpr double kMaxCdFactor = 100.0;

// What a method reads from one texel for one motion direction; the meaning of the numbers is private to
// the method (curvature: a = n''_x and the slope angle, here and 1 px behind; depth: the height, and its change
// per px along the motion). Six, so that a method reading normals and heights together keeps both methods'
// readings; the walkers call the listed methods inline (core/engine/methods.hpp), so numbers a method leaves
// unused cost nothing.
struct TexelSample {
  double v0 = 0.0;
  double v1 = 0.0;
  double v2 = 0.0;
  double v3 = 0.0;
  double v4 = 0.0;
  double v5 = 0.0;
};

// A surface's exact values at one point, in double precision: what the ground truth's analytic surfaces
// give a method in place of a texel (core/lab/ground_truth.hpp). Only what the method's needs() names is set.
struct SurfacePoint {
  double height = 0.0;  // px toward the viewer
  Vec2 gradient;        // (dh/dx, dh/dy), y down
  // For a method that reads both heights and normals, at the second point p of the ground truth's pair (p - m, p):
  // the height change from p - m, and the part of it that the slopes along the way do not explain (a step of the
  // surface between the two points; 0 where the surface is smooth there).
  double rise = 0.0;
  double unexplained_rise = 0.0;
};

// The intermediate quantities of one step, for traces and tests. Fields a method does not use stay NaN
// (a trace writes them as empty cells; they never reach an event).
struct StepDetail {
  double cos_alpha;
  double delta_beta_deg;
  double kmax;
  double kmin;
  double dh;
};
StepDetail empty_step_detail();

// Names a method's concrete class, so that a walker can call the methods of core/engine/methods.hpp without a
// virtual call per texel (one compare per region a frame meets). A method outside that list has none.
using MethodTag = const void*;
template <typename M>
inline constexpr char kMethodTagOf = 0;
template <typename M>
constexpr MethodTag method_tag() {
  return &kMethodTagOf<M>;
}

class Method {
 public:
  virtual ~Method() = default;
  MethodTag tag() const { return tag_; }

  virtual std::string_view name() const = 0;
  virtual FieldNeeds needs() const = 0;

  // Derives at load, once, what the method reads beyond the loaded fields (Scene's constructor calls it after
  // checking them), so that a step costs no more than its reads. The default derives nothing.
  virtual void prepare(RegionFields& fields) const { static_cast<void>(fields); }

  // Sample of texel `local` of a region's fields; a region whose fields lack what this method reads
  // (or a texel outside every region, `fields == nullptr`) gives the flat surface's sample.
  virtual TexelSample sample(const RegionFields* fields, Texel local, Vec2 direction) const = 0;

  // Sample at a continuous position `at` (region-local px) inside texel `local`, for Sampling::bilinear.
  // A method that has no interpolated reading keeps the texel's: the default is sample(fields, local, m).
  virtual TexelSample sample_at(const RegionFields* fields, Texel local, Vec2 at, Vec2 direction) const {
    static_cast<void>(at);
    return sample(fields, local, direction);
  }

  // Sample at a point of an exact continuous surface (the ground truth): the value sample() would read
  // there with no rounding and no approximation (exact atan where the walk uses fast_atan). The default
  // reads nothing: the flat surface's sample.
  virtual TexelSample sample_exact(const SurfacePoint& point, Vec2 direction) const {
    static_cast<void>(point);
    return sample(nullptr, {}, direction);
  }

  // C/D ratio of the segment inside the texel `to`, entered from the neighbour texel `from`, whose
  // centres are `step_px` apart. Always finite and within the method's documented bounds.
  virtual double cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const = 0;

  // The range every value of cd() lies in.
  virtual double cd_lower_bound() const = 0;
  virtual double cd_upper_bound() const = 0;

 protected:
  explicit Method(MethodTag tag = nullptr) : tag_(tag) {}

 private:
  MethodTag tag_;
};

using MethodPtr = std::shared_ptr<const Method>;

}  // namespace ph
