// Least-squares derivative filters (a 2D Savitzky-Golay filter) and the curvature formulas of docs/INTERROGATION.md,
// "Curvature" and "Derivative filter".
//
// On a square window of offsets t in [-r, r]^2 the monomials 1, x, y, x^2 - m, y^2 - m, xy (m = mean of t^2) are
// orthogonal, so each coefficient of the least-squares quadric is one correlation that separates into a kernel
// along x times a kernel along y:
//   h_x  = sum x h / (n S2)            -> slope_x * box_y        (S2 = sum t^2, n = 2r + 1)
//   h_xx = 2 sum (x^2 - m) h / (n Q)   -> 2 curve_x * box_y      (Q = sum (t^2 - m)^2)
//   h_xy = sum x y h / S2^2            -> slope_x * slope_y
// A plane fit to p = h_x gives p_x and p_y with the same slope and box kernels.
#include "core/curvature_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ph {
namespace {

// 1D kernels indexed by t + r.
struct Kernels {
  std::int32_t r = 0;
  std::vector<double> box, slope, curve;
};

// The kernels of radius min(radius, (size - 1) / 2), so that a window fits in the image; an axis of one texel
// has no slope or curvature along it (radius 0, zero kernels).
Kernels make_kernels(std::int32_t radius, std::int32_t size) {
  Kernels k;
  k.r = std::max<std::int32_t>(std::min<std::int32_t>(std::max<std::int32_t>(radius, 1), (size - 1) / 2), 0);
  const double n = 2.0 * k.r + 1.0;
  double s2 = 0.0;
  for (std::int32_t t = -k.r; t <= k.r; ++t) s2 += double(t) * t;
  const double m = s2 / n;
  double q = 0.0;
  for (std::int32_t t = -k.r; t <= k.r; ++t) q += (double(t) * t - m) * (double(t) * t - m);
  for (std::int32_t t = -k.r; t <= k.r; ++t) {
    k.box.push_back(1.0 / n);
    k.slope.push_back(k.r > 0 ? t / s2 : 0.0);
    k.curve.push_back(k.r > 0 ? (double(t) * t - m) / q : 0.0);
  }
  return k;
}

std::int32_t clamp_index(std::int32_t i, std::int32_t size) { return std::clamp<std::int32_t>(i, 0, size - 1); }

// Correlation along rows (windows never leave the image where they are used; clamping is a safety net).
Grid<double> filter_rows(const Grid<double>& in, const std::vector<double>& kernel, std::int32_t r) {
  Grid<double> out(in.width, in.height);
  for (std::int32_t y = 0; y < in.height; ++y) {
    for (std::int32_t x = 0; x < in.width; ++x) {
      double sum = 0.0;
      for (std::int32_t t = -r; t <= r; ++t) sum += kernel[t + r] * in.at(clamp_index(x + t, in.width), y);
      out.at(x, y) = sum;
    }
  }
  return out;
}

// Correlation along the column of one texel.
double filter_column(const Grid<double>& in, const std::vector<double>& kernel, std::int32_t r, std::int32_t x,
                     std::int32_t y) {
  double sum = 0.0;
  for (std::int32_t t = -r; t <= r; ++t) sum += kernel[t + r] * in.at(x, clamp_index(y + t, in.height));
  return sum;
}

// A slope of 1e6 is already a wall; clamping keeps every product below in range.
double tame(double v) {
  constexpr double limit = 1e6;
  return std::isfinite(v) ? std::clamp(v, -limit, limit) : 0.0;
}

// Near the border the window stops at the edge instead of leaving the image: the fit is made over the nearest
// window inside, and its polynomial evaluated at the texel (offset d from the window's centre). Repeating edge
// texels instead would bend every surface at the border.
struct Window {
  std::int32_t cx = 0, cy = 0;  // the window's centre
  double dx = 0.0, dy = 0.0;    // texel - centre
};

Window window_for(std::int32_t x, std::int32_t y, const Kernels& kx, const Kernels& ky, std::int32_t w,
                  std::int32_t h) {
  Window win;
  win.cx = std::clamp<std::int32_t>(x, kx.r, std::max(w - 1 - kx.r, kx.r));
  win.cy = std::clamp<std::int32_t>(y, ky.r, std::max(h - 1 - ky.r, ky.r));
  win.dx = x - win.cx;
  win.dy = y - win.cy;
  return win;
}

template <typename F>
void for_each_depth_derivatives(const DepthField& depth, const DerivativeFilter& filter, F&& visit) {
  const Kernels kx = make_kernels(filter.radius, depth.width);
  const Kernels ky = make_kernels(filter.radius, depth.height);
  Grid<double> h(depth.width, depth.height);
  for (std::size_t i = 0; i < h.values.size(); ++i) h.values[i] = tame(depth.values[i]);
  const Grid<double> box_x = filter_rows(h, kx.box, kx.r);
  const Grid<double> slope_x = filter_rows(h, kx.slope, kx.r);
  const Grid<double> curve_x = filter_rows(h, kx.curve, kx.r);
  for (std::int32_t y = 0; y < h.height; ++y) {
    for (std::int32_t x = 0; x < h.width; ++x) {
      const Window win = window_for(x, y, kx, ky, h.width, h.height);
      HeightDerivatives d;
      d.hxx = 2.0 * filter_column(curve_x, ky.box, ky.r, win.cx, win.cy);
      d.hyy = 2.0 * filter_column(box_x, ky.curve, ky.r, win.cx, win.cy);
      d.hxy = filter_column(slope_x, ky.slope, ky.r, win.cx, win.cy);
      d.hx = filter_column(slope_x, ky.box, ky.r, win.cx, win.cy) + d.hxx * win.dx + d.hxy * win.dy;
      d.hy = filter_column(box_x, ky.slope, ky.r, win.cx, win.cy) + d.hxy * win.dx + d.hyy * win.dy;
      visit(x, y, d);
    }
  }
}

template <typename F>
void for_each_gradient_derivatives(const GradientField& gradient, const DerivativeFilter& filter, F&& visit) {
  const Kernels kx = make_kernels(filter.radius, gradient.width);
  const Kernels ky = make_kernels(filter.radius, gradient.height);
  Grid<double> p(gradient.width, gradient.height);
  Grid<double> q(gradient.width, gradient.height);
  for (std::size_t i = 0; i < gradient.values.size(); ++i) {
    p.values[i] = tame(gradient.values[i].x);
    q.values[i] = tame(gradient.values[i].y);
  }
  const Grid<double> p_box = filter_rows(p, kx.box, kx.r);
  const Grid<double> p_slope = filter_rows(p, kx.slope, kx.r);
  const Grid<double> q_box = filter_rows(q, kx.box, kx.r);
  const Grid<double> q_slope = filter_rows(q, kx.slope, kx.r);
  for (std::int32_t y = 0; y < p.height; ++y) {
    for (std::int32_t x = 0; x < p.width; ++x) {
      const Window win = window_for(x, y, kx, ky, p.width, p.height);
      const double px = filter_column(p_slope, ky.box, ky.r, win.cx, win.cy);
      const double py = filter_column(p_box, ky.slope, ky.r, win.cx, win.cy);
      const double qx = filter_column(q_slope, ky.box, ky.r, win.cx, win.cy);
      const double qy = filter_column(q_box, ky.slope, ky.r, win.cx, win.cy);
      HeightDerivatives d;
      d.hx = filter_column(p_box, ky.box, ky.r, win.cx, win.cy) + px * win.dx + py * win.dy;
      d.hy = filter_column(q_box, ky.box, ky.r, win.cx, win.cy) + qx * win.dx + qy * win.dy;
      d.hxx = px;
      d.hyy = qy;
      d.hxy = 0.5 * (py + qx);  // both mixed partials estimate h_xy; their mean uses all the data
      visit(x, y, d);
    }
  }
}

// Non-finite results become 0 and the rest stays within the float range the grids store.
double storable(double v) {
  if (!std::isfinite(v)) return 0.0;
  constexpr double limit = std::numeric_limits<float>::max();
  return std::clamp(v, -limit, limit);
}

template <typename ForEach, typename Input>
CurvatureFields curvature_fields(const Input& input, const DerivativeFilter& filter, const CurvatureRequest& request,
                                 ForEach for_each) {
  CurvatureFields out;
  const std::int32_t w = input.width;
  const std::int32_t h = input.height;
  if (request.gaussian) out.gaussian = Grid<float>(w, h);
  if (request.mean) out.mean = Grid<float>(w, h);
  if (request.principal) out.k1 = Grid<float>(w, h), out.k2 = Grid<float>(w, h);
  for_each(input, filter, [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) {
    const Curvatures c = curvatures_from_derivatives(d);
    if (request.gaussian) out.gaussian.at(x, y) = static_cast<float>(c.gaussian);
    if (request.mean) out.mean.at(x, y) = static_cast<float>(c.mean);
    if (request.principal) out.k1.at(x, y) = static_cast<float>(c.k1), out.k2.at(x, y) = static_cast<float>(c.k2);
  });
  return out;
}

}  // namespace

