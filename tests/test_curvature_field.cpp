// Curvature fields and classes (core/effects/curvature_field, core/effects/curvature_class) on the analytic surfaces,
// quantised the way the files `pseudohaptic surfaces` writes are, and on degenerate input.
#include "core/effects/curvature_field.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "core/effects/curvature_class.hpp"
#include "core/engine/decode.hpp"
#include "core/lab/surfaces.hpp"

namespace ph {
namespace {

// The surface's exact normals stored as a bits-deep unorm RGB image (OpenGL green, as write_normal_png16 does)
// and decoded as a loader decodes it.
GradientField quantised_gradient(const SurfaceSpec& spec, int bits) {
  const std::uint32_t cmax = (1u << bits) - 1;
  const NormalImage exact = surface_normal_image(spec);
  RawImage raw;
  raw.width = exact.width;
  raw.height = exact.height;
  raw.channels = 3;
  raw.code_max = cmax;
  for (const Normal& n : exact.values) {
    for (double c : {(n.x + 1.0) / 2.0, (-n.y + 1.0) / 2.0, (n.z + 1.0) / 2.0})
      raw.pixels.push_back(static_cast<float>(std::lround(c * cmax) / double(cmax)));
  }
  DecodeReport report;
  const NormalImage decoded = decode_normals(raw, {}, report);
  GradientField out(decoded.width, decoded.height);
  for (std::size_t i = 0; i < out.values.size(); ++i) out.values[i] = gradient_from_normal(decoded.values[i]);
  return out;
}

// The surface's exact heights stored as v = 0.5 + h / (2 relief) in a bits-deep grey image, decoded back to px.
DepthField quantised_depth(const SurfaceSpec& spec, int bits) {
  const std::uint32_t cmax = (1u << bits) - 1;
  const DepthField exact = surface_depth_field(spec);
  RawImage raw;
  raw.width = exact.width;
  raw.height = exact.height;
  raw.channels = 1;
  raw.code_max = cmax;
  for (float h : exact.values)
    raw.pixels.push_back(static_cast<float>(std::lround((0.5 + h / (2 * spec.relief_px())) * cmax) / double(cmax)));
  DecodeReport report;
  return decode_depth(raw, {0.5, 2 * spec.relief_px()}, report);
}

// K = 0 for planar and parabolic, else the sign of K: what the class map must match.
int sign_group(std::uint8_t c) {
  return c == static_cast<std::uint8_t>(CurvatureClass::elliptic)     ? 1
         : c == static_cast<std::uint8_t>(CurvatureClass::hyperbolic) ? -1
                                                                      : 0;
}

struct Agreement {
  double sign = 0.0;     // fraction of interior texels whose sign group matches the exact one
  double classes = 0.0;  // ... whose class matches exactly
  double k_error = 0.0;  // largest |K - K_exact| / curvedness_max^2 over interior texels
  double h_error = 0.0;  // largest |H - H_exact| / curvedness_max
};

// Errors are relative to the surface's largest curvedness (or the planar tolerance where that is larger).
// Compares with the exact classes under the same tolerances, over texels at least the filter radius from the border.
Agreement compare(const SurfaceSpec& spec, const CurvatureFields& measured, const ClassTolerances& tolerances,
                  std::int32_t border) {
  const CurvatureFields exact = surface_curvature_fields(spec);
  const Grid<std::uint8_t> want = class_map(exact, tolerances);
  const Grid<std::uint8_t> got = class_map(measured, tolerances);
  double scale = tolerances.planar_curvedness;  // the plane has no curvature to measure against
  for (std::size_t i = 0; i < exact.k1.values.size(); ++i) {
    const double k1 = exact.k1.values[i], k2 = exact.k2.values[i];
    scale = std::max(scale, std::sqrt((k1 * k1 + k2 * k2) / 2.0));
  }
  Agreement a;
  std::size_t n = 0, sign = 0, classes = 0;
  for (std::int32_t y = border; y < spec.size - border; ++y) {
    for (std::int32_t x = border; x < spec.size - border; ++x) {
      ++n;
      sign += sign_group(got.at(x, y)) == sign_group(want.at(x, y));
      classes += got.at(x, y) == want.at(x, y);
      a.k_error = std::max(a.k_error, std::abs(double(measured.gaussian.at(x, y)) - exact.gaussian.at(x, y)));
      a.h_error = std::max(a.h_error, std::abs(double(measured.mean.at(x, y)) - exact.mean.at(x, y)));
    }
  }
  a.sign = double(sign) / n;
  a.classes = double(classes) / n;
  a.k_error /= scale * scale;
  a.h_error /= scale;
  return a;
}

Agreement measure(const SurfaceSpec& spec, bool from_depth, int bits) {
  const DerivativeFilter filter = DerivativeFilter::recommended(from_depth, bits);
  const CurvatureFields fields = from_depth ? curvature_from_depth(quantised_depth(spec, bits), filter)
                                            : curvature_from_gradient(quantised_gradient(spec, bits), filter);
  return compare(spec, fields, ClassTolerances::recommended(bits), filter.radius);
}

// A least-squares quadric fit is exact on a quadric, so the filter returns exact derivatives there at any radius,
// up to the border.
TEST(Curvature, FilterIsExactOnQuadrics) {
  const double a = 0.003, b = -0.002, c = 0.0015, d = 0.2, e = -0.1;
  auto h = [&](double x, double y) { return a * x * x + b * x * y + c * y * y + d * x + e * y + 7.0; };
  DepthField depth(40, 30);
  GradientField gradient(40, 30);
  for (std::int32_t y = 0; y < 30; ++y) {
    for (std::int32_t x = 0; x < 40; ++x) {
      depth.at(x, y) = static_cast<float>(h(x, y));
      gradient.at(x, y) = {static_cast<float>(2 * a * x + b * y + d), static_cast<float>(b * x + 2 * c * y + e)};
    }
  }
  for (std::int32_t r : {1, 3, 6}) {
    SCOPED_TRACE(r);
    const auto from_depth = derivatives_from_depth(depth, {r});
    const auto from_gradient = derivatives_from_gradient(gradient, {r});
    for (std::int32_t y = 0; y < 30; ++y) {  // the border too: its windows stay inside the map
      for (std::int32_t x = 0; x < 40; ++x) {
        for (const HeightDerivatives& got : {from_depth.at(x, y), from_gradient.at(x, y)}) {
          EXPECT_NEAR(got.hx, 2 * a * x + b * y + d, 2e-5);
          EXPECT_NEAR(got.hy, b * x + 2 * c * y + e, 2e-5);
          EXPECT_NEAR(got.hxx, 2 * a, 1e-5);  // the float heights' rounding, over a 3-texel window
          EXPECT_NEAR(got.hxy, b, 1e-5);
          EXPECT_NEAR(got.hyy, 2 * c, 1e-5);
        }
      }
    }
  }
}

// Class maps from 16-bit normal and depth maps agree with the sign of the exact K on at least 99% of
// interior texels of every surface; K and H within the stated tolerance. The 8-bit figures are measured and
// printed, and held to the lower bounds docs/INTERROGATION.md ("Measured agreement") states (measured minus a margin).
TEST(Curvature, ClassesAndCurvaturesOfQuantisedSurfaces) {
  std::printf("%-14s %-6s %4s %8s %8s %9s %9s\n", "surface", "source", "bits", "sign", "class", "K err", "H err");
  double worst_sign8[2] = {1.0, 1.0};
  for (const SurfaceSpec& spec : all_surfaces()) {
    for (bool from_depth : {false, true}) {
      for (int bits : {16, 8}) {
        SCOPED_TRACE(spec.name() + (from_depth ? " depth " : " normal ") + std::to_string(bits));
        const Agreement a = measure(spec, from_depth, bits);
        std::printf("%-14s %-6s %4d %8.4f %8.4f %9.2e %9.2e\n", spec.name().c_str(), from_depth ? "depth" : "normal",
                    bits, a.sign, a.classes, a.k_error, a.h_error);
        if (bits == 16) {
          EXPECT_GE(a.sign, 0.99);
          EXPECT_GE(a.classes, 0.99);
          // Relative to the surface's largest curvedness (squared for K).
          EXPECT_LT(a.k_error, from_depth ? 0.05 : 0.02);
          EXPECT_LT(a.h_error, from_depth ? 0.1 : 0.02);
        } else {
          worst_sign8[from_depth] = std::min(worst_sign8[from_depth], a.sign);
        }
      }
    }
  }
  std::printf("8-bit worst sign agreement: normal %.4f, depth %.4f\n", worst_sign8[0], worst_sign8[1]);
  EXPECT_GE(worst_sign8[0], 0.97);
  EXPECT_GE(worst_sign8[1], 0.90);
}

bool all_finite(const CurvatureFields& f) {
  for (const Grid<float>* g : {&f.gaussian, &f.mean, &f.k1, &f.k2}) {
    for (float v : g->values) {
      if (!std::isfinite(v)) return false;
    }
  }
  return true;
}

constexpr CurvatureRequest kEverything{true, true, true};

TEST(Curvature, FlatMapIsPlanarEverywhere) {
  const CurvatureFields f = curvature_from_gradient(GradientField(20, 10), {3}, kEverything);
  ASSERT_EQ(f.k1.width, 20);
  for (float v : f.gaussian.values) EXPECT_EQ(v, 0.0f);
  for (float v : f.mean.values) EXPECT_EQ(v, 0.0f);
  const Grid<std::uint8_t> classes = class_map(f, {});
  for (std::uint8_t c : classes.values) EXPECT_EQ(c, static_cast<std::uint8_t>(CurvatureClass::planar));
  const CurvatureFields d = curvature_from_depth(DepthField(20, 10, 42.0f), {3}, kEverything);
  for (float v : d.gaussian.values) EXPECT_EQ(v, 0.0f);
}

TEST(Curvature, StepsWallsAndOddInputStayFinite) {
  DepthField step(32, 32);
  for (std::int32_t y = 0; y < 32; ++y) {
    for (std::int32_t x = 16; x < 32; ++x) step.at(x, y) = 1e4f;  // a 10000 px cliff
  }
  for (std::int32_t r : {0, 1, 4, 40}) {  // 0 counts as 1; 40 is wider than the map
    SCOPED_TRACE(r);
    EXPECT_TRUE(all_finite(curvature_from_depth(step, {r}, kEverything)));
    // A vertical wall as a normal map decodes it (n_z tiny), and texels a repair could not fix.
    GradientField wall(32, 32);
    for (std::int32_t y = 0; y < 32; ++y) {
      wall.at(10, y) = {3e38f, -3e38f};
      wall.at(11, y) = {std::numeric_limits<float>::infinity(), 0.0f};
      wall.at(12, y) = {std::numeric_limits<float>::quiet_NaN(), 1e20f};
    }
    const CurvatureFields f = curvature_from_gradient(wall, {r}, kEverything);
    EXPECT_TRUE(all_finite(f));
    EXPECT_EQ(class_map(f, {}).values.size(), 32u * 32u);
  }
  // Tiny maps: one texel, one row, one column.
  for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 1}, std::pair{1, 7}}) {
    EXPECT_TRUE(all_finite(curvature_from_depth(DepthField(w, h, 3.0f), {3}, kEverything)));
    EXPECT_TRUE(all_finite(curvature_from_gradient(GradientField(w, h, {0.5f, -0.5f}), {3}, kEverything)));
  }
  const Curvatures c = curvatures_from_derivatives({1e300, -1e300, 1e300, 1e300, -1e300});
  for (double v : {c.gaussian, c.mean, c.k1, c.k2}) EXPECT_TRUE(std::isfinite(v));
}

