#include "core/lab/failure_modes.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <stdexcept>
#include <utility>

#include "core/lab/map_storage.hpp"

namespace ph {

namespace {

constexpr double kPi = std::numbers::pi;
double radians(double deg) { return deg * kPi / 180.0; }
double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }

// A relief of one coordinate: a 1-D profile h(u), u = (p - centre) . direction, or of the distance r to the centre.
struct Profile {
  std::function<double(double)> h, dh;
  std::vector<double> kinks;  // where h or dh is not smooth
  bool flat_normals = false;  // the normals are (0, 0, 1) whatever h does (a height jump a normal map cannot see)
};

class ProfileSurface final : public AnalyticSurface {
 public:
  ProfileSurface(Vec2 centre, Vec2 direction, Profile profile)
      : c_(centre), d_(direction), profile_(std::move(profile)) {}
  double height(Vec2 p) const override { return profile_.h(dot(p - c_, d_)); }
  ExactGradient gradient(Vec2 p) const override {
    if (profile_.flat_normals) return {};
    const double s = profile_.dh(dot(p - c_, d_));
    return {s * d_.x, s * d_.y};
  }
  void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const override {
    const double md = dot(m, d_);
    if (md == 0.0) return;
    const double start = dot(p0 - c_, d_);
    for (double k : profile_.kinks) {
      const double s = (k - start) / md;
      if (s > u0 && s < u1) out.push_back(s);
    }
  }

 private:
  Vec2 c_, d_;
  Profile profile_;
};

class RadialSurface final : public AnalyticSurface {
 public:
  RadialSurface(Vec2 centre, Profile profile) : c_(centre), profile_(std::move(profile)) {}
  double height(Vec2 p) const override { return profile_.h(length(p - c_)); }
  ExactGradient gradient(Vec2 p) const override {
    const Vec2 v = p - c_;
    const double r = length(v);
    if (r == 0.0) return {};
    const double s = profile_.dh(r);
    return {s * v.x / r, s * v.y / r};
  }
  void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const override {
    const Vec2 v = c_ - p0;
    const double closest = dot(v, m);
    const double perp2 = std::max(dot(v, v) - closest * closest, 0.0);
    auto add = [&](double s) {
      if (s > u0 && s < u1) out.push_back(s);
    };
    add(closest);  // the apex, or the steepest turn of the profile along the line
    for (double r : profile_.kinks) {
      if (r * r < perp2) continue;
      const double half = std::sqrt(r * r - perp2);
      add(closest - half);
      add(closest + half);
    }
  }

 private:
  Vec2 c_;
  Profile profile_;
};

// A sum of plane waves about a centre: h = sum a sin(k . (p - c) + phase).
struct Wave {
  Vec2 k;
  double amplitude = 0.0;
  double phase = 0.0;
};

class SpectralSurface final : public AnalyticSurface {
 public:
  SpectralSurface(Vec2 centre, std::vector<Wave> waves) : c_(centre), waves_(std::move(waves)) {}
  double height(Vec2 p) const override {
    double h = 0.0;
    for (const Wave& w : waves_) h += w.amplitude * std::sin(dot(w.k, p - c_) + w.phase);
    return h;
  }
  ExactGradient gradient(Vec2 p) const override {
    ExactGradient g;
    for (const Wave& w : waves_) {
      const double s = w.amplitude * std::cos(dot(w.k, p - c_) + w.phase);
      g.x += s * w.k.x;
      g.y += s * w.k.y;
    }
    return g;
  }
  void breakpoints(Vec2, Vec2, double, double, std::vector<double>&) const override {}

