#include "core/effects/curvature_class.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/engine/row_bands.hpp"

namespace ph {

const char* class_name(CurvatureClass c) {
  switch (c) {
    case CurvatureClass::planar:
      return "planar";
    case CurvatureClass::parabolic:
      return "parabolic";
    case CurvatureClass::elliptic:
      return "elliptic";
    case CurvatureClass::hyperbolic:
      return "hyperbolic";
  }
  return "unknown";
}

CurvatureClass classify(double k1, double k2, const ClassTolerances& tolerances) {
  if (!std::isfinite(k1) || !std::isfinite(k2)) return CurvatureClass::planar;
  const double curvedness = std::sqrt((k1 * k1 + k2 * k2) / 2.0);
  if (curvedness < tolerances.planar_curvedness) return CurvatureClass::planar;
  const double small = std::min(std::abs(k1), std::abs(k2));
  const double large = std::max(std::abs(k1), std::abs(k2));  // > 0: the curvedness is not 0
  if (small < tolerances.parabolic_ratio * large) return CurvatureClass::parabolic;
  return k1 * k2 > 0.0 ? CurvatureClass::elliptic : CurvatureClass::hyperbolic;
}

Grid<std::uint8_t> class_map(const CurvatureFields& fields, const ClassTolerances& tolerances) {
  const bool principal = !fields.k1.empty() && !fields.k2.empty();
  const bool from_kh = !fields.gaussian.empty() && !fields.mean.empty();
  if (!principal && !from_kh) return {};
  const Grid<float>& shape = principal ? fields.k1 : fields.gaussian;
  Grid<std::uint8_t> out(shape.width, shape.height);
  for (std::size_t i = 0; i < out.values.size(); ++i) {
    double k1 = 0.0, k2 = 0.0;
    if (principal) {
      k1 = fields.k1.values[i];
      k2 = fields.k2.values[i];
    } else {
      const double h = fields.mean.values[i];
      const double spread = std::sqrt(std::max(h * h - double(fields.gaussian.values[i]), 0.0));
      k1 = h + spread;
      k2 = h - spread;
    }
    out.values[i] = static_cast<std::uint8_t>(classify(k1, k2, tolerances));
  }
  return out;
}

namespace {

// Each band of rows on a thread of its own (for_each_row_band); a row's classes depend on the rows its filter's
// window reads alone.
template <typename Field, typename Rows>
Grid<std::uint8_t> classes_by_row(const Field& field, const DerivativeFilter& filter, const ClassTolerances& tolerances,
                                  unsigned threads, Rows rows) {
  Grid<std::uint8_t> out(field.width, field.height);
  const auto classify_band = [&](RowRange band) {
    rows(field, filter, band, [&](std::int32_t y, const float* k1, const float* k2) {
      std::uint8_t* row = &out.values[static_cast<std::size_t>(y) * static_cast<std::size_t>(out.width)];
      for (std::int32_t x = 0; x < out.width; ++x)
        row[x] = static_cast<std::uint8_t>(classify(k1[x], k2[x], tolerances));
    });
  };
  for_row_bands_on_threads(field.height, threads, classify_band);
  return out;
}

}  // namespace

Grid<std::uint8_t> class_map_from_depth(const DepthField& depth, const DerivativeFilter& filter,
                                        const ClassTolerances& tolerances, unsigned threads) {
  return classes_by_row(depth, filter, tolerances, threads, principal_rows_from_depth);
}

Grid<std::uint8_t> class_map_from_gradient(const GradientField& gradient, const DerivativeFilter& filter,
                                           const ClassTolerances& tolerances, unsigned threads) {
  return classes_by_row(gradient, filter, tolerances, threads, principal_rows_from_gradient);
}

}  // namespace ph
