#include "core/engine/method_hybrid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ph {

namespace {

bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

// One pass of the binomial kernel [1 2 1] / 4 along x and then along y, the border texels repeated; written as
// differences from the texel's own value, so that a constant field stays exactly constant.
GradientField binomial_pass(const GradientField& in) {
  const std::int32_t w = in.width, h = in.height;
  auto smooth = [](Gradient a, Gradient c, Gradient b) {
    return Gradient{c.x + 0.25f * ((a.x - c.x) + (b.x - c.x)), c.y + 0.25f * ((a.y - c.y) + (b.y - c.y))};
  };
  GradientField along_x(w, h);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x)
      along_x.at(x, y) = smooth(in.at(std::max(x - 1, 0), y), in.at(x, y), in.at(std::min(x + 1, w - 1), y));
  }
  GradientField out(w, h);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      out.at(x, y) = smooth(along_x.at(x, std::max(y - 1, 0)), along_x.at(x, y), along_x.at(x, std::min(y + 1, h - 1)));
    }
  }
  return out;
}

// How far a height change `dh` over 1 px lies outside the slopes a and b of the two texels: a continuous surface
// whose slope goes from a to b changes by anything between them (a kink or a rim between the centres included),
// so only the excess is unexplained.
double unexplained(double dh, double a, double b) {
  const double lo = std::min(a, b), hi = std::max(a, b);
  return dh < lo ? lo - dh : (dh > hi ? dh - hi : 0.0);
}

// Marks both texels of every edge across which the height changes by more than `threshold` beyond what the
// normals explain.
DiscontinuityField find_discontinuities(const GradientField& g, const DepthField& d, double threshold) {
  const std::int32_t w = g.width, h = g.height;
  DiscontinuityField marks(w, h, 0);
  for (std::int32_t y = 0; y < h; ++y) {
    for (std::int32_t x = 0; x < w; ++x) {
      if (x + 1 < w && unexplained(d.at(x + 1, y) - d.at(x, y), g.at(x, y).x, g.at(x + 1, y).x) > threshold)
        marks.at(x, y) = marks.at(x + 1, y) = 1;
      if (y + 1 < h && unexplained(d.at(x, y + 1) - d.at(x, y), g.at(x, y).y, g.at(x, y + 1).y) > threshold)
        marks.at(x, y) = marks.at(x, y + 1) = 1;
    }
  }
  return marks;
}

}  // namespace

std::string validate(const HybridParams& p) {
  if (!(std::isfinite(p.discontinuity_px) && p.discontinuity_px > 0.0))
    return "discontinuity_px must be a finite number > 0";
  if (!finite_non_negative(p.noise_slope)) return "noise_slope must be a finite number >= 0";
  if (!finite_non_negative(p.far_noise_gain)) return "far_noise_gain must be a finite number >= 0";
  return {};
}

void prepare_hybrid_fields(const HybridParams& params, RegionFields& fields) {
  if (!fields.gradient || fields.discontinuity) return;  // prepared once: a scene built again keeps its fields
  GradientField& g = *fields.gradient;
  const bool has_depth = fields.depth && fields.depth->width == g.width && fields.depth->height == g.height;
  fields.discontinuity = has_depth ? find_discontinuities(g, *fields.depth, params.discontinuity_px)
                                   : DiscontinuityField(g.width, g.height, 0);
  if (params.noise_slope <= 0.0) return;
  // Two passes: a Gaussian of about 1 px.
  const GradientField smoothed = binomial_pass(binomial_pass(g));
  float lowest = 0.0f, highest = 0.0f;
  if (has_depth) {
    const auto [lo, hi] = std::minmax_element(fields.depth->values.begin(), fields.depth->values.end());
    lowest = *lo;
    highest = *hi;
  }
  const double range = static_cast<double>(highest) - lowest;
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    const double farness = range > 0.0 ? (highest - static_cast<double>(fields.depth->values[i])) / range : 0.0;
    const double band = params.noise_slope * (1.0 + params.far_noise_gain * farness);
    const Gradient s = smoothed.values[i];
    // Within the band the difference is the map's noise (rounding, a generator's jitter); beyond it, a
    // feature (a rim, a kink), which stays sharp.
    if (std::abs(s.x - g.values[i].x) <= band && std::abs(s.y - g.values[i].y) <= band) g.values[i] = s;
  }
}

void HybridMethod::prepare(RegionFields& fields) const { prepare_hybrid_fields(params_, fields); }

HybridParams HybridMethod::parse_params(const ParamReader& reader) {
  HybridParams p;
  if (const auto v = reader.number("discontinuity_px")) p.discontinuity_px = *v;
  if (!(std::isfinite(p.discontinuity_px) && p.discontinuity_px > 0.0))
    reader.reject("discontinuity_px", "must be a finite number > 0 (px of height)");
  if (const auto v = reader.number("noise_slope")) p.noise_slope = *v;
  if (!finite_non_negative(p.noise_slope))
    reader.reject("noise_slope", "must be a finite number >= 0 (0: no smoothing)");
  if (const auto v = reader.number("far_noise_gain")) p.far_noise_gain = *v;
  if (!finite_non_negative(p.far_noise_gain)) reader.reject("far_noise_gain", "must be a finite number >= 0");
  return p;
}

HybridMethod::HybridMethod(const HybridParams& params) : Method(method_tag<HybridMethod>()), params_(params) {
  if (auto error = validate(params); !error.empty()) throw std::invalid_argument("hybrid method: " + error);
}

}  // namespace ph