TEST(Curvature, OnlyWhatIsAskedIsStored) {
  const GradientField g = surface_gradient_field({SurfaceKind::sphere, 64});
  const CurvatureFields k_only = curvature_from_gradient(g, {3}, {true, false, false});
  EXPECT_FALSE(k_only.gaussian.empty());
  EXPECT_TRUE(k_only.mean.empty());
  EXPECT_TRUE(k_only.k1.empty());
  EXPECT_TRUE(class_map(k_only, {}).empty());  // classes need H too
  const CurvatureFields principal = curvature_from_gradient(g, {3}, {false, false, true});
  EXPECT_TRUE(principal.gaussian.empty());
  EXPECT_EQ(class_map(principal, {}).values.size(), 64u * 64u);
}

// A relief whose curvature changes everywhere, of an odd size: heights and their slopes.
DepthField wavy_depth(std::int32_t w, std::int32_t h) {
  DepthField d(w, h);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x)
      d.at(x, y) = static_cast<float>(6.0 * std::sin(x / 7.3) * std::cos(y / 5.1) + 0.01 * ((x * 31 + y * 17) % 13));
  }
  return d;
}

// Every row's k1 and k2, from the rows of each band in turn.
template <typename Field, typename Rows>
std::vector<float> principal_in_bands(const Field& field, std::int32_t radius, const std::vector<RowRange>& bands,
                                      Rows rows) {
  std::vector<float> out(2 * static_cast<std::size_t>(field.width) * static_cast<std::size_t>(field.height), -1.0f);
  for (const RowRange& band : bands) {
    rows(field, DerivativeFilter{radius}, band, [&](std::int32_t y, const float* k1, const float* k2) {
      const auto at = 2 * static_cast<std::size_t>(y) * static_cast<std::size_t>(field.width);
      std::copy(k1, k1 + field.width, out.begin() + static_cast<std::ptrdiff_t>(at));
      std::copy(k2, k2 + field.width, out.begin() + static_cast<std::ptrdiff_t>(at) + field.width);
    });
  }
  return out;
}

