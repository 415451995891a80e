#include "core/lab/ground_truth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace ph {

namespace {

// ---------------------------------------------------------------------------------------------------------------
// Surfaces.

constexpr double kGaussianSigma = 1.0 / 3.0;  // as core/engine/targets.cpp (docs/METHODS.md, "The 24 targets")

// The distances u in (u0, u1) where the line p0 + u m meets the circle of radius r about c, and the closest point.
void circle_breakpoints(Vec2 c, double r, Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) {
  const Vec2 d = c - p0;
  const double uc = d.x * m.x + d.y * m.y;
  const double perp2 = d.x * d.x + d.y * d.y - uc * uc;
  auto add = [&](double u) {
    if (u > u0 && u < u1) out.push_back(u);
  };
  add(uc);
  if (perp2 <= r * r) {
    const double half = std::sqrt(r * r - std::max(perp2, 0.0));
    add(uc - half);
    add(uc + half);
  }
}

// A target in double precision: the formulas of core/engine/targets.cpp without the final rounding to float. Kept
// in step with them by tests/test_ground_truth.cpp (heights equal, gradients equal after rounding).
class TargetSurface final : public AnalyticSurface {
 public:
  explicit TargetSurface(const TargetSpec& spec)
      : spec_(spec),
        centre_{spec.size / 2.0, spec.size / 2.0},
        peak_((spec.shape == TargetShape::bump ? 1.0 : -1.0) * spec.height * spec.relief_px) {}

  double height(Vec2 p) const override {
    const double r = length(p - centre_);
    if (r > spec_.radius) return 0.0;
    return peak_ * value(r / spec_.radius);
  }
  ExactGradient gradient(Vec2 p) const override {
    const Vec2 d = p - centre_;
    const double r = length(d);
    if (r > spec_.radius || r == 0.0) return {};
    const double dh_dr = peak_ * slope(r / spec_.radius) / spec_.radius;
    return {dh_dr * d.x / r, dh_dr * d.y / r};
  }
  void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const override {
    circle_breakpoints(centre_, spec_.radius, p0, m, u0, u1, out);
  }

 private:
  double value(double u) const {
    switch (spec_.profile) {
      case TargetProfile::linear:
        return 1.0 - u;
      case TargetProfile::gaussian:
        return std::exp(-u * u / (2.0 * kGaussianSigma * kGaussianSigma));
      case TargetProfile::polynomial:
        return 1.0 - u * u * u * u;
    }
    return 0.0;
  }
  double slope(double u) const {
    switch (spec_.profile) {
      case TargetProfile::linear:
        return -1.0;
      case TargetProfile::gaussian:
        return -u / (kGaussianSigma * kGaussianSigma) * value(u);
      case TargetProfile::polynomial:
        return -4.0 * u * u * u;
    }
    return 0.0;
  }

  TargetSpec spec_;
  Vec2 centre_;
  double peak_;
};

// An interrogation surface inside its square, flat outside: what a region of that size holds.
class InterrogationSurface final : public AnalyticSurface {
 public:
  explicit InterrogationSurface(const SurfaceSpec& spec) : spec_(spec) {}

  double height(Vec2 p) const override { return inside(p) ? surface_height(spec_, p) : 0.0; }
  ExactGradient gradient(Vec2 p) const override {
    if (!inside(p)) return {};
    const HeightDerivatives d = surface_derivatives(spec_, p);
    return {d.hx, d.hy};
  }
  bool outside_regions(Vec2 p) const override { return !inside(p); }
  void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const override {
    const double size = spec_.size;
    auto add = [&](double coord0, double dir, double edge) {
      if (dir == 0.0) return;
      const double u = (edge - coord0) / dir;
      if (u > u0 && u < u1) out.push_back(u);
    };
    for (double edge : {0.0, size}) {
      add(p0.x, m.x, edge);
      add(p0.y, m.y, edge);
    }
  }

 private:
  bool inside(Vec2 p) const { return p.x >= 0.0 && p.y >= 0.0 && p.x < spec_.size && p.y < spec_.size; }
  SurfaceSpec spec_;
};

// ---------------------------------------------------------------------------------------------------------------
// Adaptive Gauss-Kronrod 7-15 (the QUADPACK qk15 rule).

constexpr std::array<double, 8> kXgk = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                        0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                        0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                        0.207784955007898467600689403773245, 0.0};
constexpr std::array<double, 8> kWgk = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                        0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                        0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                        0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
// Gauss weights of the nodes kXgk[1], kXgk[3], kXgk[5] and 0.
constexpr std::array<double, 4> kWg = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                       0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

