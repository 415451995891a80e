// Isophote and contour masks (core/effects/patterns.hpp) on small analytic height fields built here, against
// the analytic curves.
#include "core/effects/patterns.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

namespace ph {
namespace {

using Mask = Grid<std::uint8_t>;

// Analytic surface sampled at texel centres (x + 0.5, y + 0.5), relative to a centre off the texel grid
// so that no texel sits exactly on the axis.
constexpr double kCx = 64.3;
constexpr double kCy = 63.6;

struct Point {
  double x;
  double y;
};
Point centred(std::int32_t x, std::int32_t y) { return {x + 0.5 - kCx, y + 0.5 - kCy}; }
double radius_of(std::int32_t x, std::int32_t y) {
  const Point p = centred(x, y);
  return std::hypot(p.x, p.y);
}

DepthField depth_of(std::int32_t w, std::int32_t h, const std::function<double(Point)>& f) {
  DepthField d(w, h);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) d.at(x, y) = static_cast<float>(f(centred(x, y)));
  }
  return d;
}

GradientField gradient_of(std::int32_t w, std::int32_t h, const std::function<std::pair<double, double>(Point)>& g) {
  GradientField out(w, h);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      const auto [gx, gy] = g(centred(x, y));
      out.at(x, y) = {static_cast<float>(gx), static_cast<float>(gy)};
    }
  }
  return out;
}

// Sphere cap h = sqrt(R² - r²) with exact gradient; R beyond the grid's corners.
constexpr double kSphereR = 100.0;
GradientField sphere_gradient(std::int32_t side) {
  return gradient_of(side, side, [](Point p) {
    const double h = std::sqrt(kSphereR * kSphereR - p.x * p.x - p.y * p.y);
    return std::pair{-p.x / h, -p.y / h};
  });
}

std::int64_t count(const Mask& m) {
  std::int64_t n = 0;
  for (auto v : m.values) n += v != 0;
  return n;
}

// 8-connected components of the set texels for which keep(x, y) holds.
int components(const Mask& m, const std::function<bool(std::int32_t, std::int32_t)>& keep) {
  Grid<std::uint8_t> seen(m.width, m.height, 0);
  int found = 0;
  std::vector<Texel> stack;
  for (std::int32_t y = 0; y < m.height; ++y) {
    for (std::int32_t x = 0; x < m.width; ++x) {
      if (m.at(x, y) == 0 || seen.at(x, y) != 0 || !keep(x, y)) continue;
      ++found;
      stack.push_back({x, y});
      seen.at(x, y) = 1;
      while (!stack.empty()) {
        const Texel t = stack.back();
        stack.pop_back();
        for (std::int32_t dy = -1; dy <= 1; ++dy) {
          for (std::int32_t dx = -1; dx <= 1; ++dx) {
            const std::int32_t u = t.x + dx;
            const std::int32_t v = t.y + dy;
            if (u < 0 || v < 0 || u >= m.width || v >= m.height) continue;
            if (m.at(u, v) == 0 || seen.at(u, v) != 0 || !keep(u, v)) continue;
            seen.at(u, v) = 1;
            stack.push_back({u, v});
          }
        }
      }
    }
  }
  return found;
}

// Whether every point of the circle of radius r lies within `reach` of the centre of a set texel.
bool covers_circle(const Mask& m, double r, double reach) {
  for (int i = 0; i < 720; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 720.0;
    const double px = kCx + r * std::cos(a);
    const double py = kCy + r * std::sin(a);
    bool hit = false;
    for (std::int32_t y = static_cast<std::int32_t>(py) - 2; y <= static_cast<std::int32_t>(py) + 2 && !hit; ++y) {
      for (std::int32_t x = static_cast<std::int32_t>(px) - 2; x <= static_cast<std::int32_t>(px) + 2 && !hit; ++x) {
        if (x < 0 || y < 0 || x >= m.width || y >= m.height || m.at(x, y) == 0) continue;
        hit = std::hypot(x + 0.5 - px, y + 0.5 - py) <= reach;
      }
    }
    if (!hit) return false;
  }
  return true;
}

// ------------------------------------------------------------------------------------------------------
// Isophotes

