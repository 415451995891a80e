// The exact continuous answer the traversal approximates: the C/D ratio of an analytic surface at any
// point from exact double-precision gradients and heights, and where the cursor ends after a frame from an
// adaptive Gauss-Kronrod integral of that C/D along the motion. Nothing here looks at texels, so it measures the
// traversal, the storage and the sampling of the engine from outside (docs/SPEED_VS_ACCURACY.md, "Ground truth").
//
// The continuous C/D (our analogue of the engine's step, docs/METHODS.md). The engine gives the segment
// inside texel p2 the C/D of a pair read along the motion: p2's centre and the point 1 px behind it (the
// curvature method interpolates the normal there; the depth method takes upwind differences). The continuous
// analogue at a point p moving along the unit direction m takes the pair (p - m, p): the point itself and the point
// one px behind it along the motion, both at exact positions, with exact values:
//   the method's cd() with its sample_exact() at p - m as the first sample and at p as the second, and a step of
//   1 px. Curvature: a = -t / sqrt(1 + t^2), theta = atan(t), t = g . m (docs/METHODS.md), then curvature_cd of
//   core/engine/method_curvature.hpp; depth: depth_cd of core/engine/method_depth.hpp with h(p - m), h(p).
// The "to" sample is the point itself because the engine's "to" texel is the one the cursor is in; the pair lies
// along m rather than along a grid axis because that is the step the paper's wording ("each time the cursor
// advances one pixel") describes, independent of how a grid is oriented.
//
// The cursor after a frame. The frame's motor displacement D (px at C/D 1) moves the cursor along m = D / |D|; the
// display distance d it reaches solves  integral_0^d CD(p0 + s m, m) ds = |D|  (the motor travel of the display
// path is the integral of C/D over display arc length). Integrals use adaptive Gauss-Kronrod (7-15) in double
// precision, split at the surface's known non-smooth points (and the same points shifted 1 px, where the sample
// behind crosses them), with a minimum interval length so a discontinuity the surface does not declare still
// terminates; d is found by a safeguarded Newton iteration (F' = CD > 0).
#pragma once

#include <memory>
#include <vector>

#include "core/engine/geometry.hpp"
#include "core/engine/method.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/surfaces.hpp"

namespace ph {

// A gradient in double precision (core/engine/field.hpp's Gradient is float, which would make the integrand noisy at
// the 1e-7 level and keep an adaptive integrator at 1e-9 px from converging).
struct ExactGradient {
  double x = 0.0;  // dh/dx, px per px
  double y = 0.0;  // dh/dy, y down
};

// A height field in screen px with exact values everywhere on the screen (flat where it has no relief).
class AnalyticSurface {
 public:
  virtual ~AnalyticSurface() = default;
  virtual double height(Vec2 p) const = 0;
  virtual ExactGradient gradient(Vec2 p) const = 0;
  // Appends the distances u in (u0, u1) along the line p0 + u m (m unit) where the height or the gradient is not
  // smooth (a rim, an apex, a region's border); may append extra points, never needs to be sorted.
  virtual void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const = 0;
  // Whether p lies outside every region, on the desktop: it has no depth map, so the hybrid method looks for no step
  // against it (docs/METHODS.md, "Hybrid"), and neither does its truth. None by default.
  virtual bool outside_regions(Vec2 p) const {
    static_cast<void>(p);
    return false;
  }
};

// A target at its own pixels (region at (0, 0), as the tools build it), in double precision. Its heights equal
// target_height and its gradients equal target_gradient before their rounding to float (tests check both).
// Breakpoints: the rim, and the point closest to the centre (the linear apex; elsewhere a steep turn).
std::unique_ptr<AnalyticSurface> make_target_surface(const TargetSpec& spec);

// An interrogation surface on its square [0, size)^2, flat outside it as a region of that size is.
// Breakpoints: the square's border.
std::unique_ptr<AnalyticSurface> make_interrogation_surface(const SurfaceSpec& spec);

// A surface and a method (any, through Method::sample_exact). Both must outlive the model.
struct TruthModel {
  const AnalyticSurface* surface = nullptr;
  const Method* method = nullptr;
  // For a method that reads heights only where a depth map is given (FieldNeeds::depth_if_given): whether it is
  // given one, that is the surface's heights.
  bool depth_given = true;
};

// Smallest and largest C/D the model can give (the method's bounds).
double truth_cd_lower_bound(const TruthModel& model);
double truth_cd_upper_bound(const TruthModel& model);

// C/D at p for the unit motion direction m, with the pair (p - m, p) described above. detail may be null.
double truth_cd(const TruthModel& model, Vec2 p, Vec2 m, StepDetail* detail = nullptr);

struct TruthTolerance {
  double display_px = 1e-9;   // bound on the error of a display distance (before double rounding)
  double min_step_px = 1e-9;  // intervals shorter than this are not split further
};

// Motor travel of the display path from p0 along m over display length d >= 0: integral_0^d CD ds.
double truth_motor_travel(const TruthModel& model, Vec2 p0, Vec2 m, double d, const TruthTolerance& tol = {});

// Display distance reached from p0 along m with `motor_px` >= 0 of motor travel.
double truth_display_distance(const TruthModel& model, Vec2 p0, Vec2 m, double motor_px,
                              const TruthTolerance& tol = {});

// The cursor after one frame of motor displacement `motor` from p (p itself for a zero or non-finite motor).
Vec2 truth_advance(const TruthModel& model, Vec2 p, Vec2 motor, const TruthTolerance& tol = {});

}  // namespace ph
