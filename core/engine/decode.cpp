#include "core/engine/decode.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/engine/row_bands.hpp"

namespace ph {
namespace {

// A decoded length below this means the texel held no direction (e.g. a black pixel).
constexpr double min_normal_length = 0.5;

std::size_t texel_count(std::int32_t width, std::int32_t height) {
  return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
}

// Throws unless the image has a size and exactly width x height x channels pixel values.
void require_consistent(const RawImage& image) {
  if (image.width <= 0 || image.height <= 0) {
    throw FieldError("image has zero size (" + std::to_string(image.width) + " x " + std::to_string(image.height) +
                     " px)");
  }
  if (image.channels <= 0 || image.pixels.size() != texel_count(image.width, image.height) * image.channels) {
    throw FieldError("image holds " + std::to_string(image.pixels.size()) + " values, not " +
                     std::to_string(image.width) + " x " + std::to_string(image.height) + " x " +
                     std::to_string(image.channels) + " channels");
  }
}

void require_normal_channels(const RawImage& image) {
  if (image.channels != 3 && image.channels != 4) {
    throw FieldError("a normal map needs 3 (RGB) or 4 (RGBA) channels, this image has " +
                     std::to_string(image.channels));
  }
}

void require_depth_channels(const RawImage& image) {
  if (image.channels != 1 && image.channels != 2) {
    throw FieldError("a depth map needs 1 channel (grey) or 2 (grey + alpha), this image has " +
                     std::to_string(image.channels));
  }
}

bool stores_unorm(const RawImage& image, NormalEncoding encoding) {
  switch (encoding) {
    case NormalEncoding::unorm:
      return true;
    case NormalEncoding::signed_values:
      return false;
    case NormalEncoding::automatic:
      break;
  }
  return !image.is_float;
}

// The screen-frame unit normal of one texel, or nothing when the texel is invalid.
// `zero_band`: tangent components this close to 0 are quantisation of 0 (see decode.hpp).
std::optional<Normal> decode_normal_texel(const float* rgb, bool unorm, double zero_band, GreenConvention green) {
  std::array<double, 3> c{rgb[0], rgb[1], rgb[2]};
  if (unorm) {
    for (double& v : c) v = 2.0 * v - 1.0;
    for (int i = 0; i < 2; ++i) {
      if (std::abs(c[i]) <= zero_band) c[i] = 0.0;
    }
  }
  // Tangent space has +green toward the top of the image; screen y points down.
  const double x = c[0];
  const double y = green == GreenConvention::opengl ? -c[1] : c[1];
  const double z = c[2];
  const double length = std::sqrt(x * x + y * y + z * z);
  if (!std::isfinite(length) || length < min_normal_length || z <= 0.0) return std::nullopt;
  return Normal{static_cast<float>(x / length), static_cast<float>(y / length), static_cast<float>(z / length)};
}

// Replaces every texel whose valid flag is 0 by the value of its nearest valid texel, nearest by a
// multi-source breadth-first search over the 8-neighbourhood (Chebyshev distance; ties go to the texel
// reached first). With no valid texel at all, every texel becomes the fallback.
template <typename T>
void repair_from_nearest_valid(Grid<T>& grid, std::vector<std::uint8_t> valid, T fallback) {
  const std::int32_t w = grid.width;
  const std::int32_t h = grid.height;
  auto is_valid = [&](std::int32_t x, std::int32_t y) { return valid[static_cast<std::size_t>(y) * w + x] != 0; };
  auto has_invalid_neighbour = [&](std::int32_t x, std::int32_t y) {
    for (std::int32_t ny = std::max(y - 1, 0); ny <= std::min(y + 1, h - 1); ++ny) {
      for (std::int32_t nx = std::max(x - 1, 0); nx <= std::min(x + 1, w - 1); ++nx) {
        if (!is_valid(nx, ny)) return true;
      }
    }
    return false;
  };

  // Only valid texels that touch an invalid one can be someone's nearest, so only they seed the search.
  std::vector<std::pair<std::int32_t, std::int32_t>> queue;
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      if (is_valid(x, y) && has_invalid_neighbour(x, y)) queue.emplace_back(x, y);
    }
  }
  if (queue.empty()) {
    std::fill(grid.values.begin(), grid.values.end(), fallback);
    return;
  }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const auto [x, y] = queue[head];
    for (std::int32_t ny = std::max(y - 1, 0); ny <= std::min(y + 1, h - 1); ++ny) {
      for (std::int32_t nx = std::max(x - 1, 0); nx <= std::min(x + 1, w - 1); ++nx) {
        if (is_valid(nx, ny)) continue;
        grid.at(nx, ny) = grid.at(x, y);
        valid[static_cast<std::size_t>(ny) * w + nx] = 1;
        queue.emplace_back(nx, ny);
      }
    }
  }
}

