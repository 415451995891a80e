#include "core/engine/method_hybrid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/engine/decode.hpp"
#include "core/engine/row_bands.hpp"

namespace ph {

namespace {

bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

// One pass of the binomial kernel [1 2 1] / 4 along x and then along y, the border texels repeated; written as
// differences from the texel's own value, so that a constant field stays exactly constant. The rows smoothed along x
// are kept three at a time, the ones the output row reads.
Gradient binomial(Gradient a, Gradient c, Gradient b) {
  return {c.x + 0.25f * ((a.x - c.x) + (b.x - c.x)), c.y + 0.25f * ((a.y - c.y) + (b.y - c.y))};
}
void binomial_row_along_x(const Gradient* in, std::int32_t w, Gradient* out) {
  if (w == 1) {
    out[0] = in[0];
    return;
  }
  out[0] = binomial(in[0], in[0], in[1]);
  for (std::int32_t x = 1; x + 1 < w; ++x) out[x] = binomial(in[x - 1], in[x], in[x + 1]);
  out[w - 1] = binomial(in[w - 2], in[w - 1], in[w - 1]);
}
GradientField binomial_pass(const GradientField& in, unsigned threads) {
  const std::int32_t w = in.width, h = in.height;
  GradientField out(w, h);
  if (w == 0 || h == 0) return out;
  const auto width = static_cast<std::size_t>(w);
  // In bands of rows, each with a ring of its own filled from the row above its first.
  for_row_bands_on_threads(h, threads, [&](RowRange rows) {
    std::vector<Gradient> ring(3 * width);  // the x-smoothed rows y - 1, y and y + 1 (clamped), at (row % 3) * width
    auto row = [&](std::int32_t y) { return ring.data() + static_cast<std::size_t>(y % 3) * width; };
    std::int32_t smoothed_to = std::max(rows.begin - 1, 0) - 1;  // the last row smoothed along x
    for (std::int32_t y = rows.begin; y < rows.end; ++y) {
      while (smoothed_to < std::min(y + 1, h - 1)) {
        ++smoothed_to;
        binomial_row_along_x(&in.at(0, smoothed_to), w, row(smoothed_to));
      }
      const Gradient* above = row(std::max(y - 1, 0));
      const Gradient* here = row(y);
      const Gradient* below = row(std::min(y + 1, h - 1));
      Gradient* o = &out.at(0, y);
      for (std::int32_t x = 0; x < w; ++x) o[x] = binomial(above[x], here[x], below[x]);
    }
  });
  return out;
}

}  // namespace

GradientField binomial_smoothed(const GradientField& g, unsigned threads) {
  return binomial_pass(binomial_pass(g, threads), threads);
}

namespace {

// The robust standard deviation of zero-centred values given as magnitudes: their median times 1.4826, which is
// a Gaussian's sigma; features (rims, steps) are fewer than half the texels and do not move it.
double robust_sigma(std::vector<double> magnitudes) {
  if (magnitudes.empty()) return 0.0;
  const auto mid = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2);
  std::nth_element(magnitudes.begin(), mid, magnitudes.end());
  return 1.4826 * *mid;
}

// Texels whose differences the noise estimates read: every one up to 2^20, every k-th beyond (the median of a
// million values is as good as that of all, and a 4K region's would take 130 MB).
constexpr std::size_t kSampledTexels = std::size_t{1} << 20;

// Every k-th texel of a field `width` wide holding `texels`, so that at most `samples` are read: k sharing no factor
// with the width, so that the texels read fall on every column in turn (a k that divides the width reads the same
// columns on every row: one phase of a relief periodic along x).
std::size_t sample_stride(std::size_t texels, std::int32_t width, std::size_t samples = kSampledTexels) {
  std::size_t k = texels / samples + 1;
  while (k > 1 && std::gcd(k, static_cast<std::size_t>(width)) != 1) ++k;
  return k;
}

// Both components of a - b, as magnitudes, at every sample_stride-th texel.
std::vector<double> differences(const GradientField& a, const GradientField& b) {
  const std::size_t stride = sample_stride(a.values.size(), a.width);
  std::vector<double> out;
  out.reserve(2 * (a.values.size() / stride + 1));
  for (std::size_t i = 0; i < a.values.size(); i += stride) {
    out.push_back(std::abs(static_cast<double>(a.values[i].x) - b.values[i].x));
    out.push_back(std::abs(static_cast<double>(a.values[i].y) - b.values[i].y));
  }
  return out;
}

// White noise of sigma s leaves a residual g - binomial_smoothed(g) of sigma 0.891 s: sqrt(1 - 2 k0 + sum k^2) with the
// two-pass kernel's centre k0 = 36/256 and sum k^2 = (70/256)^2.
constexpr double kResidualGain = 0.891;

// A gradient field's noise as the field itself shows it: the robust sigma of its residual from the smoothed field.
// It counts the relief's own fine detail too (a grating, a rough surface), so it is an upper bound.
double gradient_noise(const GradientField& g) {
  return robust_sigma(differences(g, binomial_smoothed(g))) / kResidualGain;
}

// The universal threshold (Donoho and Johnstone): of n Gaussian values of sigma 1, none is likely to exceed
// sqrt(2 ln n); a difference beyond it times the noise's sigma is a feature, not noise.
double universal_threshold(std::size_t n) { return std::sqrt(2.0 * std::log(std::max<double>(2.0, n))); }

// The slopes along one axis across an edge between two texels: a_out, a (the texel before the edge and the one before
// it), b, b_out (the texel after it and the one after that).
using EdgeSlopes = std::array<double, 4>;

// How far a height change `dh` over 1 px lies outside what the slopes of the two texels explain, signed. A
// continuous surface whose slope goes from a to b changes by anything between them (a kink or a rim between the
// centres included). A smooth surface's slope may also peak between the centres, as on a relief near the texel
// period: over the edge it changes by the mean of its slope there, which the trapezoid rule with its end
// correction estimates from the slopes one texel further out on each side (a_out before a, b_out after b):
// (a + b) / 2 - (c_b - c_a) / 12, the curvatures c by central differences of the slopes. That is explained too;
// only the excess beyond all of these is not.
double unexplained(double dh, const EdgeSlopes& s) {
  const auto [a_out, a, b, b_out] = s;
  const double smooth = 0.5 * (a + b) - ((b_out - b) - (a - a_out)) / 24.0;
  const double lo = std::min({a, b, smooth}), hi = std::max({a, b, smooth});
  return dh < lo ? dh - lo : (dh > hi ? dh - hi : 0.0);
}

// Whether the texels resolve the relief around an edge whose unexplained change is `e`: the slopes beside the edge
// (from each of its texels to the one further out) change by at most kAliasedSlopeChange times e. Relief that varies
// faster than the texels resolve (a grating at about the texel period, met at an angle) aliases in the heights as it
// does in the normals, and a change they leave unexplained there is no step. A step's own normals change by a
// fraction of it, even smeared by a generator (Sobel: by a quarter of its height, where about 0.6 of it is left
// unexplained: 0.42 of it, a margin of five). On the finest octave (4 px) of a rough relief read by a generator (Sobel
// reads it at 0.64 of its slope, the heights change by 0.9 of it across an edge) most edges fail this test at a factor
// of two; at four, twice as many texels were marked (tests/test_method_hybrid.cpp).
constexpr double kAliasedSlopeChange = 2.0;
bool resolved(const EdgeSlopes& s, double e) {
  const auto [a_out, a, b, b_out] = s;
  return std::max(std::abs(a - a_out), std::abs(b_out - b)) <= kAliasedSlopeChange * std::abs(e);
}

// Whether the unexplained change `e` of an edge is a change of level, `nearby` those of the two edges before it and
// the two after it along the same axis. An opposite change on one of them of comparable size (less than twice `e`'s)
// takes it back within two texels: a spike, a line two texels wide or an alternation of the heights, which is what a
// grating near the texel period and the finest octave (4 px) of a rough relief alias to, not a step. What is left of
// `e` after those must exceed the threshold. (A much larger opposite neighbour is its own step, of which `e` is the
// overshoot of a generator's smeared normals.)
bool is_step(double e, const std::array<double, 4>& nearby, double threshold) {
  if (std::abs(e) <= threshold) return false;
  double kept = e;
  for (double n : nearby) {
    if (n * e < 0.0 && std::abs(n) < 2.0 * std::abs(e)) kept += n;
  }
  return kept * e > threshold * std::abs(e);
}

// Whether a height change `dh` across an edge is a jump between level treads: the two edges before it and the two
// after it along its axis each change by at most kLevelBeside of it, and the slopes of its own two texels
// fall short of it by more than a quarter. Normals that a generator made from the heights (Sobel) or the heights'
// own central differences (a region given no normal map) give the two texels of a step of height h a slope of h / 2
// along an axis-aligned step (3h / 8 across a diagonal one), which explains about half of it: by unexplained alone a
// step of 1 px was no step at the default 0.5 px. Where the heights are level on both sides, nothing of a smooth
// relief is there to explain the change, and all of it is unexplained. A wall the normals show (a cliff 1 px wide, its
// exact normals) gives one of the two texels the wall's slope, at least the change: no jump. The edges beside a step
// change by none of it; on a generator's 8-bit maps of a rough relief (the suite's `fbm`, ad hoc) no edge has four
// such neighbours within a fifth.
constexpr double kLevelBeside = 0.2;
constexpr double kSmearedSlope = 0.75;
// `change_at(k)`: the height change across the edge k edges further along the axis. The slopes, at hand, are read
// first: on a relief the normals explain they are the change's own size, and its neighbours are not read.
template <typename ChangeAt>
bool between_level_treads(double dh, const EdgeSlopes& s, const ChangeAt& change_at) {
  const double size = std::abs(dh);
  if (std::max(std::abs(s[1]), std::abs(s[2])) > kSmearedSlope * size) return false;
  for (const std::int32_t k : {-2, -1, 1, 2}) {
    if (std::abs(change_at(k)) > kLevelBeside * size) return false;
  }
  return true;
}

}  // namespace