 private:
  Vec2 c_;
  std::vector<Wave> waves_;
};

// Regions' surfaces on the screen, later ones on top, flat outside them all: what the scene's regions hold.
struct Layer {
  Rect rect;
  std::shared_ptr<const AnalyticSurface> surface;
};

bool inside(const Rect& r, Vec2 p) { return p.x >= r.x && p.y >= r.y && p.x < r.x + r.w && p.y < r.y + r.h; }

class LayeredSurface final : public AnalyticSurface {
 public:
  explicit LayeredSurface(std::vector<Layer> layers) : layers_(std::move(layers)) {}
  double height(Vec2 p) const override {
    const Layer* l = top(p);
    return l != nullptr ? l->surface->height(p) : 0.0;
  }
  ExactGradient gradient(Vec2 p) const override {
    const Layer* l = top(p);
    return l != nullptr ? l->surface->gradient(p) : ExactGradient{};
  }
  bool outside_regions(Vec2 p) const override { return top(p) == nullptr; }
  void breakpoints(Vec2 p0, Vec2 m, double u0, double u1, std::vector<double>& out) const override {
    for (const Layer& l : layers_) {
      auto add = [&](double start, double dir, double edge) {
        if (dir == 0.0) return;
        const double s = (edge - start) / dir;
        if (s > u0 && s < u1) out.push_back(s);
      };
      add(p0.x, m.x, l.rect.x);
      add(p0.x, m.x, l.rect.x + l.rect.w);
      add(p0.y, m.y, l.rect.y);
      add(p0.y, m.y, l.rect.y + l.rect.h);
      l.surface->breakpoints(p0, m, u0, u1, out);
    }
  }