Curvatures curvatures_from_derivatives(const HeightDerivatives& d) {
  const double hx = tame(d.hx), hy = tame(d.hy);
  const double hxx = tame(d.hxx), hxy = tame(d.hxy), hyy = tame(d.hyy);
  const double g = 1.0 + hx * hx + hy * hy;
  const double k = (hxx * hyy - hxy * hxy) / (g * g);
  const double m = ((1.0 + hx * hx) * hyy - 2.0 * hx * hy * hxy + (1.0 + hy * hy) * hxx) / (2.0 * g * std::sqrt(g));
  const double spread = std::sqrt(std::max(m * m - k, 0.0));
  Curvatures c;
  c.gaussian = storable(k);
  c.mean = storable(m);
  c.k1 = storable(m + spread);
  c.k2 = storable(m - spread);
  return c;
}

Grid<HeightDerivatives> derivatives_from_depth(const DepthField& depth, const DerivativeFilter& filter) {
  Grid<HeightDerivatives> out(depth.width, depth.height);
  for_each_depth_derivatives(depth, filter,
                             [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) { out.at(x, y) = d; });
  return out;
}

Grid<HeightDerivatives> derivatives_from_gradient(const GradientField& gradient, const DerivativeFilter& filter) {
  Grid<HeightDerivatives> out(gradient.width, gradient.height);
  for_each_gradient_derivatives(gradient, filter,
                                [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) { out.at(x, y) = d; });
  return out;
}

CurvatureFields curvature_from_depth(const DepthField& depth, const DerivativeFilter& filter,
                                     const CurvatureRequest& request) {
  return curvature_fields(depth, filter, request, [](const auto& in, const auto& f, auto&& visit) {
    for_each_depth_derivatives(in, f, visit);
  });
}

CurvatureFields curvature_from_gradient(const GradientField& gradient, const DerivativeFilter& filter,
                                        const CurvatureRequest& request) {
  return curvature_fields(gradient, filter, request, [](const auto& in, const auto& f, auto&& visit) {
    for_each_gradient_derivatives(in, f, visit);
  });
}

}  // namespace ph