DiscontinuityField find_discontinuities(const GradientField& g, const DepthField& d, double threshold,
                                        double depth_step, unsigned threads) {
  // A jump between level treads must be more than one step of the depth map's storage: a single one is how the map
  // rounds a gentle slope (an 8-bit map of a relief 150 px high steps by 0.6 px every few texels), not relief.
  const double jump_floor = std::max(threshold, 1.5 * depth_step);
  const std::int32_t w = g.width, h = g.height;
  auto slopes_x = [&](std::int32_t x, std::int32_t y) {  // across the edge between (x, y) and (x + 1, y)
    return EdgeSlopes{g.at(std::max(x - 1, 0), y).x, g.at(x, y).x, g.at(x + 1, y).x, g.at(std::min(x + 2, w - 1), y).x};
  };
  auto slopes_y = [&](std::int32_t x, std::int32_t y) {  // between (x, y) and (x, y + 1)
    return EdgeSlopes{g.at(x, std::max(y - 1, 0)).y, g.at(x, y).y, g.at(x, y + 1).y, g.at(x, std::min(y + 2, h - 1)).y};
  };
  auto change_x = [&](std::int32_t x, std::int32_t y) {  // 0 outside
    return x < 0 || x + 1 >= w ? 0.0 : static_cast<double>(d.at(x + 1, y)) - d.at(x, y);
  };
  auto change_y = [&](std::int32_t x, std::int32_t y) {
    return y < 0 || y + 1 >= h ? 0.0 : static_cast<double>(d.at(x, y + 1)) - d.at(x, y);
  };
  auto along_x = [&](std::int32_t x, std::int32_t y) {  // 0 outside
    if (x < 0 || x + 1 >= w) return 0.0;
    const double dh = change_x(x, y);
    const EdgeSlopes s = slopes_x(x, y);
    if (std::abs(dh) > jump_floor && between_level_treads(dh, s, [&](std::int32_t k) { return change_x(x + k, y); }))
      return dh;
    return unexplained(dh, s);
  };
  auto along_y = [&](std::int32_t x, std::int32_t y) {
    if (y < 0 || y + 1 >= h) return 0.0;
    const double dh = change_y(x, y);
    const EdgeSlopes s = slopes_y(x, y);
    if (std::abs(dh) > jump_floor && between_level_treads(dh, s, [&](std::int32_t k) { return change_y(x, y + k); }))
      return dh;
    return unexplained(dh, s);
  };
  // Which edges are steps, in bands of rows on threads of their own: bit 0 of a texel the edge to its right, bit 1
  // the edge below it. A band writes only its own rows, so the bands agree to the bit with one band.
  constexpr std::uint8_t kStepRight = 1, kStepBelow = 2;
  Grid<std::uint8_t> steps(w, h, 0);
  auto find_in_band = [&](RowRange rows) {
    // Each edge's change is read by itself and by the four edges nearest along its axis: computed once, a row of the
    // edges along x at a time and the rows of edges along y two either side of the one being tested.
    std::vector<double> across_x(static_cast<std::size_t>(w));
    constexpr std::int32_t kRows = 5;
    std::vector<std::vector<double>> across_y(kRows, std::vector<double>(static_cast<std::size_t>(w)));
    auto fill_row_y = [&](std::int32_t y) {
      for (std::int32_t x = 0; x < w; ++x)
        across_y[static_cast<std::size_t>(y % kRows)][static_cast<std::size_t>(x)] = along_y(x, y);
    };
    auto edge_x = [&](std::int32_t x) { return x < 0 || x + 1 >= w ? 0.0 : across_x[static_cast<std::size_t>(x)]; };
    auto edge_y = [&](std::int32_t x, std::int32_t y) {
      return y < 0 || y + 1 >= h ? 0.0 : across_y[static_cast<std::size_t>(y % kRows)][static_cast<std::size_t>(x)];
    };
    for (std::int32_t y = std::max(0, rows.begin - 2); y < std::min(h, rows.begin + 2); ++y) fill_row_y(y);
    for (std::int32_t y = rows.begin; y < rows.end; ++y) {
      if (y + 2 < h) fill_row_y(y + 2);
      for (std::int32_t x = 0; x < w; ++x) across_x[static_cast<std::size_t>(x)] = along_x(x, y);
      for (std::int32_t x = 0; x < w; ++x) {
        std::uint8_t found = 0;
        if (x + 1 < w) {
          const double e = edge_x(x);
          const std::array<double, 4> nearby{edge_x(x - 2), edge_x(x - 1), edge_x(x + 1), edge_x(x + 2)};
          if (is_step(e, nearby, threshold) && resolved(slopes_x(x, y), e)) found |= kStepRight;
        }
        if (y + 1 < h) {
          const double e = edge_y(x, y);
          const std::array<double, 4> nearby{edge_y(x, y - 2), edge_y(x, y - 1), edge_y(x, y + 1), edge_y(x, y + 2)};
          if (is_step(e, nearby, threshold) && resolved(slopes_y(x, y), e)) found |= kStepBelow;
        }
        steps.at(x, y) = found;
      }
    }
  };
  for_row_bands_on_threads(h, threads, find_in_band);
  // Both texels of each step.
  DiscontinuityField marks(w, h, 0);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      const bool marked = (steps.at(x, y) != 0) || (x > 0 && (steps.at(x - 1, y) & kStepRight) != 0) ||
                          (y > 0 && (steps.at(x, y - 1) & kStepBelow) != 0);
      marks.at(x, y) = marked ? 1 : 0;
    }
  }
  return marks;
}