 private:
  const Layer* top(Vec2 p) const {
    for (auto it = layers_.rbegin(); it != layers_.rend(); ++it) {
      if (inside(it->rect, p)) return &*it;
    }
    return nullptr;
  }
  std::vector<Layer> layers_;
};

// How the maps of a case are stored, as a user's files would be.
struct Storage {
  bool sobel_normals = false;         // normals made from the depth map by a generator, not the exact ones
  bool sobel_from_stored = false;     // ... from the depth map as stored (quantised), as a generator reads a file
  std::uint32_t normal_code_max = 0;  // 0: float
  std::uint32_t depth_code_max = 0;
  double normal_noise = 0.0;  // sigma of the noise added to n_x and n_y before renormalising
};

struct Recipe {
  std::vector<Layer> layers;
  Storage storage;
  Vec2 centre;                   // of the strokes
  std::vector<double> features;  // along the central stroke's direction, px from the centre
  bool turns_relief = true;      // false: the regions keep their rectangles, only the strokes turn
};

Profile step_profile(double height) {
  return {[height](double u) { return u >= 0.0 ? height : 0.0; }, [](double) { return 0.0; }, {0.0}, true};
}

Profile kink_profile(double slope, double half_width) {
  return {[=](double u) { return slope * std::max(0.0, half_width - std::abs(u)); },
          [=](double u) { return std::abs(u) < half_width ? (u > 0.0 ? -slope : (u < 0.0 ? slope : 0.0)) : 0.0; },
          {-half_width, 0.0, half_width}};
}

Profile gaussian_profile(double height, double sigma) {
  return {[=](double r) { return height * std::exp(-r * r / (2.0 * sigma * sigma)); },
          [=](double r) { return -height * r / (sigma * sigma) * std::exp(-r * r / (2.0 * sigma * sigma)); },
          {}};
}

std::uint32_t code_max_of_bits(double bits) {
  return bits >= 32.0 ? 0u : static_cast<std::uint32_t>((std::uint64_t{1} << static_cast<int>(bits)) - 1);
}

// A fractional Brownian relief by spectral synthesis: octaves of period 128 px down to 4 px, amplitude
// proportional to period^0.8 (128 px: `amplitude`), three waves of random direction and phase each; one seeded
// surface, turned by the angle.
std::vector<Wave> fbm_waves(double amplitude, double angle) {
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> turn(0.0, 2.0 * kPi);
  std::vector<Wave> waves;
  for (double period = 128.0; period >= 4.0; period /= 2.0) {
    for (int i = 0; i < 3; ++i) {
      const double dir = turn(rng) + angle;
      const double phase = turn(rng);
      const double k = 2.0 * kPi / period;
      waves.push_back({{k * std::cos(dir), k * std::sin(dir)}, amplitude * std::pow(period / 128.0, 0.8), phase});
    }
  }
  return waves;
}

Recipe recipe_for(const std::string& mode, double sev, double angle, const CaseGeometry& g) {
  const double S = g.size;
  const Vec2 c{S / 2.0, S / 2.0};
  const Vec2 d{std::cos(angle), std::sin(angle)};
  const Rect all{0, 0, g.size, g.size};
  Recipe r;
  r.centre = c;
  auto profile_layer = [&](Profile p) { return Layer{all, std::make_shared<ProfileSurface>(c, d, std::move(p))}; };
  if (mode == "jump") {
    r.layers = {profile_layer(step_profile(sev))};
    r.features = {0.0};
  } else if (mode == "terraces") {
    const double tread = std::max(3.0, std::round(S * 0.094));
    Profile p{[=](double u) { return sev * std::clamp(std::round(u / tread), -2.0, 2.0); },
              [](double) { return 0.0; },
              {-1.5 * tread, -0.5 * tread, 0.5 * tread, 1.5 * tread},
              true};
    r.features = p.kinks;
    r.layers = {profile_layer(std::move(p))};
    r.storage.sobel_normals = true;
  } else if (mode == "cliff") {
    r.layers = {profile_layer({[=](double u) { return sev * std::clamp(u, 0.0, 1.0); },
                               [=](double u) { return u > 0.0 && u < 1.0 ? sev : 0.0; },
                               {0.0, 1.0}})};
    r.features = {0.5};
  } else if (mode == "cone") {
    const double radius = 0.25 * S, slope = std::tan(radians(sev));
    r.layers = {
        {all, std::make_shared<RadialSurface>(c, Profile{[=](double q) { return slope * std::max(0.0, radius - q); },
                                                         [=](double q) { return q < radius ? -slope : 0.0; },
                                                         {radius}})}};
    r.features = {-radius, 0.0, radius};
  } else if (mode == "ridge") {
    const double half = 0.16 * S;
    r.layers = {profile_layer(kink_profile(std::tan(radians(sev)), half))};
    r.features = {-half, 0.0, half};
  } else if (mode == "grating-a0.5" || mode == "grating-a4") {
    const double a = mode == "grating-a4" ? 4.0 : 0.5, k = 2.0 * kPi / sev;
    r.layers = {profile_layer(
        {[=](double u) { return a * std::sin(k * u); }, [=](double u) { return a * k * std::cos(k * u); }, {}})};
  } else if (mode == "quantised" || mode == "normal-noise") {
    r.layers = {{all, std::make_shared<RadialSurface>(c, gaussian_profile(0.08 * S, 0.15 * S))}};
    if (mode == "quantised") {
      r.storage.normal_code_max = r.storage.depth_code_max = code_max_of_bits(sev);
    } else {
      r.storage.normal_noise = sev;
    }
  } else if (mode == "fbm") {
    r.layers = {{all, std::make_shared<SpectralSurface>(c, fbm_waves(sev, angle))}};
    r.storage = {.sobel_normals = true, .sobel_from_stored = true, .normal_code_max = 255, .depth_code_max = 255};
  } else if (mode == "grazing") {
    // A quarter pipe: the slope angle grows linearly from 0 to `sev` degrees over the stroke, then stays.
    const double width = g.stroke_px, top = radians(sev);
    auto angle_at = [=](double u) { return top * std::clamp((u + width / 2.0) / width, 0.0, 1.0); };
    const double h_end = -(width / top) * std::log(std::cos(top));
    r.layers = {profile_layer({[=](double u) {
                                 if (u <= width / 2.0) return -(width / top) * std::log(std::cos(angle_at(u)));
                                 return h_end + std::tan(top) * (u - width / 2.0);
                               },
                               [=](double u) { return std::tan(angle_at(u)); },
                               {-width / 2.0, width / 2.0}})};
    r.storage.normal_code_max = r.storage.depth_code_max = 65535;
  } else if (mode == "thin") {
    // A strip `sev` px wide holding a 45-degree roof, alone in its region.
    const auto w = static_cast<std::int32_t>(sev);
    const std::int32_t x0 = g.size / 2 - w / 2;
    const Vec2 centre{x0 + sev / 2.0, S / 2.0};
    r.layers = {
        {{x0, 0, w, g.size}, std::make_shared<ProfileSurface>(centre, Vec2{1.0, 0.0}, kink_profile(1.0, sev / 2.0))}};
    r.centre = centre;
    r.features = {0.0};
    r.turns_relief = false;
  } else if (mode == "border") {
    // A region whose surface rises at `sev` degrees from its left border: a kink where the region starts.
    const double slope = std::tan(radians(sev));
    r.layers = {
        {{g.size / 2, 0, g.size - g.size / 2, g.size},
         std::make_shared<ProfileSurface>(
             c, Vec2{1.0, 0.0}, Profile{[=](double u) { return slope * u; }, [=](double) { return slope; }, {}})}};
    r.features = {0.0};
    r.turns_relief = false;
  } else if (mode == "overlap") {
    // Two regions holding the same gentle slope, the one on top raised by `sev` px.
    const double slope = 0.2;
    auto plane = [&](double offset) {
      return std::make_shared<ProfileSurface>(
          c, Vec2{1.0, 0.0}, Profile{[=](double u) { return slope * u + offset; }, [=](double) { return slope; }, {}});
    };
    r.layers = {{all, plane(0.0)}, {{g.size / 2, g.size / 4, g.size - g.size / 2, g.size / 2}, plane(sev)}};
    r.features = {0.0};
    r.turns_relief = false;
  } else {
    throw std::invalid_argument("unknown failure mode '" + mode + "'");
  }
  return r;
}

std::uint64_t seed_of(const std::string& mode, double severity, double angle_deg) {
  std::uint64_t h = 1469598103934665603ull;
  for (char ch : mode) h = (h ^ static_cast<unsigned char>(ch)) * 1099511628211ull;
  h ^= static_cast<std::uint64_t>(std::llround(severity * 1e6)) * 0x9E3779B97F4A7C15ull;
  h ^= static_cast<std::uint64_t>(std::llround(angle_deg * 1e3)) * 0xC2B2AE3D27D4EB4Full;
  return h;
}

// The maps of one layer as stored (core/lab/map_storage.hpp), from its surface sampled at texel centres.
CaseMap make_map(const Layer& layer, const Storage& storage, std::mt19937_64& rng) {
  const Rect& rect = layer.rect;
  CaseMap map{rect, NormalImage(rect.w, rect.h), DepthField(rect.w, rect.h)};
  for (std::int32_t y = 0; y < rect.h; ++y) {
    for (std::int32_t x = 0; x < rect.w; ++x) {
      const Vec2 p{rect.x + x + 0.5, rect.y + y + 0.5};
      map.depth.at(x, y) = static_cast<float>(layer.surface->height(p));
      const ExactGradient gr = layer.surface->gradient(p);
      map.normals.at(x, y) = normal_from_gradient({static_cast<float>(gr.x), static_cast<float>(gr.y)});
    }
  }
  DecodeReport depth_decoded;
  const DepthField stored_depth_field = stored_depth(map.depth, storage.depth_code_max, &depth_decoded);
  if (storage.sobel_normals) map.normals = sobel_normals(storage.sobel_from_stored ? stored_depth_field : map.depth);
  if (storage.normal_noise > 0.0) {
    std::normal_distribution<double> gauss(0.0, storage.normal_noise);
    for (Normal& n : map.normals.values) {
      const double nx = n.x + gauss(rng), ny = n.y + gauss(rng), nz = std::max<double>(n.z, 1e-3);
      const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      n = {static_cast<float>(nx / len), static_cast<float>(ny / len), static_cast<float>(nz / len)};
    }
  }
  DecodeReport decoded;
  map.normals = stored_normals(map.normals, storage.normal_code_max, &decoded);
  map.gradient_rounding = gradient_rounding_of_normals(decoded.value_step);
  map.depth = stored_depth_field;
  map.depth_rounding = height_rounding_of_depth(depth_decoded.value_step);
  return map;
}

}  // namespace