template <typename F>
double gauss_kronrod(const F& f, double a, double b, double& error) {
  const double centre = 0.5 * (a + b);
  const double half = 0.5 * (b - a);
  const double fc = f(centre);
  double kronrod = fc * kWgk[7];
  double gauss = fc * kWg[3];
  for (int i = 0; i < 7; ++i) {
    const double dx = half * kXgk[i];
    const double sum = f(centre - dx) + f(centre + dx);
    kronrod += kWgk[i] * sum;
    if (i % 2 == 1) gauss += kWg[i / 2] * sum;
  }
  error = std::abs((kronrod - gauss) * half);
  return kronrod * half;
}

// Splits until the two halves agree with the whole and each half's Kronrod-Gauss difference is within its share
// of `tol`, or the interval is shorter than min_step (a discontinuity nobody declared: its contribution is then at
// most jump x min_step). The check against the whole guards against a Kronrod-Gauss difference that is small by
// coincidence across a kink (a clamp of the C/D), which happens: one 2 px interval was off by 1.6e-7 without it.
template <typename F>
double adaptive_split(const F& f, double a, double b, double whole, double tol, double min_step, int depth) {
  const double mid = 0.5 * (a + b);
  double error_left = 0.0, error_right = 0.0;
  const double left = gauss_kronrod(f, a, mid, error_left);
  const double right = gauss_kronrod(f, mid, b, error_right);
  const double both = left + right;
  if ((std::abs(both - whole) <= tol && error_left + error_right <= tol) || b - a <= min_step || depth >= 60) {
    return both;
  }
  return adaptive_split(f, a, mid, left, 0.5 * tol, min_step, depth + 1) +
         adaptive_split(f, mid, b, right, 0.5 * tol, min_step, depth + 1);
}

template <typename F>
double adaptive(const F& f, double a, double b, double tol, double min_step) {
  double error = 0.0;
  const double whole = gauss_kronrod(f, a, b, error);
  return adaptive_split(f, a, b, whole, tol, min_step, 0);
}

// Where the integrand C/D(p0 + s m) may be non-smooth for s in (s0, s1): the surface's breakpoints at the point
// itself (s = u) and at the sample behind it (s = u + 1). Sorted, with s0 and s1 at the ends.
std::vector<double> integrand_breakpoints(const TruthModel& model, Vec2 p0, Vec2 m, double s0, double s1) {
  std::vector<double> us;
  model.surface->breakpoints(p0, m, s0 - 1.0, s1, us);
  std::vector<double> cuts{s0, s1};
  for (double u : us) {
    for (double s : {u, u + 1.0}) {
      if (s > s0 && s < s1) cuts.push_back(s);
    }
  }
  std::sort(cuts.begin(), cuts.end());
  return cuts;
}

// Whether the truth gives the model's method the surface's heights.
bool reads_heights(const TruthModel& model) {
  const FieldNeeds needs = model.method->needs();
  return needs.reads_depth(model.depth_given);
}

// What a method with `needs` reads of the surface at p (the heights where `heights`).
SurfacePoint point_of(const AnalyticSurface& surface, Vec2 p, FieldNeeds needs, bool heights) {
  SurfacePoint point;
  if (heights) point.height = surface.height(p);
  if (needs.gradient) {
    const ExactGradient g = surface.gradient(p);
    point.gradient = {g.x, g.y};
  }
  return point;
}

// The part of `rise`, the height change from a to a + m (m unit), that the slopes along the way do not explain: a step
// of the surface between the two points. Between the surface's breakpoints it is smooth, and its height change there is
// the integral of its slope along m (one Gauss-Kronrod rule per piece); with no breakpoint between the points there is
// no step.
double unexplained_rise(const AnalyticSurface& surface, Vec2 a, Vec2 m, double rise) {
  std::vector<double> cuts;
  surface.breakpoints(a, m, 0.0, 1.0, cuts);
  if (cuts.empty()) return 0.0;
  cuts.push_back(0.0);
  cuts.push_back(1.0);
  std::sort(cuts.begin(), cuts.end());
  const auto slope = [&](double s) {
    const ExactGradient g = surface.gradient(a + m * s);
    return g.x * m.x + g.y * m.y;
  };
  double explained = 0.0, error = 0.0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    if (cuts[i + 1] > cuts[i]) explained += gauss_kronrod(slope, cuts[i], cuts[i + 1], error);
  }
  return rise - explained;
}

}  // namespace