namespace {

// The marks and the band a generator smeared around them: every 8-neighbour of a texel of the band that is level with
// it (heights within `threshold` px), flatter than it (the length of the gradient less by more than
// kSmearDecrement x `threshold`, or less than a quarter of it: a residue) and not sloping against it (the two
// gradients' dot product not negative) joins the band, and passes it on in turn. A generator smears a step's normals
// over the texels of its edge and the ones beside them (Sobel across a diagonal step of height h: 3h/8 and h/8 along
// each axis either side of the line), and curvature's reading of a texel, which pairs its normal with those of the
// texels behind it (any of its 8 neighbours, by the direction of the motion), would feel the smeared normals as a
// wall where the heights are level. Depth's C/D there is the height change along the motion: the step's where the
// motion crosses it, none beside it. A smear slopes one way, up the step; a level neighbour sloping the other way is
// relief of its own (a crest beside a false mark on a rough relief). Each texel that joins is flatter than the one
// that passed the band on, by more than kSmearDecrement x `threshold` or to less than a quarter of its steepness, so
// the band ends where the gradients stop falling that fast.
// A diagonal step of height h smeared by Sobel has gradients of length 0.53 h on its edge's texels, 0.18 h beside them
// and 0 beyond: the band falls by 0.35 h and then by 0.18 h. A decrement of 0.4 x `threshold` passes it on to the flat
// texels beyond from h = 2.26 x `threshold` (1.13 px at the default 0.5 px; `threshold` itself did from 5.66 x,
// 2.83 px); below that the fall from 0.18 h to 0, to none of it, does (the suite's terraces of 1 px: C/D error 0.188
// against depth's 0.179 and a travel sensitivity above curvature's without it, depth's to every digit with it). A
// smooth relief's gradients fall by a quarter and more between neighbours only where they are small (a dome's foot):
// on the hybrid's 32 px dome whose depth map holds half the normals' relief, where the step test marks a third of the
// texels (tests/test_tool.cpp), a decrement of 0.3 x `threshold` instead took the band over two thirds.
constexpr double kSmearDecrement = 0.4;
constexpr double kSmearResidue = 0.75;
DiscontinuityField with_smeared_neighbours(const DiscontinuityField& marks, const GradientField& g, const DepthField& d,
                                           double threshold) {
  const std::int32_t w = marks.width, h = marks.height;
  DiscontinuityField out = marks;
  auto steepness = [&](std::int32_t x, std::int32_t y) { return std::hypot(g.at(x, y).x, g.at(x, y).y); };
  std::vector<std::pair<std::int32_t, std::int32_t>> to_pass_on;
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      if (marks.at(x, y) != 0) to_pass_on.emplace_back(x, y);
    }
  }
  while (!to_pass_on.empty()) {
    const auto [x, y] = to_pass_on.back();
    to_pass_on.pop_back();
    const double level = d.at(x, y), steep = steepness(x, y);
    for (std::int32_t v = std::max(0, y - 1); v <= std::min(h - 1, y + 1); ++v) {
      for (std::int32_t u = std::max(0, x - 1); u <= std::min(w - 1, x + 1); ++u) {
        if (out.at(u, v) != 0 || std::abs(d.at(u, v) - level) > threshold) continue;
        const double flatter_by = steep - steepness(u, v);
        if (flatter_by <= kSmearDecrement * threshold && !(flatter_by > kSmearResidue * steep)) continue;
        const Gradient a = g.at(x, y), b = g.at(u, v);
        if (static_cast<double>(a.x) * b.x + static_cast<double>(a.y) * b.y < 0.0) continue;
        out.at(u, v) = 1;
        to_pass_on.emplace_back(u, v);
      }
    }
  }
  return out;
}