TEST(Isophotes, SphereUnderOverheadLightIsACircle) {
  // n·l = n_z = sqrt(1 - r²/R²) = c on the circle r = R sqrt(1 - c²).
  constexpr std::int32_t side = 128;
  const GradientField g = sphere_gradient(side);
  for (double c : {0.8, 0.9, 0.97}) {
    IsophoteParams p;
    p.light = {0.0, 0.0, 1.0};
    p.cos_alpha = c;
    const double r0 = kSphereR * std::sqrt(1.0 - c * c);
    const Mask m = isophote_mask(g, p);
    ASSERT_GT(count(m), 0);
    for (std::int32_t y = 0; y < side; ++y) {
      for (std::int32_t x = 0; x < side; ++x) {
        if (m.at(x, y) == 0) continue;
        EXPECT_LE(std::abs(radius_of(x, y) - r0), 0.75) << "c=" << c << " at " << x << "," << y;
      }
    }
    EXPECT_TRUE(covers_circle(m, r0, 1.0)) << "c=" << c;
    EXPECT_EQ(components(m, [](std::int32_t, std::int32_t) { return true; }), 1) << "c=" << c;
    // One texel thin: an 8-connected digital circle has about 4 sqrt(2) r texels, 2 pi r at most.
    EXPECT_LE(count(m), 2.0 * std::numbers::pi * r0 + 8.0) << "c=" << c;
  }
}

TEST(Isophotes, BandRuleIsTheLiteralDefinition) {
  constexpr std::int32_t side = 128;
  const GradientField g = sphere_gradient(side);
  IsophoteParams p;
  p.light = {0.0, 0.0, 2.0};  // any length
  p.cos_alpha = 0.9;
  p.rule = PatternRule::band;
  p.tol = 0.02;
  const Mask m = isophote_mask(g, p);
  std::int64_t checked = 0;
  for (std::int32_t y = 0; y < side; ++y) {
    for (std::int32_t x = 0; x < side; ++x) {
      const double r = radius_of(x, y);
      const double nz = std::sqrt(1.0 - r * r / (kSphereR * kSphereR));
      const double margin = std::abs(std::abs(nz - p.cos_alpha) - p.tol);
      if (margin < 1e-5) continue;  // float gradients: too close to the band's edge to call
      EXPECT_EQ(m.at(x, y) != 0, std::abs(nz - p.cos_alpha) < p.tol) << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, side * side - 50);
}

TEST(Isophotes, ConeUnderOverheadLightIsAllOrNothing) {
  // A cone h = -0.5 r has n_z = 1/sqrt(1.25) everywhere but the apex.
  constexpr std::int32_t side = 128;
  const GradientField g = gradient_of(side, side, [](Point p) {
    const double r = std::hypot(p.x, p.y);
    return std::pair{-0.5 * p.x / r, -0.5 * p.y / r};
  });
  const double nz = 1.0 / std::sqrt(1.25);
  IsophoteParams p;
  p.light = {0.0, 0.0, 1.0};
  p.rule = PatternRule::band;
  p.cos_alpha = nz;
  p.tol = 0.01;
  EXPECT_EQ(count(isophote_mask(g, p)), side * side);
  p.cos_alpha = nz + 0.05;
  EXPECT_EQ(count(isophote_mask(g, p)), 0);
  p.rule = PatternRule::crossing;
  EXPECT_EQ(count(isophote_mask(g, p)), 0);  // n·l never passes through c
  p.cos_alpha = nz - 0.05;
  EXPECT_EQ(count(isophote_mask(g, p)), 0);
}

TEST(Isophotes, LightVectorPointsTowardTheLightInTheScreenFrame) {
  // A ridge along y: left half rises to the right (h_x > 0, faces -x), right half faces +x.
  constexpr std::int32_t side = 64;
  const GradientField g = gradient_of(side, side, [](Point p) { return std::pair{p.x < 0.0 ? 1.0 : -1.0, 0.0}; });
  IsophoteParams p;
  p.light = {-1.0, 0.0, 1.0};  // from the left (screen -x)
  p.rule = PatternRule::band;
  p.cos_alpha = 1.0;  // n = (-1, 0, 1)/sqrt(2) faces the light exactly
  p.tol = 1e-3;
  const Mask m = isophote_mask(g, p);
  for (std::int32_t y = 0; y < side; ++y) {
    for (std::int32_t x = 0; x < side; ++x) EXPECT_EQ(m.at(x, y) != 0, centred(x, y).x < 0.0) << x << "," << y;
  }
  p.light = {0.0, -1.0, 1.0};  // from the top (screen -y): both halves at the same angle, n·l = 1/2
  p.cos_alpha = 0.5;
  EXPECT_EQ(count(isophote_mask(g, p)), side * side);
}

// The light is a direction: scaled by 1e300 or 1e-300 its squares overflow or underflow, and the light was refused as
// not finite and non-zero. The mask is the unit light's.
TEST(Isophotes, ALightOfAnyFiniteLengthIsItsDirection) {
  const GradientField g = sphere_gradient(48);
  IsophoteParams p;
  p.light = {-1.0, -1.0, 2.0};
  const Mask unit = isophote_mask(g, p);
  ASSERT_GT(count(unit), 0);
  for (const double scale : {1e300, 1e-300}) {
    SCOPED_TRACE(scale);
    p.light = {-scale, -scale, 2.0 * scale};
    EXPECT_EQ(isophote_mask(g, p).values, unit.values);
  }
}

TEST(Isophotes, FlatFieldAndBadInput) {
  const GradientField flat(40, 30);
  IsophoteParams p;  // defaults: the flat desktop is not on the isophote
  EXPECT_EQ(count(isophote_mask(flat, p)), 0);
  const PatternField f = isophote_field(flat, p, 50.0f);
  EXPECT_FALSE(f.nearest({10, 10}));

  GradientField bad(8, 8);
  bad.at(3, 3) = {std::numeric_limits<float>::quiet_NaN(), 0.0f};
  p.light = {0.0, 0.0, 1.0};
  p.cos_alpha = 1.0;
  p.rule = PatternRule::band;
  p.tol = 0.01;
  const Mask m = isophote_mask(bad, p);
  EXPECT_EQ(m.at(3, 3), 0);
  EXPECT_EQ(count(m), 63);

  p.light = {0.0, 0.0, 0.0};
  EXPECT_THROW(isophote_mask(flat, p), std::invalid_argument);
  p.light = {0.0, 0.0, 1.0};
  p.cos_alpha = 1.5;
  EXPECT_THROW(isophote_mask(flat, p), std::invalid_argument);
  p.cos_alpha = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(isophote_mask(flat, p), std::invalid_argument);
  p.cos_alpha = 0.5;
  p.tol = -1.0;
  EXPECT_THROW(isophote_mask(flat, p), std::invalid_argument);
}

// ------------------------------------------------------------------------------------------------------
// Contours

constexpr std::int32_t kSide = 128;
constexpr double kA = 0.01;  // paraboloid h = a r²: level L at r = sqrt(L / a)

DepthField paraboloid() {
  return depth_of(kSide, kSide, [](Point p) { return kA * (p.x * p.x + p.y * p.y); });
}

// Each level is a closed, one-texel-thin ring at its radius: every mask texel near one ring, each ring
// covered all round and one 8-connected component, rings separate.
void expect_rings(const Mask& m, const std::vector<double>& radii, double slack, const char* what) {
  auto ring_of = [&](std::int32_t x, std::int32_t y) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < radii.size(); ++i) {
      if (std::abs(radius_of(x, y) - radii[i]) < std::abs(radius_of(x, y) - radii[best])) best = i;
    }
    return best;
  };
  for (std::int32_t y = 0; y < m.height; ++y) {
    for (std::int32_t x = 0; x < m.width; ++x) {
      if (m.at(x, y) == 0) continue;
      EXPECT_LE(std::abs(radius_of(x, y) - radii[ring_of(x, y)]), slack) << what << " at " << x << "," << y;
    }
  }
  EXPECT_EQ(components(m, [](std::int32_t, std::int32_t) { return true; }), static_cast<int>(radii.size())) << what;
  for (std::size_t i = 0; i < radii.size(); ++i) {
    EXPECT_TRUE(covers_circle(m, radii[i], slack + 0.5)) << what << " ring " << radii[i];
    EXPECT_EQ(components(m, [&](std::int32_t x, std::int32_t y) { return ring_of(x, y) == i; }), 1)
        << what << " ring " << radii[i];
    std::int64_t n = 0;
    for (std::int32_t y = 0; y < m.height; ++y) {
      for (std::int32_t x = 0; x < m.width; ++x) n += m.at(x, y) != 0 && ring_of(x, y) == i;
    }
    EXPECT_LE(n, 2.0 * std::numbers::pi * radii[i] + 8.0) << what << " ring " << radii[i];
  }
}

