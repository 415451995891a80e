#include "core/effects/distance_transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ph {

double NearestPattern::distance() const { return std::sqrt(static_cast<double>(distance_squared())); }

std::optional<Vec2> PatternField::toward(Vec2 p) const {
  if (!is_finite(p)) return std::nullopt;
  const Texel t = texel_at(p);
  const std::optional<NearestPattern> n = nearest(t);
  if (!n) return std::nullopt;
  return Vec2{t.x + n->dx + 0.5 - p.x, t.y + n->dy + 0.5 - p.y};
}

namespace {

// ceil(num / den) for den > 0, exact: a double quotient is within one of it (|num| < 2^53), and one
// cvttsd2si plus an integer check is cheaper than a 64-bit idiv or a libm ceil on baseline x86-64.
std::int64_t ceil_div(std::int64_t num, std::int64_t den) {
  std::int64_t q = static_cast<std::int64_t>(static_cast<double>(num) / static_cast<double>(den));
  while (q * den < num) ++q;
  while ((q - 1) * den >= num) --q;
  return q;
}

// Pass 1, down the columns in row order (cache-friendly): out.dy = offset to the nearest pattern texel
// in the same column, or kNoPatternComponent when none lies within r texels.
void column_pass(const Grid<std::uint8_t>& mask, std::int32_t r, Grid<PatternOffset>& out) {
  const std::int32_t w = mask.width;
  const std::int32_t h = mask.height;
  constexpr std::int32_t kNone = -1;
  std::vector<std::int32_t> seen(static_cast<std::size_t>(w), kNone);  // last pattern row above, then below
  for (std::int32_t y = 0; y < h; ++y) {
    const std::uint8_t* m = &mask.values[static_cast<std::size_t>(y) * w];
    PatternOffset* o = &out.values[static_cast<std::size_t>(y) * w];
    for (std::int32_t x = 0; x < w; ++x) {
      if (m[x] != 0) seen[x] = y;
      const std::int32_t up = y - seen[x];
      o[x].dy = (seen[x] != kNone && up <= r) ? static_cast<std::int16_t>(-up) : kNoPatternComponent;
    }
  }
  std::fill(seen.begin(), seen.end(), kNone);
  for (std::int32_t y = h - 1; y >= 0; --y) {
    const std::uint8_t* m = &mask.values[static_cast<std::size_t>(y) * w];
    PatternOffset* o = &out.values[static_cast<std::size_t>(y) * w];
    for (std::int32_t x = 0; x < w; ++x) {
      if (m[x] != 0) seen[x] = y;
      if (seen[x] == kNone) continue;
      const std::int32_t down = seen[x] - y;
      if (down <= r && (o[x].dy == kNoPatternComponent || down < -o[x].dy)) o[x].dy = static_cast<std::int16_t>(down);
    }
  }
}

// Scratch of pass 2, one row long, reused across rows.
struct Envelope {
  std::vector<std::int32_t> col_dy;  // the row's pass-1 result
  std::vector<std::int32_t> site;    // columns of the parabolas on the lower envelope
  std::vector<std::int64_t> f;       // their dy² + q²
  std::vector<std::int64_t> start;   // first integer x where each is lowest
};

// Pass 2 along one row: the lower envelope of the parabolas (x - q)² + dy(q)² over the columns q with a
// pattern texel within reach; its argmin at x is the nearest pattern texel of (x, y).
void row_pass(PatternOffset* row, std::int32_t w, std::int64_t r2, Envelope& e) {
  std::int32_t n = 0;
  for (std::int32_t q = 0; q < w; ++q) {
    e.col_dy[q] = row[q].dy;
    if (row[q].dy == kNoPatternComponent) continue;
    const std::int64_t fq = std::int64_t{row[q].dy} * row[q].dy + std::int64_t{q} * q;
    std::int64_t s = 0;
    while (n > 0) {
      // q is at least as low as the top parabola from x = s on.
      s = ceil_div(fq - e.f[n - 1], 2 * std::int64_t{q - e.site[n - 1]});
      if (n > 1 && s <= e.start[n - 1]) {
        --n;  // the top is never strictly lowest at an integer x
        continue;
      }
      break;
    }
    e.site[n] = q;
    e.f[n] = fq;
    e.start[n] = n == 0 ? std::int64_t{-1} : s;
    ++n;
  }
  if (n == 0) {
    std::fill(row, row + w, kNoPattern);
    return;
  }
  std::int32_t k = 0;
  for (std::int32_t x = 0; x < w; ++x) {
    while (k + 1 < n && e.start[k + 1] <= x) ++k;
    const std::int32_t q = e.site[k];
    const std::int64_t dx = q - x;
    const std::int64_t dy = e.col_dy[q];
    // |dx| <= sqrt(r2) <= 32767 whenever the texel is kept, so the casts are exact.
    row[x] = dx * dx + dy * dy <= r2 ? PatternOffset{static_cast<std::int16_t>(dx), static_cast<std::int16_t>(dy)}
                                     : kNoPattern;
  }
}

}  // namespace

PatternField make_pattern_field(const Grid<std::uint8_t>& mask, float radius) {
  PatternField out;
  if (radius > kMaxPatternRadius) {
    out.radius = kMaxPatternRadius;  // +inf included
  } else if (radius > 0.0f) {
    out.radius = radius;  // NaN and negative radii fail both tests and stay 0
  }
  const std::int32_t w = std::max(mask.width, 0);
  const std::int32_t h = std::max(mask.height, 0);
  out.offsets = Grid<PatternOffset>(w, h, kNoPattern);
  if (w == 0 || h == 0 || mask.values.size() != out.offsets.values.size()) return out;

  const double r = out.radius;
  const auto r_int = static_cast<std::int32_t>(std::floor(r));
  const auto r2 = static_cast<std::int64_t>(std::floor(r * r));  // d² <= r² for integer d² <=> d² <= floor(r²)
  column_pass(mask, r_int, out.offsets);
  Envelope e;
  const auto n = static_cast<std::size_t>(w);
  e.col_dy.resize(n);
  e.site.resize(n);
  e.f.resize(n);
  e.start.resize(n);
  for (std::int32_t y = 0; y < h; ++y) row_pass(&out.offsets.values[static_cast<std::size_t>(y) * n], w, r2, e);
  return out;
}

}  // namespace ph