// Bands of rows, however cut, give each row the values the whole field gives it, to the bit; and the class maps made
// on several threads are the one made on one.
TEST(Curvature, BandsOfRowsAgreeWithTheWholeFieldToTheBit) {
  const std::int32_t w = 53, h = 131;
  const DepthField depth = wavy_depth(w, h);
  const GradientField gradient = gradient_from_depth(depth);
  const std::vector<std::vector<RowRange>> cuts = {
      {{0, 3}, {3, 9}, {9, 70}, {70, 128}, {128, h}},  // bands inside the windows' border rows
      {{0, 65}, {65, h}},
      {{0, 1}, {1, h}},
  };
  for (std::int32_t radius : {1, 3, 8}) {
    SCOPED_TRACE("radius " + std::to_string(radius));
    const std::vector<float> depth_whole = principal_in_bands(depth, radius, {RowRange{}}, principal_rows_from_depth);
    const std::vector<float> gradient_whole =
        principal_in_bands(gradient, radius, {RowRange{}}, principal_rows_from_gradient);
    for (const std::vector<RowRange>& cut : cuts) {
      const std::vector<float> d = principal_in_bands(depth, radius, cut, principal_rows_from_depth);
      const std::vector<float> g = principal_in_bands(gradient, radius, cut, principal_rows_from_gradient);
      EXPECT_EQ(std::memcmp(d.data(), depth_whole.data(), d.size() * sizeof(float)), 0);
      EXPECT_EQ(std::memcmp(g.data(), gradient_whole.data(), g.size() * sizeof(float)), 0);
    }
    const ClassTolerances tolerances{1e-3, 0.2};
    const Grid<std::uint8_t> depth_classes = class_map_from_depth(depth, {radius}, tolerances, 1);
    const Grid<std::uint8_t> gradient_classes = class_map_from_gradient(gradient, {radius}, tolerances, 1);
    EXPECT_EQ(depth_classes.values,
              class_map(curvature_from_depth(depth, {radius}, {false, false, true}), tolerances).values);
    EXPECT_EQ(std::count(depth_classes.values.begin(), depth_classes.values.end(), std::uint8_t{0}) <
                  static_cast<std::ptrdiff_t>(depth_classes.values.size()),
              true);  // not all planar: the comparison has classes to compare
    // 131 rows hold two bands of 64; asked for more threads, the map is made in two.
    for (unsigned threads : {2u, 3u, 4u}) {
      EXPECT_EQ(class_map_from_depth(depth, {radius}, tolerances, threads).values, depth_classes.values);
      EXPECT_EQ(class_map_from_gradient(gradient, {radius}, tolerances, threads).values, gradient_classes.values);
    }
  }
}

TEST(Curvature, ClassifyFollowsTheTolerances) {
  const ClassTolerances t{1e-3, 0.2};
  EXPECT_EQ(classify(0.0, 0.0, t), CurvatureClass::planar);
  EXPECT_EQ(classify(5e-4, -5e-4, t), CurvatureClass::planar);
  EXPECT_EQ(classify(0.01, 0.001, t), CurvatureClass::parabolic);
  EXPECT_EQ(classify(-0.001, -0.01, t), CurvatureClass::parabolic);
  EXPECT_EQ(classify(0.01, 0.003, t), CurvatureClass::elliptic);
  EXPECT_EQ(classify(-0.003, -0.01, t), CurvatureClass::elliptic);
  EXPECT_EQ(classify(0.01, -0.003, t), CurvatureClass::hyperbolic);
  EXPECT_EQ(classify(std::nan(""), 1.0, t), CurvatureClass::planar);
  EXPECT_STREQ(class_name(CurvatureClass::hyperbolic), "hyperbolic");
}

}  // namespace
}  // namespace ph