// The unit normal's x and y of a slope: what a normal map stores, so that its rounding is the same everywhere.
std::array<double, 2> normal_xy(Gradient g) {
  const double gx = g.x, gy = g.y, length = std::sqrt(1.0 + gx * gx + gy * gy);
  return {gx / length, gy / length};
}

// The texels that one figure of a whole region reads: every one up to 2^17, every k-th beyond (the median of a quarter
// of a million values gives it to a few parts in a thousand, and a full-HD region's load would otherwise take a fifth
// longer).
constexpr std::size_t kDecisionTexels = std::size_t{1} << 17;

// The robust sigma of the difference between the unit normals' x and y of two slopes, `pair(x, y)`, at the texels of
// a w x h field that one figure of a region reads: it decides one thing for the whole region.
template <typename Pair>
double robust_sigma_of_normals(std::int32_t w, std::int32_t h, const Pair& pair) {
  const std::size_t texels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const std::size_t stride = sample_stride(texels, w, kDecisionTexels);
  std::vector<double> out;
  out.reserve(2 * (texels / stride + 1));
  for (std::size_t i = 0; i < texels; i += stride) {
    const auto [a, b] = pair(static_cast<std::int32_t>(i % static_cast<std::size_t>(w)),
                             static_cast<std::int32_t>(i / static_cast<std::size_t>(w)));
    const auto [ax, ay] = normal_xy(a);
    const auto [bx, by] = normal_xy(b);
    out.push_back(std::abs(ax - bx));
    out.push_back(std::abs(ay - by));
  }
  return robust_sigma(std::move(out));
}