const std::vector<FailureMode>& failure_modes() {
  static const std::vector<FailureMode> modes = {
      {"jump",
       "C-1 step",
       "height (px)",
       {0.5, 1, 2, 4, 8, 16},
       {1, 8},
       true,
       "a height jump with flat normals on both sides (a normal map alone cannot see it)"},
      {"terraces",
       "C-1 step",
       "step height (px)",
       {0.5, 1, 2, 4, 8, 16},
       {1, 8},
       true,
       "four steps 0.094 x size apart, normals made from the depth map by Sobel as a generator does"},
      {"cliff",
       "C-1 step",
       "height (px)",
       {0.5, 1, 2, 4, 8, 16},
       {1, 8},
       true,
       "the height rises over a 1 px wall, exact normals"},
      {"cone",
       "C0 kink",
       "slope (deg)",
       {5, 10, 20, 30, 45, 60},
       {10, 45},
       true,
       "the linear profile: a cone of radius 0.25 x size, its rim and apex"},
      {"ridge",
       "C0 kink",
       "slope (deg)",
       {5, 10, 20, 30, 45, 60},
       {10, 45},
       true,
       "a straight roof ridge 0.32 x size wide, its apex and feet"},
      {"grating-a0.5",
       "high frequency",
       "period (px)",
       {128, 64, 32, 16, 8, 6, 4, 3, 2},
       {16, 2},
       false,
       "a sinusoidal grating of amplitude 0.5 px"},
      {"grating-a4",
       "high frequency",
       "period (px)",
       {128, 64, 32, 16, 8, 6, 4, 3, 2},
       {16, 2},
       false,
       "a sinusoidal grating of amplitude 4 px"},
      {"quantised",
       "quantisation",
       "bits per channel (32: float)",
       {32, 16, 12, 10, 8, 6},
       {32, 8},
       false,
       "a Gaussian hill 0.08 x size high, normal and depth maps of that many bits"},
      {"normal-noise",
       "noise",
       "normal noise sigma",
       {0, 0.005, 0.01, 0.02, 0.05, 0.1},
       {0, 0.05},
       false,
       "the Gaussian hill, its float normals with Gaussian noise on n_x and n_y (depth clean)"},
      {"fbm",
       "noise",
       "amplitude of the 128 px octave (px)",
       {0.25, 0.5, 1, 2, 4, 8},
       {0.5, 4},
       false,
       "a rough fBm surface (periods 128 to 4 px) as an 8-bit height image, its normal map made by Sobel (8-bit)"},
      {"grazing",
       "grazing",
       "steepest slope (deg)",
       {30, 60, 75, 85, 88, 89},
       {60, 89},
       false,
       "a quarter pipe whose slope grows to that angle along the stroke (n_z -> 0), 16-bit maps"},
      {"thin",
       "regions",
       "region width (px)",
       {16, 8, 4, 3, 2, 1},
       {8, 1},
       true,
       "a region that many px wide holding a 45-degree roof"},
      {"border",
       "regions",
       "slope (deg)",
       {5, 10, 20, 30, 45, 60},
       {10, 45},
       true,
       "a region whose surface rises from its border (a kink at the border)"},
      {"overlap",
       "regions",
       "height offset (px)",
       {0, 0.5, 1, 2, 4, 8},
       {0, 4},
       true,
       "two overlapping regions with the same slope, the upper one raised by the offset"},
  };
  return modes;
}