// --- Separable resampling -------------------------------------------------------------------------

struct Tap {
  std::int32_t source = 0;
  double weight = 0.0;
};
using Taps = std::vector<Tap>;  // the source texels that make one output texel

// Bilinear taps with texel centres aligned: output i samples the source at (i + 0.5) * in / out - 0.5.
Taps bilinear_taps(std::int32_t i, std::int32_t in, std::int32_t out) {
  const double position = (i + 0.5) * static_cast<double>(in) / out - 0.5;
  const double clamped = std::clamp(position, 0.0, static_cast<double>(in - 1));
  const auto left = static_cast<std::int32_t>(std::floor(clamped));
  const std::int32_t right = std::min(left + 1, in - 1);
  const double t = clamped - left;
  return {{left, 1.0 - t}, {right, t}};
}

// Box-filter taps: output i averages the source interval [i, i + 1) * in / out, edge texels by coverage.
Taps area_taps(std::int32_t i, std::int32_t in, std::int32_t out) {
  const double scale = static_cast<double>(in) / out;
  const double begin = i * scale;
  const double end = std::min((i + 1) * scale, static_cast<double>(in));
  Taps taps;
  double total = 0.0;
  for (auto j = static_cast<std::int32_t>(std::floor(begin)); j < in && j < end; ++j) {
    const double coverage = std::min(end, j + 1.0) - std::max(begin, static_cast<double>(j));
    if (coverage <= 0.0) continue;
    taps.push_back({j, coverage});
    total += coverage;
  }
  for (Tap& tap : taps) tap.weight /= total;
  return taps;
}

// For each of `out` output texels along an axis of `in` source texels.
std::vector<Taps> axis_taps(std::int32_t in, std::int32_t out) {
  std::vector<Taps> taps(static_cast<std::size_t>(out));
  for (std::int32_t i = 0; i < out; ++i) {
    if (in == out) {
      taps[i] = {{i, 1.0}};
    } else if (out > in) {
      taps[i] = bilinear_taps(i, in, out);
    } else {
      taps[i] = area_taps(i, in, out);
    }
  }
  return taps;
}

// One channel, row-major.
struct Plane {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::vector<float> values;
};

Plane resample_rows(const Plane& in, std::int32_t width) {
  const std::vector<Taps> taps = axis_taps(in.width, width);
  Plane out{width, in.height, std::vector<float>(texel_count(width, in.height))};
  for (std::int32_t y = 0; y < in.height; ++y) {
    const float* row = &in.values[static_cast<std::size_t>(y) * in.width];
    for (std::int32_t x = 0; x < width; ++x) {
      double sum = 0.0;
      for (const Tap& tap : taps[x]) sum += tap.weight * row[tap.source];
      out.values[static_cast<std::size_t>(y) * width + x] = static_cast<float>(sum);
    }
  }
  return out;
}

Plane resample_columns(const Plane& in, std::int32_t height) {
  const std::vector<Taps> taps = axis_taps(in.height, height);
  Plane out{in.width, height, std::vector<float>(texel_count(in.width, height))};
  for (std::int32_t y = 0; y < height; ++y) {
    for (std::int32_t x = 0; x < in.width; ++x) {
      double sum = 0.0;
      for (const Tap& tap : taps[y]) sum += tap.weight * in.values[static_cast<std::size_t>(tap.source) * in.width + x];
      out.values[static_cast<std::size_t>(y) * in.width + x] = static_cast<float>(sum);
    }
  }
  return out;
}

Plane resample_plane(const Plane& in, std::int32_t width, std::int32_t height) {
  return resample_columns(resample_rows(in, width), height);
}

void require_resample_sizes(std::int32_t in_width, std::int32_t in_height, std::int32_t width, std::int32_t height) {
  if (in_width <= 0 || in_height <= 0) throw FieldError("cannot resample an empty field");
  if (width < 1 || height < 1) {
    throw FieldError("cannot resample to " + std::to_string(width) + " x " + std::to_string(height) +
                     " texels: both sides must be at least 1");
  }
}