TEST(Contours, ParaboloidGivesClosedThinCircles) {
  ContourParams p;
  p.levels = {16.0, 4.0, 9.0, 25.0, 36.0};  // unsorted on purpose
  const Mask m = contour_mask(paraboloid(), p);
  expect_rings(m, {20.0, 30.0, 40.0, 50.0, 60.0}, 0.75, "paraboloid");
}

TEST(Contours, EvenlySpacedLevelsInsideTheRange) {
  const DepthField d = paraboloid();
  double lo = d.values[0];
  double hi = d.values[0];
  for (float v : d.values) {
    lo = std::min(lo, static_cast<double>(v));
    hi = std::max(hi, static_cast<double>(v));
  }
  ContourParams p;
  p.count = 4;
  const std::vector<double> levels = contour_levels(d, p);
  ASSERT_EQ(levels.size(), 4u);
  for (int k = 1; k <= 4; ++k) EXPECT_DOUBLE_EQ(levels[k - 1], lo + (hi - lo) * k / 5.0);
  p.count = 0;
  EXPECT_TRUE(contour_levels(d, p).empty());
  EXPECT_EQ(count(contour_mask(d, p)), 0);
}

TEST(Contours, QuantisedHeightsStillGiveClosedRings) {
  // The paraboloid through an 8-bit-like depth map: 64 px of relief in 256 codes, terraces of 0.25 px.
  const DepthField exact = paraboloid();
  DepthField q = exact;
  for (float& v : q.values) v = static_cast<float>(std::round(v / 0.25) * 0.25);
  ContourParams p;
  p.levels = {4.0, 9.0, 16.0, 25.0, 36.0};  // exactly on codes: the terrace at the level counts as above
  expect_rings(contour_mask(q, p), {20.0, 30.0, 40.0, 50.0, 60.0}, 1.5, "on codes");
  p.levels = {4.1, 9.1, 16.1, 25.1, 36.1};  // between codes
  std::vector<double> radii;
  for (double l : p.levels) radii.push_back(std::sqrt(l / kA));
  expect_rings(contour_mask(q, p), radii, 1.5, "between codes");
}