// A texel's gradient and its four neighbours', the border texels repeated.
struct Cross {
  Gradient c, left, right, up, down;
};
Cross cross_at(const GradientField& f, std::int32_t x, std::int32_t y) {
  return {f.at(x, y), f.at(std::max(x - 1, 0), y), f.at(std::min(x + 1, f.width - 1), y), f.at(x, std::max(y - 1, 0)),
          f.at(x, std::min(y + 1, f.height - 1))};
}

// A normal-map generator's reading of a height image at (x, y), from its central differences `d`: those smoothed
// [1 2 1] / 4 across their axis, which is the Sobel filter (divided by 8, so that a plane's slope comes out as it is).
Gradient sobel_reading(const GradientField& d, std::int32_t x, std::int32_t y) {
  const auto [c, left, right, up, down] = cross_at(d, x, y);
  return {c.x + 0.25f * ((up.x - c.x) + (down.x - c.x)), c.y + 0.25f * ((left.y - c.y) + (right.y - c.y))};
}

// The normals' own mean at (x, y) over the 2 px a central difference spans, by Simpson's rule: [1 4 1] / 6 along
// each component's axis.
Gradient simpson_mean(const GradientField& g, std::int32_t x, std::int32_t y) {
  const auto [n, left, right, up, down] = cross_at(g, x, y);
  return {n.x + ((left.x - n.x) + (right.x - n.x)) / 6.0f, n.y + ((up.y - n.y) + (down.y - n.y)) / 6.0f};
}

// The heights' derivative at a texel as the relief they sample would have it if it held no detail finer than the
// texels resolve (band-limited: periods above 2 px along each axis): the derivative of their sinc interpolation,
// sum over n of (-1)^(n+1) / n x (h(x + n) - h(x - n)), its taps tapered by a Hann window so that the sum ends. With
// 12 taps a side it reads a sine of any period from 2.83 px up within 0.2 % of its slope, where a central difference
// reads a 3 px grating at 0.41 of it and Simpson's mean of its normals at 0.5. Within 12 texels of the region's edge
// along an axis the central difference stands in.
constexpr std::int32_t kBandLimitedTaps = 12;
class BandLimitedDerivative {
 public:
  BandLimitedDerivative() {
    for (std::int32_t n = 1; n <= kBandLimitedTaps; ++n) {
      const double hann = 0.5 * (1.0 + std::cos(std::numbers::pi * n / (kBandLimitedTaps + 1)));
      taps_[static_cast<std::size_t>(n - 1)] = (n % 2 == 1 ? 1.0 : -1.0) / n * hann;
    }
  }
  // At (x, y) of `depth`, `central` its central differences.
  Gradient at(const DepthField& depth, const GradientField& central, std::int32_t x, std::int32_t y) const {
    constexpr std::int32_t N = kBandLimitedTaps;
    Gradient out = central.at(x, y);
    if (x >= N && x + N < depth.width) {
      out.x = sum([&](std::int32_t n) { return static_cast<double>(depth.at(x + n, y)) - depth.at(x - n, y); });
    }
    if (y >= N && y + N < depth.height) {
      out.y = sum([&](std::int32_t n) { return static_cast<double>(depth.at(x, y + n)) - depth.at(x, y - n); });
    }
    return out;
  }

 private:
  template <typename Difference>
  float sum(const Difference& difference) const {
    double s = 0.0;
    for (std::int32_t n = 1; n <= kBandLimitedTaps; ++n) s += taps_[static_cast<std::size_t>(n - 1)] * difference(n);
    // Clamped as gradient_from_depth clamps: heights near the float's limit would sum beyond it.
    return static_cast<float>(std::clamp(s, -static_cast<double>(kMaxSlope), static_cast<double>(kMaxSlope)));
  }
  std::array<double, kBandLimitedTaps> taps_{};
};

// How far the normals `g` lie from what the depth map says they are, `d` its central differences: the robust sigma
// of their difference (as unit normals) for each of four readings of the heights. Its central differences; a
// generator's (sobel_reading); the normals' own mean over the 2 px a central difference spans (simpson_mean),
// against the central differences: a relief's exact normals at the texel centres and
// its exact heights agree so to the fourth order, where a central difference alone flattens a grating of period 8 px
// by a tenth; and the band-limited derivative of the heights (BandLimitedDerivative), with which the exact samples of
// relief down to 2.83 px agree, a grating of 3 px included. Generators and exact samples differ in their finest
// detail, which neither reads as the other does, so the closest reading is the one that explains the normals.
struct Disagreement {
  double central, sobel, simpson, band_limited;
  double closest() const { return std::min({central, sobel, simpson, band_limited}); }
};
Disagreement disagreement_with_depth(const GradientField& g, const GradientField& d, const DepthField& depth) {
  const std::int32_t w = g.width, h = g.height;
  Disagreement out{};
  out.central = robust_sigma_of_normals(w, h, [&](std::int32_t x, std::int32_t y) {
    return std::pair{g.at(x, y), d.at(x, y)};
  });
  out.sobel = robust_sigma_of_normals(w, h, [&](std::int32_t x, std::int32_t y) {
    return std::pair{g.at(x, y), sobel_reading(d, x, y)};
  });
  out.simpson = robust_sigma_of_normals(w, h, [&](std::int32_t x, std::int32_t y) {
    return std::pair{simpson_mean(g, x, y), d.at(x, y)};
  });
  const BandLimitedDerivative band_limited;
  out.band_limited = robust_sigma_of_normals(w, h, [&](std::int32_t x, std::int32_t y) {
    return std::pair{g.at(x, y), band_limited.at(depth, d, x, y)};
  });
  return out;
}