// Unit length again after averaging; a vector that cannot be normalised becomes flat.
Normal renormalised(double x, double y, double z) {
  const double length = std::sqrt(x * x + y * y + z * z);
  if (!std::isfinite(length) || length <= 0.0) return Normal{};
  return {static_cast<float>(x / length), static_cast<float>(y / length), static_cast<float>(z / length)};
}

// A normal component's step between codes: a unorm code c is 2c / cmax - 1, a signed one c / cmax.
double normal_value_step(const RawImage& image, bool unorm) {
  if (image.code_max == 0) return 0.0;
  return (unorm ? 2.0 : 1.0) / image.code_max;
}

}  // namespace

double gradient_rounding_of_normals(double value_step) { return value_step / std::sqrt(12.0); }
double gradient_rounding_of_depth(double value_step) { return value_step / std::sqrt(24.0); }
double height_rounding_of_depth(double value_step) { return value_step / std::sqrt(12.0); }
double depth_step_of_rounding(double height_rounding) { return height_rounding * std::sqrt(12.0); }

NormalImage decode_normals(const RawImage& image, const NormalDecodeOptions& options, DecodeReport& report) {
  require_normal_channels(image);
  require_consistent(image);
  const bool unorm = stores_unorm(image, options.encoding);
  // One code is 2/cmax in n; half of it plus float slack catches the two codes around 0.
  const double zero_band = image.code_max > 0 ? 1.0 / image.code_max + 1e-7 : 0.0;
  NormalImage normals(image.width, image.height);
  std::vector<std::uint8_t> valid(normals.values.size(), 1);
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < normals.values.size(); ++i) {
    const std::optional<Normal> n =
        decode_normal_texel(&image.pixels[i * image.channels], unorm, zero_band, options.green);
    if (n) {
      normals.values[i] = *n;
    } else {
      valid[i] = 0;
      ++invalid;
    }
  }
  if (invalid > 0) repair_from_nearest_valid(normals, std::move(valid), Normal{});
  report = {normals.values.size(), invalid, normal_value_step(image, unorm), image.width, image.height};
  return normals;
}

namespace {

// decode_normal_texel then clamped_gradient for one row of a unorm image, in a form the compiler vectorises:
// the same operations in the same order (identical results), selects instead of branches. A texel that is
// not valid gets ok = 0 and a gradient to be repaired. Returns the number of such texels.
std::size_t decode_unorm_row(const float* pixels, std::int32_t channels, std::size_t count, double zero_band,
                             bool opengl, std::vector<float>& planes, Gradient* out, std::uint8_t* ok) {
  planes.resize(4 * count);
  float* __restrict r = planes.data();
  float* __restrict g = r + count;
  float* __restrict b = g + count;
  float* __restrict marks = b + count;  // 1 valid, 0 not: floats, so that the loop has one element width
  for (std::size_t i = 0; i < count; ++i) {
    r[i] = pixels[i * channels];
    g[i] = pixels[i * channels + 1];
    b[i] = pixels[i * channels + 2];
  }
  const double flip = opengl ? -1.0 : 1.0;  // an exact negation, or nothing
  // std::clamp by value: the same comparisons, without the references that keep the loop from vectorising.
  auto clamp_slope = [](float v) { return v < -kMaxSlope ? -kMaxSlope : (kMaxSlope < v ? kMaxSlope : v); };
  Gradient* __restrict dst = out;
  for (std::size_t i = 0; i < count; ++i) {
    double x = 2.0 * r[i] - 1.0;
    double y = 2.0 * g[i] - 1.0;
    const double z = 2.0 * b[i] - 1.0;
    x = std::abs(x) <= zero_band ? 0.0 : x;
    y = (std::abs(y) <= zero_band ? 0.0 : y) * flip;
    const double length = std::sqrt(x * x + y * y + z * z);
    const bool valid = (length >= min_normal_length) & (length <= std::numeric_limits<double>::max()) & (z > 0.0);
    const float nx = static_cast<float>(x / length), ny = static_cast<float>(y / length);
    const float nz = static_cast<float>(z / length);
    dst[i] = {clamp_slope(-nx / nz), clamp_slope(-ny / nz)};
    marks[i] = valid ? 1.0f : 0.0f;
  }
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < count; ++i) {
    ok[i] = marks[i] != 0.0f ? 1 : 0;
    invalid += marks[i] != 0.0f ? 0 : 1;
  }
  return invalid;
}

}  // namespace