std::unique_ptr<AnalyticSurface> make_target_surface(const TargetSpec& spec) {
  return std::make_unique<TargetSurface>(spec);
}

std::unique_ptr<AnalyticSurface> make_interrogation_surface(const SurfaceSpec& spec) {
  return std::make_unique<InterrogationSurface>(spec);
}

double truth_cd_lower_bound(const TruthModel& model) { return model.method->cd_lower_bound(); }

double truth_cd_upper_bound(const TruthModel& model) { return model.method->cd_upper_bound(); }

double truth_cd(const TruthModel& model, Vec2 p, Vec2 m, StepDetail* detail) {
  const Method& method = *model.method;
  const FieldNeeds needs = method.needs();
  const bool heights = reads_heights(model);
  const SurfacePoint point_behind = point_of(*model.surface, p - m, needs, heights);
  SurfacePoint point = point_of(*model.surface, p, needs, heights);
  if (needs.gradient && heights) {
    point.rise = point.height - point_behind.height;
    if (!model.surface->outside_regions(p - m) && !model.surface->outside_regions(p)) {
      point.unexplained_rise = unexplained_rise(*model.surface, p - m, m, point.rise);
    }
  }
  return method.cd(method.sample_exact(point_behind, m), method.sample_exact(point, m), 1.0, detail);
}

double truth_motor_travel(const TruthModel& model, Vec2 p0, Vec2 m, double d, const TruthTolerance& tol) {
  if (!(d > 0.0)) return 0.0;
  const auto f = [&](double s) { return truth_cd(model, p0 + m * s, m); };
  const double tol_motor = tol.display_px * truth_cd_lower_bound(model);
  const std::vector<double> cuts = integrand_breakpoints(model, p0, m, 0.0, d);
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = cuts[i], b = cuts[i + 1];
    if (b > a) sum += adaptive(f, a, b, tol_motor * (b - a) / d, tol.min_step_px);
  }
  return sum;
}

double truth_display_distance(const TruthModel& model, Vec2 p0, Vec2 m, double motor_px, const TruthTolerance& tol) {
  if (!(motor_px > 0.0)) return 0.0;
  const auto f = [&](double s) { return truth_cd(model, p0 + m * s, m); };
  const double cd_lo = truth_cd_lower_bound(model);
  // The cursor cannot get farther than the motor travel at the smallest C/D.
  const double s_max = motor_px / cd_lo * (1.0 + 1e-12) + 1e-9;
  // Half of the motor-travel tolerance for the pieces passed whole, a quarter for the solve in the last one.
  const double tol_motor = tol.display_px * cd_lo;
  constexpr double kMaxPiecePx = 2.0;  // short pieces: little integrated past the answer
  const std::vector<double> cuts = integrand_breakpoints(model, p0, m, 0.0, s_max);
  double done = 0.0;  // motor travel up to a
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double piece_end = cuts[i + 1];
    for (double a = cuts[i]; a < piece_end;) {
      const double b = std::min(piece_end, a + kMaxPiecePx);
      const double travel = adaptive(f, a, b, 0.5 * tol_motor * (b - a) / s_max, tol.min_step_px);
      const double left = motor_px - done;
      if (travel < left) {
        done += travel;
        a = b;
        continue;
      }
      // The answer lies in [a, b]: safeguarded Newton on F(x) = integral_a^x C/D - left, F' = C/D > 0.
      double lo = a, hi = b, x = a, fx = 0.0;
      const double step_tol = tol_motor / 16.0;
      for (int iter = 0; iter < 200; ++iter) {
        const double residual = fx - left;
        if (std::abs(residual) <= 0.25 * tol_motor || hi - lo <= tol.min_step_px) break;
        if (residual < 0.0) {
          lo = x;
        } else {
          hi = x;
        }
        double next = x - residual / f(x);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        fx += next > x ? adaptive(f, x, next, step_tol, tol.min_step_px)
                       : -adaptive(f, next, x, step_tol, tol.min_step_px);
        x = next;
      }
      return x;
    }
  }
  return s_max;  // unreachable for C/D >= cd_lo; the bound itself otherwise
}

Vec2 truth_advance(const TruthModel& model, Vec2 p, Vec2 motor, const TruthTolerance& tol) {
  const double budget = length(motor);
  if (!std::isfinite(budget) || budget == 0.0) return p;
  const Vec2 m = motor * (1.0 / budget);
  return p + m * truth_display_distance(model, p, m, budget, tol);
}

}  // namespace ph
