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
#include "core/effects/curvature_field.hpp"

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

// Correlation of one row with a kernel. Windows never leave the image where they are used (the window's
// centre is clamped inward, see window_for); the few border texels keep a clamped window as a safety net.
void filter_row(const double* __restrict in, std::int32_t w, const std::vector<double>& kernel, std::int32_t r,
                double* __restrict out) {
  auto clamped = [&](std::int32_t x) {
    double sum = 0.0;
    for (std::int32_t t = -r; t <= r; ++t) sum += kernel[t + r] * in[clamp_index(x + t, w)];
    return sum;
  };
  const std::int32_t inner_end = std::max(w - r, r);
  for (std::int32_t x = 0; x < std::min(r, w); ++x) out[x] = clamped(x);
  for (std::int32_t x = r; x < inner_end; ++x) {
    double sum = 0.0;  // the same terms in the same order as `clamped`: identical results
    for (std::int32_t t = -r; t <= r; ++t) sum += kernel[t + r] * in[x + t];
    out[x] = sum;
  }
  for (std::int32_t x = std::max(inner_end, std::min(r, w)); x < w; ++x) out[x] = clamped(x);
}

// The row filters of one input, row by row: only the rows a column window spans (2 r_y + 1) are kept, in a
// ring, so no whole grid of intermediates is ever allocated and the rows stay in cache.
class RowRing {
 public:
  // `first`: the first input row any window will need.
  RowRing(std::int32_t width, std::int32_t r_y, std::vector<const std::vector<double>*> kernels, std::int32_t r_x,
          std::int32_t first)
      : width_(width),
        span_(2 * r_y + 1),
        r_x_(r_x),
        kernels_(std::move(kernels)),
        input_(static_cast<std::size_t>(width)),
        rows_(kernels_.size() * static_cast<std::size_t>(span_) * static_cast<std::size_t>(width)),
        next_(first) {}

  // Filters the input rows up to `last` that are not filtered yet; load(y, row) writes input row y.
  template <typename Load>
  void filter_up_to(std::int32_t last, Load&& load) {
    for (; next_ <= last; ++next_) {
      load(next_, input_.data());
      for (std::size_t k = 0; k < kernels_.size(); ++k)
        filter_row(input_.data(), width_, *kernels_[k], r_x_, slot(k, next_));
    }
  }
  const double* row(std::size_t kernel, std::int32_t y) const {
    return &rows_[(kernel * static_cast<std::size_t>(span_) + static_cast<std::size_t>(y % span_)) * width_];
  }

 private:
  double* slot(std::size_t kernel, std::int32_t y) { return const_cast<double*>(row(kernel, y)); }

  std::int32_t width_, span_, r_x_;
  std::vector<const std::vector<double>*> kernels_;
  std::vector<double> input_;
  std::vector<double> rows_;
  std::int32_t next_;
};