GradientField decode_normals_to_gradient(const RawImage& image, const NormalDecodeOptions& options,
                                         DecodeReport& report, unsigned threads) {
  require_normal_channels(image);
  require_consistent(image);
  const bool unorm = stores_unorm(image, options.encoding);
  const double zero_band = image.code_max > 0 ? 1.0 / image.code_max + 1e-7 : 0.0;
  GradientField gradient(image.width, image.height);
  std::vector<std::uint8_t> valid(gradient.values.size(), 1);
  std::size_t invalid = 0;
  if (unorm) {
    const auto width = static_cast<std::size_t>(image.width);
    std::atomic<std::size_t> invalid_in_bands{0};
    for_row_bands_on_threads(image.height, threads, [&](RowRange rows) {
      std::vector<float> planes;
      std::size_t count = 0;
      for (auto row = static_cast<std::size_t>(rows.begin); row < static_cast<std::size_t>(rows.end); ++row) {
        const std::size_t first = row * width;
        count +=
            decode_unorm_row(&image.pixels[first * image.channels], image.channels, width, zero_band,
                             options.green == GreenConvention::opengl, planes, &gradient.values[first], &valid[first]);
      }
      invalid_in_bands += count;
    });
    invalid = invalid_in_bands;
  } else {
    for (std::size_t i = 0; i < gradient.values.size(); ++i) {
      const std::optional<Normal> n =
          decode_normal_texel(&image.pixels[i * image.channels], unorm, zero_band, options.green);
      if (n) {
        gradient.values[i] = clamped_gradient(*n);
      } else {
        valid[i] = 0;
        ++invalid;
      }
    }
  }
  // A texel's gradient depends on its normal alone, so repairing gradients equals repairing normals first;
  // the fallback is a flat normal's gradient.
  if (invalid > 0) repair_from_nearest_valid(gradient, std::move(valid), clamped_gradient(Normal{}));
  report = {gradient.values.size(), invalid, normal_value_step(image, unorm), image.width, image.height};
  return gradient;
}

DepthField decode_depth(const RawImage& image, const DepthDecodeOptions& options, DecodeReport& report) {
  require_depth_channels(image);
  require_consistent(image);
  DepthField depth(image.width, image.height);
  std::vector<std::uint8_t> valid(depth.values.size(), 1);
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < depth.values.size(); ++i) {
    const double v = image.pixels[i * image.channels];
    const double h = (v - options.depth_zero) * options.relief_px;
    if (std::isfinite(h) && std::abs(h) <= std::numeric_limits<float>::max()) {
      depth.values[i] = static_cast<float>(h);
    } else {
      valid[i] = 0;
      ++invalid;
    }
  }
  if (invalid > 0) repair_from_nearest_valid(depth, std::move(valid), 0.0f);
  report = {depth.values.size(), invalid, image.code_max > 0 ? std::abs(options.relief_px) / image.code_max : 0.0,
            image.width, image.height};
  return depth;
}

NormalImage resample_normals(const NormalImage& image, std::int32_t width, std::int32_t height) {
  require_resample_sizes(image.width, image.height, width, height);
  if (image.width == width && image.height == height) return image;
  std::array<Plane, 3> planes;
  for (Plane& plane : planes) plane = {image.width, image.height, std::vector<float>(image.values.size())};
  for (std::size_t i = 0; i < image.values.size(); ++i) {
    planes[0].values[i] = image.values[i].x;
    planes[1].values[i] = image.values[i].y;
    planes[2].values[i] = image.values[i].z;
  }
  for (Plane& plane : planes) plane = resample_plane(plane, width, height);
  NormalImage out(width, height);
  for (std::size_t i = 0; i < out.values.size(); ++i) {
    out.values[i] = renormalised(planes[0].values[i], planes[1].values[i], planes[2].values[i]);
  }
  return out;
}

DepthField resample_depth(const DepthField& depth, std::int32_t width, std::int32_t height) {
  require_resample_sizes(depth.width, depth.height, width, height);
  if (depth.width == width && depth.height == height) return depth;
  Plane resampled = resample_plane({depth.width, depth.height, depth.values}, width, height);
  DepthField out;
  out.width = width;
  out.height = height;
  out.values = std::move(resampled.values);
  return out;
}

}  // namespace ph
