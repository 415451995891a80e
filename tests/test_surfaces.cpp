// The analytic test surfaces (core/surfaces): closed-form derivatives against finite differences of the exact
// height, the curvature formulas against known values, ranges and classes.
#include "core/surfaces.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace ph {
namespace {

// Points spread over the square, texel centres and points between them, near the edges too.
std::vector<Vec2> sample_points(const SurfaceSpec& spec) {
  std::vector<Vec2> points;
  for (int i = 0; i <= 16; ++i) {
    for (int j = 0; j <= 16; ++j) {
      points.push_back({1.0 + (spec.size - 2.0) * i / 16.0 + 0.37 * (j % 3), 1.0 + (spec.size - 2.0) * j / 16.0});
    }
  }
  return points;
}

// The largest curvedness sqrt((k1^2 + k2^2) / 2) over the samples: the scale errors are measured against.
double curvedness_scale(const SurfaceSpec& spec) {
  double scale = 0.0;
  for (Vec2 p : sample_points(spec)) {
    const Curvatures c = surface_curvatures(spec, p);
    scale = std::max(scale, std::sqrt((c.k1 * c.k1 + c.k2 * c.k2) / 2.0));
  }
  return scale;
}

TEST(Surfaces, NineNamedSurfacesInTheirClasses) {
  const auto all = all_surfaces();
  ASSERT_EQ(all.size(), 9u);
  std::set<std::string> names;
  for (const SurfaceSpec& s : all) names.insert(s.name());
  EXPECT_EQ(names.size(), 9u);
  EXPECT_EQ(all.front().size, 512);
  EXPECT_EQ(all_surfaces(100).back().size, 100);
  EXPECT_EQ(surface_class(SurfaceKind::plane), CurvatureClass::planar);
  EXPECT_EQ(surface_class(SurfaceKind::cone), CurvatureClass::parabolic);
  EXPECT_EQ(surface_class(SurfaceKind::sphere), CurvatureClass::elliptic);
  EXPECT_EQ(surface_class(SurfaceKind::monkey_saddle), CurvatureClass::hyperbolic);
}

// Central differences of the exact height (double, step 0.5 px) match the closed-form derivatives, and K and H
// computed from those differences match the exact K and H: this checks every closed form.
TEST(Surfaces, DerivativesMatchFiniteDifferencesOfTheHeight) {
  const double e = 0.5;
  for (const SurfaceSpec& spec : all_surfaces()) {
    SCOPED_TRACE(spec.name());
    const double scale = std::max(curvedness_scale(spec), 1e-6);
    auto h = [&](double x, double y) { return surface_height(spec, {x, y}); };
    for (Vec2 p : sample_points(spec)) {
      const HeightDerivatives exact = surface_derivatives(spec, p);
      HeightDerivatives fd;
      fd.hx = (h(p.x + e, p.y) - h(p.x - e, p.y)) / (2 * e);
      fd.hy = (h(p.x, p.y + e) - h(p.x, p.y - e)) / (2 * e);
      fd.hxx = (h(p.x + e, p.y) - 2 * h(p.x, p.y) + h(p.x - e, p.y)) / (e * e);
      fd.hyy = (h(p.x, p.y + e) - 2 * h(p.x, p.y) + h(p.x, p.y - e)) / (e * e);
      fd.hxy = (h(p.x + e, p.y + e) - h(p.x + e, p.y - e) - h(p.x - e, p.y + e) + h(p.x - e, p.y - e)) / (4 * e * e);
      EXPECT_NEAR(fd.hx, exact.hx, 1e-6) << p.x << "," << p.y;
      EXPECT_NEAR(fd.hy, exact.hy, 1e-6) << p.x << "," << p.y;
      EXPECT_NEAR(fd.hxx, exact.hxx, 1e-3 * scale) << p.x << "," << p.y;
      EXPECT_NEAR(fd.hyy, exact.hyy, 1e-3 * scale) << p.x << "," << p.y;
      EXPECT_NEAR(fd.hxy, exact.hxy, 1e-3 * scale) << p.x << "," << p.y;
      const Curvatures a = curvatures_from_derivatives(fd);
      const Curvatures b = surface_curvatures(spec, p);
      EXPECT_NEAR(a.gaussian, b.gaussian, 1e-3 * scale * scale);
      EXPECT_NEAR(a.mean, b.mean, 1e-3 * scale);
      EXPECT_NEAR(a.k1, b.k1, 1e-3 * scale);
      EXPECT_NEAR(a.k2, b.k2, 1e-3 * scale);
    }
  }
}

// The formulas of docs/INTERROGATION.md, "Curvature", against curvatures known in closed form.
TEST(Surfaces, KnownCurvatures) {
  const SurfaceSpec sphere{SurfaceKind::sphere, 512};
  const double r_sphere = 3 * sphere.half_size();
  for (Vec2 p : sample_points(sphere)) {
    const Curvatures c = surface_curvatures(sphere, p);
    EXPECT_NEAR(c.gaussian, 1 / (r_sphere * r_sphere), 1e-9 / (r_sphere * r_sphere));
    EXPECT_NEAR(c.mean, -1 / r_sphere, 1e-9 / r_sphere);  // a cap toward the viewer: H < 0
  }
  const SurfaceSpec cylinder{SurfaceKind::cylinder, 512};
  const double r_cylinder = 2 * cylinder.half_size();
  for (Vec2 p : sample_points(cylinder)) {
    const Curvatures c = surface_curvatures(cylinder, p);
    EXPECT_NEAR(c.gaussian, 0.0, 1e-15);
    EXPECT_NEAR(c.k2, -1 / r_cylinder, 1e-9 / r_cylinder);
    EXPECT_NEAR(c.k1, 0.0, 1e-12);
  }
  const double s = 256;
  const Vec2 centre{s, s};  // the centre of a 512 px surface, where the gradient of these three is 0
  const Curvatures para = surface_curvatures({SurfaceKind::paraboloid, 512}, centre);
  EXPECT_NEAR(para.gaussian, (2 * 0.14 / s) * (2 * 0.08 / s), 1e-15);
  EXPECT_NEAR(para.k2, -2 * 0.14 / s, 1e-12);
  EXPECT_NEAR(para.k1, -2 * 0.08 / s, 1e-12);
  const Curvatures saddle = surface_curvatures({SurfaceKind::simple_saddle, 512}, centre);
  EXPECT_NEAR(saddle.gaussian, -(0.4 / s) * (0.4 / s), 1e-15);
  EXPECT_NEAR(saddle.mean, 0.0, 1e-15);
  const Curvatures monkey = surface_curvatures({SurfaceKind::monkey_saddle, 512}, centre);
  EXPECT_EQ(monkey.gaussian, 0.0);
  EXPECT_EQ(monkey.mean, 0.0);
  const Curvatures plane = surface_curvatures({SurfaceKind::plane, 512}, {10.5, 300.5});
  EXPECT_EQ(plane.gaussian, 0.0);
  EXPECT_EQ(plane.mean, 0.0);
}

// Heights fill but stay within +-relief_px (what the depth map can hold), centred on 0; nothing is singular.
TEST(Surfaces, HeightsWithinTheReliefAndFinite) {
  for (std::int32_t size : {64, 512}) {
    for (const SurfaceSpec& spec : all_surfaces(size)) {
      SCOPED_TRACE(spec.name() + " at " + std::to_string(size));
      const DepthField depth = surface_depth_field(spec);
      const auto [lo, hi] = std::minmax_element(depth.values.begin(), depth.values.end());
      EXPECT_LE(*hi, spec.relief_px());
      EXPECT_GE(*lo, -spec.relief_px());
      EXPECT_GT(*hi - *lo, 0.3 * spec.relief_px()) << "a relief a user can feel";
      // Texel centres stop half a texel short of the extremes, which matters at small sizes.
      EXPECT_NEAR(*hi + *lo, 0.0, (size >= 512 ? 0.02 : 0.06) * spec.relief_px()) << "centred";
      const NormalImage normals = surface_normal_image(spec);
      const GradientField gradient = surface_gradient_field(spec);
      for (std::size_t i = 0; i < normals.values.size(); ++i) {
        const Normal n = normals.values[i];
        ASSERT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && n.z > 0.0f);
        const Gradient g = gradient_from_normal(n);
        EXPECT_NEAR(g.x, gradient.values[i].x, 1e-5);
        EXPECT_NEAR(g.y, gradient.values[i].y, 1e-5);
      }
    }
  }
}

// The exact class of every texel is the surface's class, except the monkey saddle's flat centre (planar within
// the 16-bit curvedness tolerance), which must stay a small disk around the centre.
TEST(Surfaces, ExactClassesAreHomogeneous) {
  for (const SurfaceSpec& spec : all_surfaces()) {
    SCOPED_TRACE(spec.name());
    const Grid<std::uint8_t> classes = class_map(surface_curvature_fields(spec), ClassTolerances::recommended(16));
    std::size_t other = 0;
    for (std::int32_t y = 0; y < spec.size; ++y) {
      for (std::int32_t x = 0; x < spec.size; ++x) {
        if (classes.at(x, y) == static_cast<std::uint8_t>(surface_class(spec.kind))) continue;
        ++other;
        EXPECT_EQ(spec.kind, SurfaceKind::monkey_saddle);
        EXPECT_EQ(classes.at(x, y), static_cast<std::uint8_t>(CurvatureClass::planar));
        EXPECT_LT(std::hypot(x + 0.5 - spec.half_size(), y + 0.5 - spec.half_size()), 0.1 * spec.size);
      }
    }
    EXPECT_LT(other, classes.values.size() / 100);
  }
}

}  // namespace
}  // namespace ph