// The robust sigma of a uniform rounding is 1.28 times its sigma (the median of |u| is a quarter of the step);
// normals that a generator made from the heights and then rounded disagree with them by that and a little of the
// heights' own rounding. Twice the rounding's sigma covers both; the suite's noisy and quantised maps lie at 2.6
// times and beyond (docs/METHODS.md, "Hybrid").
constexpr double kExplainedRounding = 2.0;

// The Sobel filter's weights on the six heights it reads, (+-1, +-2, +-1) / 8, make a slope whose rounding is
// sqrt(12) / 8 times the heights'.
constexpr double kSobelRoundingGain = 0.4330127018922193;

// Normals a generator made from this depth map (its reading explains them best, and within their storage's rounding,
// as fuse_with_depth_gradient asks) carry nothing the heights do not, and their own rounding besides: where the
// heights are stored finer than that (a 16-bit height image and its 8-bit normal map), the generator's reading is
// taken again from the heights, and the rounding left is the heights' through the filter. Returns whether it was.
bool reread_from_depth(const GradientField& from_depth, const Disagreement& disagreement, double depth_rounding,
                       GradientField& g, double& rounding) {
  const double reread_rounding = kSobelRoundingGain * depth_rounding;
  // The generator's reading must explain the normals better than the others do: a gradient made from this depth
  // map's central differences (a region given no normal map) is that reading exactly, and stays.
  const bool generated =
      disagreement.sobel < std::min({disagreement.central, disagreement.simpson, disagreement.band_limited}) &&
      disagreement.sobel <= kExplainedRounding * rounding;
  if (!generated || !(reread_rounding < rounding)) return false;
  for (std::int32_t y = 0; y < g.height; ++y) {
    for (std::int32_t x = 0; x < g.width; ++x) g.at(x, y) = sobel_reading(from_depth, x, y);
  }
  rounding = reread_rounding;
  return true;
}

// The normals and the depth map's central differences are two estimates of the same slopes. Where the normals
// are not what the depth map says they are (disagreement_with_depth) beyond the map's rounding (`noise_slope` at the
// universal threshold, or twice the rounding of the normals' storage, `rounding`), each texel whose disagreement is
// noise-like (within the universal threshold of its robust sigma) and that is no discontinuity takes their
// inverse-variance mean, each field's variance estimated from its own residual: noisy normals over a clean depth
// map become the depth map's slopes, clean normals over a coarse depth map stay as they are. Normals the depth map
// explains carry no noise of their own for it to take out: fusing them would trade the detail one reading resolves
// for the other's. Returns the normals' weight where it fused.
std::optional<double> fuse_with_depth_gradient(const GradientField& from_depth, const Disagreement& disagreement,
                                               const DiscontinuityField& marks, double noise_slope, double rounding,
                                               GradientField& g) {
  const double threshold = universal_threshold(2 * g.values.size());
  const double unexplained = disagreement.closest();
  if (threshold * unexplained <= noise_slope || unexplained <= kExplainedRounding * rounding) return std::nullopt;
  const double band = threshold * robust_sigma(differences(g, from_depth));
  const double vn = std::pow(gradient_noise(g), 2), vd = std::pow(gradient_noise(from_depth), 2);
  if (vn + vd <= 0.0) return std::nullopt;
  const double normals_weight = vd / (vn + vd);
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    const Gradient n = g.values[i], d = from_depth.values[i];
    if (marks.values[i] != 0 || std::abs(n.x - d.x) > band || std::abs(n.y - d.y) > band) continue;
    g.values[i] = {static_cast<float>(d.x + normals_weight * (n.x - d.x)),
                   static_cast<float>(d.y + normals_weight * (n.y - d.y))};
  }
  return normals_weight;
}

// The noise band at the region's highest height: what rounding to the map's storage can make of the gradient
// (`rounding`, its sigma, to the universal threshold), and no more than `noise_slope` nor than the noise the map
// shows. The residual from the smoothed field of a map with fine steps (16 bits, float) is its relief's own
// curvature, not noise, and its relief is kept (on a float ridge, with the band from the map's residual alone, the
// apex and the feet were smoothed). The noise shown is estimated by the universal threshold over the texels whose
// residual is not zero: those of an area decoded exactly flat carry no information on it.
double noise_band(double noise_slope, double rounding, const GradientField& g, const GradientField& s) {
  std::vector<double> residual = differences(g, s);
  std::erase(residual, 0.0);
  const std::size_t tested = residual.size() * sample_stride(g.values.size(), g.width);  // nonzero, all texels
  const double threshold = universal_threshold(tested);
  return std::min({noise_slope, threshold * robust_sigma(residual) / kResidualGain, threshold * rounding});
}

