#include "core/effects/curvature_class.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

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

// How many bands of rows a class map of `height` rows is worked out in.
unsigned band_count(std::int32_t height, unsigned threads) {
  if (threads == 0) threads = std::min(std::max(std::thread::hardware_concurrency(), 1u), kMaxClassMapThreads);
  const auto most = static_cast<unsigned>(std::max<std::int32_t>(height / kMinClassMapRows, 1));
  return std::min(threads, most);
}

// Each band on a thread of its own but the first, which the caller's thread works out, as it does any band whose
// thread cannot be started; an exception in any band (memory) is thrown again here once all have ended.
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
  const std::int32_t h = field.height;
  const auto bands = static_cast<std::int32_t>(band_count(h, threads));
  auto band = [&](std::int32_t b) {
    return RowRange{static_cast<std::int32_t>(std::int64_t{h} * b / bands),
                    static_cast<std::int32_t>(std::int64_t{h} * (b + 1) / bands)};
  };
  std::vector<std::exception_ptr> failed(static_cast<std::size_t>(bands));
  const auto run_band = [&](std::int32_t b) {
    try {
      classify_band(band(b));
    } catch (...) {
      failed[static_cast<std::size_t>(b)] = std::current_exception();
    }
  };
  {
    std::vector<std::jthread> workers;
    std::vector<std::int32_t> here{0};
    for (std::int32_t b = 1; b < bands; ++b) {
      try {
        workers.emplace_back(run_band, b);
      } catch (const std::system_error&) {
        here.push_back(b);
      }
    }
    for (std::int32_t b : here) run_band(b);
  }  // the workers join here
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
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