TEST(Contours, BandRuleIsTheLiteralDefinition) {
  const DepthField d = paraboloid();
  ContourParams p;
  p.levels = {9.0, 25.0};
  p.rule = PatternRule::band;
  p.tol = 0.3;
  const Mask m = contour_mask(d, p);
  for (std::int32_t y = 0; y < kSide; ++y) {
    for (std::int32_t x = 0; x < kSide; ++x) {
      const double h = d.at(x, y);
      EXPECT_EQ(m.at(x, y) != 0, std::abs(h - 9.0) < 0.3 || std::abs(h - 25.0) < 0.3) << x << "," << y;
    }
  }
  p.tol = 0.0;
  EXPECT_EQ(count(contour_mask(d, p)), 0);
}

TEST(Contours, FlatFieldGivesNoContoursAndNoNaN) {
  const DepthField flat(50, 40, 3.0f);
  ContourParams p;
  EXPECT_TRUE(contour_levels(flat, p).empty());
  EXPECT_EQ(count(contour_mask(flat, p)), 0);
  const PatternField f = contour_field(flat, p, 30.0f);
  EXPECT_EQ(f.width(), 50);
  for (std::int32_t y = 0; y < 40; ++y) {
    for (std::int32_t x = 0; x < 50; ++x) EXPECT_FALSE(f.nearest({x, y}));
  }
  EXPECT_TRUE(contour_levels(DepthField{}, p).empty());
  EXPECT_TRUE(contour_mask(DepthField{}, p).empty());
}

TEST(Contours, NonFiniteHeightsAreSkipped) {
  DepthField d = paraboloid();
  d.at(64, 44) = std::numeric_limits<float>::quiet_NaN();  // on the r = 20 ring
  d.at(0, 0) = std::numeric_limits<float>::infinity();     // would stretch the range
  ContourParams p;
  p.count = 3;
  const std::vector<double> levels = contour_levels(d, p);
  ASSERT_EQ(levels.size(), 3u);
  for (double l : levels) EXPECT_TRUE(std::isfinite(l));
  p.levels = {4.0};
  const Mask m = contour_mask(d, p);
  EXPECT_EQ(m.at(64, 44), 0);
  EXPECT_EQ(m.at(0, 0), 0);
  EXPECT_GT(count(m), 100);
}

TEST(Contours, BadParametersThrow) {
  const DepthField d = paraboloid();
  ContourParams p;
  p.count = -1;
  EXPECT_THROW(contour_mask(d, p), std::invalid_argument);
  p.count = kMaxContourLevels + 1;
  EXPECT_THROW(contour_mask(d, p), std::invalid_argument);
  p.count = 3;
  p.levels = {1.0, std::numeric_limits<double>::infinity()};
  EXPECT_THROW(contour_mask(d, p), std::invalid_argument);
  p.levels = {1.0};
  p.tol = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(contour_mask(d, p), std::invalid_argument);
}

TEST(Contours, FieldPointsToTheNearestRing) {
  ContourParams p;
  p.levels = {4.0, 25.0};  // rings at r = 20 and 50
  const PatternField f = contour_field(paraboloid(), p, 25.0f);
  const std::optional<NearestPattern> from_centre = f.nearest({64, 63});  // r < 1
  ASSERT_TRUE(from_centre);
  EXPECT_NEAR(from_centre->distance(), 20.0, 1.0);
  const std::optional<NearestPattern> near_outer = f.nearest({64 + 45, 63});
  ASSERT_TRUE(near_outer);
  EXPECT_NEAR(near_outer->distance(), 5.0, 1.0);
  EXPECT_GT(near_outer->dx, 0);     // outward, toward r = 50
  EXPECT_FALSE(f.nearest({0, 0}));  // r ≈ 90: 40 from the outer ring, beyond the radius
}

}  // namespace
}  // namespace ph