// Correlation along columns, centred on row cy, for a whole row at once: out[x] = sum_t k[t] in(x, cy + t),
// summed in the order of t like a texel-by-texel loop (identical results), but row after row in memory.
void filter_column_row(const RowRing& ring, std::size_t which, std::int32_t width, const std::vector<double>& kernel,
                       std::int32_t r, std::int32_t cy, std::vector<double>& out_row) {
  out_row.assign(static_cast<std::size_t>(width), 0.0);
  double* __restrict out = out_row.data();
  for (std::int32_t t = -r; t <= r; ++t) {
    const double k = kernel[t + r];
    const double* __restrict in = ring.row(which, cy + t);
    for (std::int32_t x = 0; x < width; ++x) out[x] += k * in[x];
  }
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

// The first input row the windows of rows [y, ...) read.
std::int32_t first_row_read(std::int32_t y, const Kernels& kx, const Kernels& ky, std::int32_t w, std::int32_t h) {
  return window_for(0, y, kx, ky, w, h).cy - ky.r;
}

// Both walk the rows [rows.begin, rows.end) (all: the whole field) and call visit(x, y, derivatives) for each texel
// in order. A texel's derivatives are the same whichever rows are walked: its window's rows are filtered alike.
template <typename F>
void for_each_depth_derivatives(const DepthField& depth, const DerivativeFilter& filter, RowRange rows, F&& visit) {
  const std::int32_t w = depth.width, h = depth.height;
  const Kernels kx = make_kernels(filter.radius, w);
  const Kernels ky = make_kernels(filter.radius, h);
  rows = rows.within(h);
  if (rows.empty() || w <= 0) return;
  enum : std::size_t { kBox, kSlope, kCurve };
  RowRing ring(w, ky.r, {&kx.box, &kx.slope, &kx.curve}, kx.r, first_row_read(rows.begin, kx, ky, w, h));
  auto load = [&](std::int32_t y, double* row) {
    for (std::int32_t x = 0; x < w; ++x) row[x] = tame(depth.at(x, y));
  };
  // The column filters of the window centred on row cy; rows near the border share their window's centre.
  std::vector<double> hxx_half, hyy_half, hxy, hx0, hy0;
  std::int32_t filtered_cy = -1;
  for (std::int32_t y = rows.begin; y < rows.end; ++y) {
    const std::int32_t cy = window_for(0, y, kx, ky, w, h).cy;
    if (cy != filtered_cy) {
      ring.filter_up_to(cy + ky.r, load);
      filter_column_row(ring, kCurve, w, ky.box, ky.r, cy, hxx_half);
      filter_column_row(ring, kBox, w, ky.curve, ky.r, cy, hyy_half);
      filter_column_row(ring, kSlope, w, ky.slope, ky.r, cy, hxy);
      filter_column_row(ring, kSlope, w, ky.box, ky.r, cy, hx0);
      filter_column_row(ring, kBox, w, ky.slope, ky.r, cy, hy0);
      filtered_cy = cy;
    }
    for (std::int32_t x = 0; x < w; ++x) {
      const Window win = window_for(x, y, kx, ky, w, h);
      const auto c = static_cast<std::size_t>(win.cx);
      HeightDerivatives d;
      d.hxx = 2.0 * hxx_half[c];
      d.hyy = 2.0 * hyy_half[c];
      d.hxy = hxy[c];
      d.hx = hx0[c] + d.hxx * win.dx + d.hxy * win.dy;
      d.hy = hy0[c] + d.hxy * win.dx + d.hyy * win.dy;
      visit(x, y, d);
    }
  }
}

template <typename F>
void for_each_gradient_derivatives(const GradientField& gradient, const DerivativeFilter& filter, RowRange rows,
                                   F&& visit) {
  const std::int32_t w = gradient.width, h = gradient.height;
  const Kernels kx = make_kernels(filter.radius, w);
  const Kernels ky = make_kernels(filter.radius, h);
  rows = rows.within(h);
  if (rows.empty() || w <= 0) return;
  enum : std::size_t { kBox, kSlope };
  const std::int32_t first = first_row_read(rows.begin, kx, ky, w, h);
  RowRing p_ring(w, ky.r, {&kx.box, &kx.slope}, kx.r, first);
  RowRing q_ring(w, ky.r, {&kx.box, &kx.slope}, kx.r, first);
  auto load_p = [&](std::int32_t y, double* row) {
    for (std::int32_t x = 0; x < w; ++x) row[x] = tame(gradient.at(x, y).x);
  };
  auto load_q = [&](std::int32_t y, double* row) {
    for (std::int32_t x = 0; x < w; ++x) row[x] = tame(gradient.at(x, y).y);
  };
  // The column filters of the window centred on row cy; rows near the border share their window's centre.
  std::vector<double> px_row, py_row, qx_row, qy_row, p0_row, q0_row;
  std::int32_t filtered_cy = -1;
  for (std::int32_t y = rows.begin; y < rows.end; ++y) {
    const std::int32_t cy = window_for(0, y, kx, ky, w, h).cy;
    if (cy != filtered_cy) {
      p_ring.filter_up_to(cy + ky.r, load_p);
      q_ring.filter_up_to(cy + ky.r, load_q);
      filter_column_row(p_ring, kSlope, w, ky.box, ky.r, cy, px_row);
      filter_column_row(p_ring, kBox, w, ky.slope, ky.r, cy, py_row);
      filter_column_row(q_ring, kSlope, w, ky.box, ky.r, cy, qx_row);
      filter_column_row(q_ring, kBox, w, ky.slope, ky.r, cy, qy_row);
      filter_column_row(p_ring, kBox, w, ky.box, ky.r, cy, p0_row);
      filter_column_row(q_ring, kBox, w, ky.box, ky.r, cy, q0_row);
      filtered_cy = cy;
    }
    for (std::int32_t x = 0; x < w; ++x) {
      const Window win = window_for(x, y, kx, ky, w, h);
      const auto c = static_cast<std::size_t>(win.cx);
      const double px = px_row[c], py = py_row[c], qx = qx_row[c], qy = qy_row[c];
      HeightDerivatives d;
      d.hx = p0_row[c] + px * win.dx + py * win.dy;
      d.hy = q0_row[c] + qx * win.dx + qy * win.dy;
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
  for_each(input, filter, RowRange{}, [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) {
    const Curvatures c = curvatures_from_derivatives(d);
    if (request.gaussian) out.gaussian.at(x, y) = static_cast<float>(c.gaussian);
    if (request.mean) out.mean.at(x, y) = static_cast<float>(c.mean);
    if (request.principal) out.k1.at(x, y) = static_cast<float>(c.k1), out.k2.at(x, y) = static_cast<float>(c.k2);
  });
  return out;
}

// Hands k1 and k2 on row by row.
template <typename ForEach, typename Input>
void principal_rows(const Input& input, const DerivativeFilter& filter, RowRange rows, const PrincipalRowVisitor& visit,
                    ForEach for_each) {
  std::vector<float> k1(static_cast<std::size_t>(input.width)), k2(k1.size());
  const std::int32_t last = input.width - 1;
  for_each(input, filter, rows, [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) {
    const Curvatures c = curvatures_from_derivatives(d);
    k1[static_cast<std::size_t>(x)] = static_cast<float>(c.k1);
    k2[static_cast<std::size_t>(x)] = static_cast<float>(c.k2);
    if (x == last) visit(y, k1.data(), k2.data());
  });
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
  for_each_depth_derivatives(depth, filter, RowRange{},
                             [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) { out.at(x, y) = d; });
  return out;
}

Grid<HeightDerivatives> derivatives_from_gradient(const GradientField& gradient, const DerivativeFilter& filter) {
  Grid<HeightDerivatives> out(gradient.width, gradient.height);
  for_each_gradient_derivatives(gradient, filter, RowRange{},
                                [&](std::int32_t x, std::int32_t y, const HeightDerivatives& d) { out.at(x, y) = d; });
  return out;
}

void principal_rows_from_depth(const DepthField& depth, const DerivativeFilter& filter, RowRange rows,
                               const PrincipalRowVisitor& visit) {
  principal_rows(depth, filter, rows, visit,
                 [](const auto& in, const auto& f, RowRange r, auto&& v) { for_each_depth_derivatives(in, f, r, v); });
}

void principal_rows_from_gradient(const GradientField& gradient, const DerivativeFilter& filter, RowRange rows,
                                  const PrincipalRowVisitor& visit) {
  principal_rows(gradient, filter, rows, visit, [](const auto& in, const auto& f, RowRange r, auto&& v) {
    for_each_gradient_derivatives(in, f, r, v);
  });
}

CurvatureFields curvature_from_depth(const DepthField& depth, const DerivativeFilter& filter,
                                     const CurvatureRequest& request) {
  return curvature_fields(depth, filter, request, [](const auto& in, const auto& f, RowRange r, auto&& visit) {
    for_each_depth_derivatives(in, f, r, visit);
  });
}

CurvatureFields curvature_from_gradient(const GradientField& gradient, const DerivativeFilter& filter,
                                        const CurvatureRequest& request) {
  return curvature_fields(gradient, filter, request, [](const auto& in, const auto& f, RowRange r, auto&& visit) {
    for_each_gradient_derivatives(in, f, r, visit);
  });
}

}  // namespace ph
