#include "core/lab/surfaces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ph {
namespace {

// Height and derivatives before the centring constant, at (X, Y) px from the centre.
struct Point {
  double h = 0.0;
  HeightDerivatives d;
};

// h = A X^2 + B X Y + C Y^2 (coefficients in 1/px).
Point quadratic(double a, double b, double c, double x, double y) {
  return {a * x * x + b * x * y + c * y * y, {2 * a * x + b * y, b * x + 2 * c * y, 2 * a, b, 2 * c}};
}

// h = c sqrt(g), g = 1 + alpha X^2 + beta Y^2: spheres, cylinders, ellipsoids, hyperboloids. g > 0 inside the
// square for every surface here.
Point sqrt_quadric(double c, double alpha, double beta, double x, double y) {
  const double g = 1.0 + alpha * x * x + beta * y * y;
  const double root = std::sqrt(g);
  const double gx = 2 * alpha * x, gy = 2 * beta * y;
  Point p;
  p.h = c * root;
  p.d.hx = c * gx / (2 * root);
  p.d.hy = c * gy / (2 * root);
  p.d.hxx = c * (2 * alpha / (2 * root) - gx * gx / (4 * g * root));
  p.d.hxy = c * (-gx * gy / (4 * g * root));
  p.d.hyy = c * (2 * beta / (2 * root) - gy * gy / (4 * g * root));
  return p;
}

Point raw_point(const SurfaceSpec& spec, double x, double y) {
  const double s = spec.half_size();
  switch (spec.kind) {
    case SurfaceKind::plane:
      return {0.12 * x - 0.08 * y, {0.12, -0.08, 0, 0, 0}};
    case SurfaceKind::cylinder: {
      const double r = 2 * s;
      return sqrt_quadric(r, -1 / (r * r), 0, x, y);
    }
    case SurfaceKind::cone: {
      // h = -t rho; the Hessian of rho is (I - u u^T) / rho with u the unit vector from the apex.
      const double t = 0.15, dx = x + 1.5 * s, rho = std::hypot(dx, y), rho3 = rho * rho * rho;
      return {-t * rho, {-t * dx / rho, -t * y / rho, -t * y * y / rho3, t * dx * y / rho3, -t * dx * dx / rho3}};
    }
    case SurfaceKind::paraboloid:
      return quadratic(-0.14 / s, 0, -0.08 / s, x, y);
    case SurfaceKind::ellipsoid: {
      const double a = 2.2 * s, b = 1.8 * s;
      return sqrt_quadric(0.6 * s, -1 / (a * a), -1 / (b * b), x, y);
    }
    case SurfaceKind::sphere: {
      const double r = 3 * s;
      return sqrt_quadric(r, -1 / (r * r), -1 / (r * r), x, y);
    }
    case SurfaceKind::hyperboloid: {
      const double a = 1.6 * s, b = 2 * s;
      return sqrt_quadric(0.6 * s, -1 / (a * a), 1 / (b * b), x, y);
    }
    case SurfaceKind::simple_saddle:
      return quadratic(0.2 / s, 0, -0.2 / s, x, y);
    case SurfaceKind::monkey_saddle: {
      const double a = 0.1 / (s * s);
      return {a * (x * x * x - 3 * x * y * y),
              {3 * a * (x * x - y * y), -6 * a * x * y, 6 * a * x, -6 * a * y, -6 * a * x}};
    }
  }
  return {};
}

// Minus the midpoint of the heights' range. Every surface here takes its extremes over the square at the centre,
// an edge's midpoint or a corner, so these nine points give the exact range.
double centring_offset(const SurfaceSpec& spec) {
  const double s = spec.half_size();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double x : {-s, 0.0, s}) {
    for (double y : {-s, 0.0, s}) {
      const double h = raw_point(spec, x, y).h;
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
  }
  return -(lo + hi) / 2.0;
}

template <typename T, typename F>
Grid<T> rasterise(const SurfaceSpec& spec, F value) {
  Grid<T> grid(spec.size, spec.size);
  for (std::int32_t y = 0; y < spec.size; ++y) {
    for (std::int32_t x = 0; x < spec.size; ++x) grid.at(x, y) = value(Vec2{x + 0.5, y + 0.5});
  }
  return grid;
}

}  // namespace