// Smoothing flattens relief as well as rounding: the smoothed field s = K g is off the relief's own slope by about
// (K - 1) g, which on a finely stored map (12 bits) is larger than the rounding it takes out, and always makes a
// relief feel lower (a stroke's motor travel). K s - s estimates that bias from the smoothed field; taking it off
// (Tukey's "twicing", 2 K g - K K g) leaves a bias of the order (K - 1)^2 g and more of the rounding: the kernel
// K - K K passes white noise of sigma r at kTwicingNoiseGain r (the root of the sum of its squared taps), where K
// passes 0.27 r. So the correction is made only where it is larger than the rounding could make it, at the universal
// threshold: on a 12-bit map's Gaussian hill nearly everywhere, on an 8-bit map where the relief bends sharply.
constexpr double kTwicingNoiseGain = 0.1075;
Gradient with_bias_taken_off(Gradient s, Gradient ss, double least) {
  auto component = [least](float s1, float ss1) {
    const double bias = static_cast<double>(s1) - ss1;
    return std::abs(bias) > least ? static_cast<float>(s1 + bias) : s1;
  };
  return {component(s.x, ss.x), component(s.y, ss.y)};
}

// Replaces each gradient by the smoothed one where they differ by at most the noise band, wider further from the
// viewer: within the band the difference is the map's noise (rounding, a generator's jitter); beyond it, a
// feature (a rim, a kink), which stays sharp. The smoothed value's bias is taken off (with_bias_taken_off) where the
// result is within the band too: beside a rim the twice-smoothed field is pulled by the rim, and so no texel moves
// by more than the band. Returns how many texels it smoothed, and at how many of those it took the flattening off.
struct SmoothingCounts {
  std::size_t smoothed = 0, unflattened = 0;
};
SmoothingCounts smooth_within_band(const HybridParams& params, double rounding, const DepthField* depth,
                                   GradientField& g) {
  SmoothingCounts counts;
  if (rounding <= 0.0) return counts;  // a float map: no rounding to smooth
  const GradientField s = binomial_smoothed(g);
  const GradientField ss = binomial_smoothed(s);
  const double least_bias = universal_threshold(2 * g.values.size()) * kTwicingNoiseGain * rounding;
  const double base = noise_band(params.noise_slope, rounding, g, s);
  float lowest = 0.0f, highest = 0.0f;
  if (depth != nullptr) {
    const auto [lo, hi] = std::minmax_element(depth->values.begin(), depth->values.end());
    lowest = *lo;
    highest = *hi;
  }
  const double range = static_cast<double>(highest) - lowest;
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    const double farness = range > 0.0 ? (highest - static_cast<double>(depth->values[i])) / range : 0.0;
    const double band = base * (1.0 + params.far_noise_gain * farness);
    auto within_band = [&](Gradient v) {
      return std::abs(v.x - g.values[i].x) <= band && std::abs(v.y - g.values[i].y) <= band;
    };
    if (!within_band(s.values[i])) continue;
    const Gradient t = with_bias_taken_off(s.values[i], ss.values[i], least_bias);
    const bool unflattened = within_band(t) && (t.x != s.values[i].x || t.y != s.values[i].y);
    g.values[i] = unflattened ? t : s.values[i];
    ++counts.smoothed;
    counts.unflattened += unflattened ? 1 : 0;
  }
  return counts;
}

// Central differences whose rounding would move the slope ratio by more than a few per cent are not read: 10 times the
// sigma of a central difference's rounding (a height's over sqrt(2)), and not below 0.02 (about 1 degree, where a
// float map's differences are exact but the relief is all but flat).
double ratio_floor(double depth_rounding) { return std::max(0.02, 10.0 * depth_rounding / std::sqrt(2.0)); }

// Whether a slope along an axis, `s` with its neighbours' `before` and `after` on that axis, is relief the texels
// resolve: clear of `floor`, and its second difference within a fifth of it. A central difference reads a sine of
// period P at sin(w) / w of its slope (w = 2 pi / P), where the slope's second difference is 4 sin^2(w / 2) of it:
// within a fifth from 12 px up, read within 5 %. Kinks (a roof's apex, the foot of a wall), a step's smeared slopes
// and relief near the texel period are not.
bool resolved_slope(float before, float s, float after, double floor) {
  return std::abs(s) > floor && std::abs(static_cast<double>(after) - 2.0 * s + before) <= 0.2 * std::abs(s);
}

}  // namespace

