#include "core/lab/map_storage.hpp"

#include <algorithm>
#include <cmath>

namespace ph {

RawImage quantised_image(std::int32_t width, std::int32_t height, int channels, const std::vector<double>& values,
                         std::uint32_t code_max) {
  RawImage image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.code_max = code_max;
  image.pixels.resize(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double code = std::round(std::clamp(values[i], 0.0, 1.0) * code_max);
    image.pixels[i] = static_cast<float>(code / code_max);
  }
  return image;
}

RawImage encode_normal_map(const NormalImage& normals, std::uint32_t code_max) {
  std::vector<double> v;
  v.reserve(normals.values.size() * 3);
  for (const Normal& n : normals.values) {
    v.push_back((n.x + 1.0) / 2.0);
    v.push_back((-n.y + 1.0) / 2.0);
    v.push_back((n.z + 1.0) / 2.0);
  }
  return quantised_image(normals.width, normals.height, 3, v, code_max);
}

DepthDecodeOptions depth_options_for(double lo, double hi) {
  const double range = hi > lo ? hi - lo : 1.0;
  return {-lo / range, range};
}

RawImage encode_depth_map(const DepthField& depth, double lo, double hi, std::uint32_t code_max) {
  const DepthDecodeOptions o = depth_options_for(lo, hi);
  std::vector<double> v(depth.values.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = depth.values[i] / o.relief_px + o.depth_zero;
  return quantised_image(depth.width, depth.height, 1, v, code_max);
}

NormalImage stored_normals(const NormalImage& normals, std::uint32_t code_max, DecodeReport* report) {
  DecodeReport decoded{normals.values.size(), 0, 0.0, normals.width, normals.height};
  NormalImage out = code_max == 0 ? normals : decode_normals(encode_normal_map(normals, code_max), {}, decoded);
  if (report != nullptr) *report = decoded;
  return out;
}

DepthField stored_depth(const DepthField& depth, std::uint32_t code_max, DecodeReport* report) {
  DecodeReport decoded{depth.values.size(), 0, 0.0, depth.width, depth.height};
  DepthField out = depth;
  if (code_max != 0 && !depth.empty()) {
    const auto [lo, hi] = std::minmax_element(depth.values.begin(), depth.values.end());
    out = decode_depth(encode_depth_map(depth, *lo, *hi, code_max), depth_options_for(*lo, *hi), decoded);
  }
  if (report != nullptr) *report = decoded;
  return out;
}

NormalImage sobel_normals(const DepthField& depth, double strength) {
  const std::int32_t w = depth.width, h = depth.height;
  NormalImage out(w, h);
  auto at = [&](std::int32_t x, std::int32_t y) {
    return static_cast<double>(depth.at(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1)));
  };
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      const double gx = (at(x + 1, y - 1) + 2.0 * at(x + 1, y) + at(x + 1, y + 1) - at(x - 1, y - 1) -
                         2.0 * at(x - 1, y) - at(x - 1, y + 1)) /
                        8.0;
      const double gy = (at(x - 1, y + 1) + 2.0 * at(x, y + 1) + at(x + 1, y + 1) - at(x - 1, y - 1) -
                         2.0 * at(x, y - 1) - at(x + 1, y - 1)) /
                        8.0;
      out.at(x, y) = normal_from_gradient({static_cast<float>(strength * gx), static_cast<float>(strength * gy)});
    }
  }
  return out;
}

}  // namespace ph