std::string SurfaceSpec::name() const {
  switch (kind) {
    case SurfaceKind::plane:
      return "plane";
    case SurfaceKind::cylinder:
      return "cylinder";
    case SurfaceKind::cone:
      return "cone";
    case SurfaceKind::paraboloid:
      return "paraboloid";
    case SurfaceKind::ellipsoid:
      return "ellipsoid";
    case SurfaceKind::sphere:
      return "sphere";
    case SurfaceKind::hyperboloid:
      return "hyperboloid";
    case SurfaceKind::simple_saddle:
      return "simple-saddle";
    case SurfaceKind::monkey_saddle:
      return "monkey-saddle";
  }
  return "unknown";
}

std::vector<SurfaceSpec> all_surfaces(std::int32_t size) {
  std::vector<SurfaceSpec> out;
  for (SurfaceKind kind :
       {SurfaceKind::plane, SurfaceKind::cylinder, SurfaceKind::cone, SurfaceKind::paraboloid, SurfaceKind::ellipsoid,
        SurfaceKind::sphere, SurfaceKind::hyperboloid, SurfaceKind::simple_saddle, SurfaceKind::monkey_saddle}) {
    out.push_back({kind, size});
  }
  return out;
}

CurvatureClass surface_class(SurfaceKind kind) {
  switch (kind) {
    case SurfaceKind::plane:
      return CurvatureClass::planar;
    case SurfaceKind::cylinder:
    case SurfaceKind::cone:
      return CurvatureClass::parabolic;
    case SurfaceKind::paraboloid:
    case SurfaceKind::ellipsoid:
    case SurfaceKind::sphere:
      return CurvatureClass::elliptic;
    case SurfaceKind::hyperboloid:
    case SurfaceKind::simple_saddle:
    case SurfaceKind::monkey_saddle:
      return CurvatureClass::hyperbolic;
  }
  return CurvatureClass::planar;
}

double surface_height(const SurfaceSpec& spec, Vec2 p) {
  const double s = spec.half_size();
  return raw_point(spec, p.x - s, p.y - s).h + centring_offset(spec);
}

HeightDerivatives surface_derivatives(const SurfaceSpec& spec, Vec2 p) {
  const double s = spec.half_size();
  return raw_point(spec, p.x - s, p.y - s).d;
}

DepthField surface_depth_field(const SurfaceSpec& spec) {
  const double offset = centring_offset(spec);
  const double s = spec.half_size();
  return rasterise<float>(spec,
                          [&](Vec2 p) { return static_cast<float>(raw_point(spec, p.x - s, p.y - s).h + offset); });
}

GradientField surface_gradient_field(const SurfaceSpec& spec) {
  return rasterise<Gradient>(spec, [&](Vec2 p) {
    const HeightDerivatives d = surface_derivatives(spec, p);
    return Gradient{static_cast<float>(d.hx), static_cast<float>(d.hy)};
  });
}

NormalImage surface_normal_image(const SurfaceSpec& spec) {
  // From the double-precision gradient, so the normal is not rounded twice.
  return rasterise<Normal>(spec, [&](Vec2 p) {
    const HeightDerivatives d = surface_derivatives(spec, p);
    const double len = std::sqrt(d.hx * d.hx + d.hy * d.hy + 1.0);
    return Normal{static_cast<float>(-d.hx / len), static_cast<float>(-d.hy / len), static_cast<float>(1.0 / len)};
  });
}

CurvatureFields surface_curvature_fields(const SurfaceSpec& spec) {
  CurvatureFields out;
  out.gaussian = Grid<float>(spec.size, spec.size);
  out.mean = out.k1 = out.k2 = out.gaussian;
  for (std::int32_t y = 0; y < spec.size; ++y) {
    for (std::int32_t x = 0; x < spec.size; ++x) {
      const Curvatures c = surface_curvatures(spec, {x + 0.5, y + 0.5});
      out.gaussian.at(x, y) = static_cast<float>(c.gaussian);
      out.mean.at(x, y) = static_cast<float>(c.mean);
      out.k1.at(x, y) = static_cast<float>(c.k1);
      out.k2.at(x, y) = static_cast<float>(c.k2);
    }
  }
  return out;
}

}  // namespace ph