SlopeComparison compare_slopes_with_depth(const GradientField& g, const GradientField& from_depth,
                                          const DiscontinuityField& marks, double floor) {
  const auto w = static_cast<std::size_t>(g.width), h = static_cast<std::size_t>(g.height);
  if (w < 3 || h < 3) return {};
  // Whole rows, every k-th, about as many texels as a region's other figures read: a row and its neighbours are read in
  // order (a full-HD region's preparation takes 5-8 ms more for it, about twice that with single texels strewn over
  // the region; bench_load, ad hoc).
  const std::size_t row_stride = std::max<std::size_t>(1, w * h / kDecisionTexels);
  std::vector<double> unmarked, all;  // ratios of one sign
  std::array<std::size_t, 2> both{}, opposite{};
  std::size_t normals_resolved = 0, depth_flat = 0;
  // One axis of texel i, its neighbours `step` apart.
  const auto read = [&](std::size_t i, std::size_t step, auto axis, int a) {
    const float n = axis(g.values[i]), d = axis(from_depth.values[i]);
    if (!resolved_slope(axis(g.values[i - step]), n, axis(g.values[i + step]), floor)) return;
    ++normals_resolved;
    if (!resolved_slope(axis(from_depth.values[i - step]), d, axis(from_depth.values[i + step]), floor)) {
      depth_flat += std::abs(d) <= floor ? 1 : 0;
      return;
    }
    ++both[a];
    if ((n > 0) != (d > 0)) {
      ++opposite[a];
      return;
    }
    const double ratio = static_cast<double>(n) / d;
    all.push_back(ratio);
    // Along the axis the difference spans the texel's neighbours: none of the three may be a step.
    if ((marks.values[i - step] | marks.values[i] | marks.values[i + step]) == 0) unmarked.push_back(ratio);
  };
  for (std::size_t y = 1; y + 1 < h; y += row_stride) {
    for (std::size_t x = 1; x + 1 < w; ++x) {
      const std::size_t i = y * w + x;
      read(
          i, 1, [](Gradient v) { return v.x; }, 0);
      read(
          i, w, [](Gradient v) { return v.y; }, 1);
    }
  }
  constexpr std::size_t kEnough = 100;
  const auto median = [](std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  const auto share = [](std::size_t part, std::size_t of) {
    return of >= kEnough ? std::optional<double>(static_cast<double>(part) / static_cast<double>(of)) : std::nullopt;
  };
  SlopeComparison c;
  if (unmarked.size() >= kEnough) {
    c.ratio = median(unmarked);
  } else if (all.size() >= kEnough) {
    c.ratio = median(all);
  }
  c.opposite_x = share(opposite[0], both[0]);
  c.opposite_y = share(opposite[1], both[1]);
  c.depth_flat = share(depth_flat, normals_resolved);
  return c;
}

std::string validate(const HybridParams& p) {
  if (!(std::isfinite(p.discontinuity_px) && p.discontinuity_px > 0.0))
    return "discontinuity_px must be a finite number > 0";
  if (!finite_non_negative(p.noise_slope)) return "noise_slope must be a finite number >= 0";
  if (!finite_non_negative(p.far_noise_gain)) return "far_noise_gain must be a finite number >= 0";
  return {};
}

void prepare_hybrid_fields(const HybridParams& params, RegionFields& fields) {
  if (!fields.gradient || fields.discontinuity) return;  // prepared once: a scene built again keeps its fields
  GradientField& g = *fields.gradient;
  const bool has_depth = fields.depth && fields.depth->width == g.width && fields.depth->height == g.height;
  // noise_slope 0 asks for the normals as given: neither read again, nor fused, nor smoothed.
  std::optional<GradientField> from_depth;
  std::optional<Disagreement> disagreement;
  bool reread = false;
  if (has_depth && params.noise_slope > 0.0) {
    from_depth = gradient_from_depth(*fields.depth);
    disagreement = disagreement_with_depth(g, *from_depth, *fields.depth);
    reread = reread_from_depth(*from_depth, *disagreement, fields.depth_rounding, g, fields.gradient_rounding);
  }
  fields.discontinuity =
      has_depth ? with_smeared_neighbours(find_discontinuities(g, *fields.depth, params.discontinuity_px,
                                                               depth_step_of_rounding(fields.depth_rounding)),
                                          g, *fields.depth, params.discontinuity_px)
                : DiscontinuityField(g.width, g.height, 0);
  if (has_depth) {
    fields.slope_comparison =
        compare_slopes_with_depth(g, from_depth ? *from_depth : gradient_from_depth(*fields.depth),
                                  *fields.discontinuity, ratio_floor(fields.depth_rounding));
  }
  if (params.noise_slope <= 0.0) return;
  // Normals read again from the heights are the depth map's own reading: nothing to fuse.
  if (has_depth && !reread) {
    fields.fused_normals_weight = fuse_with_depth_gradient(*from_depth, *disagreement, *fields.discontinuity,
                                                           params.noise_slope, fields.gradient_rounding, g);
  }
  const SmoothingCounts counts =
      smooth_within_band(params, fields.gradient_rounding, has_depth ? &*fields.depth : nullptr, g);
  fields.smoothed_texels = counts.smoothed;
  fields.unflattened_texels = counts.unflattened;
}

void HybridMethod::prepare(RegionFields& fields) const { prepare_hybrid_fields(params_, fields); }

HybridParams HybridMethod::parse_params(const ParamReader& reader) {
  HybridParams p;
  if (const auto v = reader.number("discontinuity_px")) p.discontinuity_px = *v;
  if (!(std::isfinite(p.discontinuity_px) && p.discontinuity_px > 0.0))
    reader.reject("discontinuity_px", "must be a finite number > 0 (px of height)");
  if (const auto v = reader.number("noise_slope")) p.noise_slope = *v;
  if (!finite_non_negative(p.noise_slope))
    reader.reject("noise_slope", "must be a finite number >= 0 (0: no smoothing)");
  if (const auto v = reader.number("far_noise_gain")) p.far_noise_gain = *v;
  if (!finite_non_negative(p.far_noise_gain)) reader.reject("far_noise_gain", "must be a finite number >= 0");
  return p;
}

HybridMethod::HybridMethod(const HybridParams& params) : Method(method_tag<HybridMethod>()), params_(params) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("hybrid method: " + error);
}

}  // namespace ph
