#include "core/effects/patterns.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace ph {
namespace {

constexpr std::int32_t kInvalid = -1;  // level index of a non-finite value

// Number of levels <= v (levels ascending), trying the neighbour's answer first: on a smooth field it
// is almost always right, and the binary search is the fallback for rough ones.
std::int32_t level_index(double v, const std::vector<double>& levels, std::int32_t hint) {
  if (!std::isfinite(v)) return kInvalid;
  const auto n = static_cast<std::int32_t>(levels.size());
  if (hint >= 0 && hint <= n) {
    const bool above_lower = hint == 0 || levels[static_cast<std::size_t>(hint - 1)] <= v;
    const bool below_upper = hint == n || v < levels[static_cast<std::size_t>(hint)];
    if (above_lower && below_upper) return hint;
  }
  return static_cast<std::int32_t>(std::upper_bound(levels.begin(), levels.end(), v) - levels.begin());
}

struct Cell {
  double v = 0.0;
  std::int32_t k = kInvalid;
};

// Marks, for each level crossed between neighbours a and b, the one nearer the level.
void mark_crossings(const Cell& a, std::uint8_t& ma, const Cell& b, std::uint8_t& mb,
                    const std::vector<double>& levels) {
  if (a.k == b.k || a.k == kInvalid || b.k == kInvalid) return;
  const std::int32_t lo = std::min(a.k, b.k);
  const std::int32_t hi = std::max(a.k, b.k);
  const bool a_above = a.k > b.k;
  for (std::int32_t j = lo; j < hi; ++j) {
    const double level = levels[static_cast<std::size_t>(j)];
    const double da = std::abs(a.v - level);
    const double db = std::abs(b.v - level);
    if (da < db || (da == db && a_above)) {
      ma = 1;
    } else {
      mb = 1;
    }
  }
}

bool within_band(const Cell& c, const std::vector<double>& levels, double tol) {
  if (c.k == kInvalid) return false;
  const auto k = static_cast<std::size_t>(c.k);
  return (k > 0 && c.v - levels[k - 1] < tol) || (k < levels.size() && levels[k] - c.v < tol);
}

// The mask of a value field given row by row: fill_row(y, double* out) writes row y's values.
// Two rows of values are kept, never a whole-region copy.
template <typename FillRow>
Grid<std::uint8_t> mark_pattern(std::int32_t w, std::int32_t h, const std::vector<double>& levels, PatternRule rule,
                                double tol, FillRow fill_row) {
  Grid<std::uint8_t> mask(std::max(w, 0), std::max(h, 0), 0);
  if (mask.empty() || levels.empty()) return mask;
  const auto n = static_cast<std::size_t>(w);
  std::vector<double> values(n);
  std::vector<Cell> prev(n);
  std::vector<Cell> cur(n);
  std::int32_t hint = 0;
  for (std::int32_t y = 0; y < h; ++y) {
    fill_row(y, values.data());
    for (std::size_t x = 0; x < n; ++x) {
      cur[x].v = values[x];
      cur[x].k = level_index(values[x], levels, hint);
      if (cur[x].k != kInvalid) hint = cur[x].k;
    }
    std::uint8_t* row = &mask.values[static_cast<std::size_t>(y) * n];
    if (rule == PatternRule::band) {
      for (std::size_t x = 0; x < n; ++x) row[x] = within_band(cur[x], levels, tol) ? 1 : 0;
    } else {
      std::uint8_t* above = y > 0 ? row - n : nullptr;
      for (std::size_t x = 0; x < n; ++x) {
        if (x + 1 < n) mark_crossings(cur[x], row[x], cur[x + 1], row[x + 1], levels);
        if (above != nullptr) mark_crossings(prev[x], above[x], cur[x], row[x], levels);
      }
    }
    std::swap(prev, cur);
  }
  return mask;
}

void check(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

std::vector<double> contour_levels(const DepthField& depth, const ContourParams& params) {
  check(params.count >= 0 && params.count <= kMaxContourLevels, "contour count must be 0 to 4096");
  check(params.levels.size() <= static_cast<std::size_t>(kMaxContourLevels), "at most 4096 contour levels");
  std::vector<double> levels;
  if (!params.levels.empty()) {
    for (double l : params.levels) check(std::isfinite(l), "contour levels must be finite");
    levels = params.levels;
  } else {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (float v : depth.values) {
      if (!std::isfinite(v)) continue;
      lo = std::min(lo, static_cast<double>(v));
      hi = std::max(hi, static_cast<double>(v));
    }
    if (!(hi > lo)) return levels;  // flat, empty or all non-finite: nothing to cross
    for (std::int32_t k = 1; k <= params.count; ++k) levels.push_back(lo + (hi - lo) * k / (params.count + 1));
  }
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  return levels;
}

double light_length(const LightVector& light) { return std::hypot(light.x, light.y, light.z); }

Grid<std::uint8_t> isophote_mask(const GradientField& gradient, const IsophoteParams& params) {
  const LightVector& l = params.light;
  const double len = light_length(l);
  check(std::isfinite(len) && len > 0.0, "the light vector must be finite and non-zero");
  check(params.cos_alpha >= -1.0 && params.cos_alpha <= 1.0, "cos_alpha must be in [-1, 1]");
  check(std::isfinite(params.tol) && params.tol >= 0.0, "isophote tolerance must be finite and >= 0");
  const double lx = l.x / len;
  const double ly = l.y / len;
  const double lz = l.z / len;
  const std::vector<double> levels{params.cos_alpha};
  const std::int32_t w = gradient.width;
  return mark_pattern(w, gradient.height, levels, params.rule, params.tol, [&](std::int32_t y, double* out) {
    const Gradient* g = &gradient.values[static_cast<std::size_t>(y) * static_cast<std::size_t>(w)];
    for (std::int32_t x = 0; x < w; ++x) {
      const double gx = g[x].x;
      const double gy = g[x].y;
      out[x] = (lz - gx * lx - gy * ly) / std::sqrt(gx * gx + gy * gy + 1.0);  // n·l, n = (-gx, -gy, 1)/|.|
    }
  });
}

Grid<std::uint8_t> contour_mask(const DepthField& depth, const ContourParams& params) {
  check(std::isfinite(params.tol) && params.tol >= 0.0, "contour tolerance must be finite and >= 0");
  const std::vector<double> levels = contour_levels(depth, params);
  const std::int32_t w = depth.width;
  return mark_pattern(w, depth.height, levels, params.rule, params.tol, [&](std::int32_t y, double* out) {
    const float* h = &depth.values[static_cast<std::size_t>(y) * static_cast<std::size_t>(w)];
    for (std::int32_t x = 0; x < w; ++x) out[x] = h[x];
  });
}

PatternField isophote_field(const GradientField& gradient, const IsophoteParams& params, float radius) {
  return make_pattern_field(isophote_mask(gradient, params), radius);
}

PatternField contour_field(const DepthField& depth, const ContourParams& params, float radius) {
  return make_pattern_field(contour_mask(depth, params), radius);
}

}  // namespace ph