StabilityCase make_case(const std::string& mode, double severity, double angle_deg, const CaseGeometry& geometry) {
  const double angle = radians(angle_deg);
  Recipe recipe = recipe_for(mode, severity, angle, geometry);
  StabilityCase c;
  c.mode = mode;
  c.severity = severity;
  c.angle_deg = angle_deg;
  std::mt19937_64 rng(seed_of(mode, severity, angle_deg));
  for (const Layer& layer : recipe.layers) c.maps.push_back(make_map(layer, recipe.storage, rng));
  c.surface = std::make_shared<LayeredSurface>(std::move(recipe.layers));
  const Vec2 m{std::cos(angle), std::sin(angle)};
  c.strokes.centre = recipe.centre;
  c.strokes.direction = m;
  c.strokes.length = geometry.stroke_px;
  c.strokes.laterals = geometry.laterals;
  // A feature at u along the relief's own axis lies u / cos(turn) along a stroke that turned without it.
  const double along = recipe.turns_relief ? 1.0 : 1.0 / m.x;
  for (double u : recipe.features) {
    const double s = geometry.stroke_px / 2.0 + u * along;
    if (s > 0.0 && s < geometry.stroke_px) c.strokes.features.push_back(s);
  }
  return c;
}

RegionFields case_fields(const CaseMap& map, FieldNeeds needs) {
  RegionFields fields;
  if (needs.gradient) {
    fields.gradient = gradient_from_normals(map.normals);
    fields.gradient_rounding = map.gradient_rounding;
  }
  if (needs.reads_depth(true)) {  // every case has a depth map
    fields.depth = map.depth;
    fields.depth_rounding = map.depth_rounding;
  }
  return fields;
}

Scene case_scene(const StabilityCase& c, const MethodPtr& method, const EngineOptions& engine) {
  std::vector<Region> regions;
  for (std::size_t i = 0; i < c.maps.size(); ++i) {
    Region region;
    region.name = c.mode + "-" + std::to_string(i);
    region.rect = c.maps[i].rect;
    region.fields = case_fields(c.maps[i], method->needs());
    region.method = method;
    regions.push_back(std::move(region));
  }
  Scene scene(std::move(regions));
  scene.set_options(engine);
  return scene;
}

}  // namespace ph
