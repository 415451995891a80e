// Regions and motion for the traversal tests (test_traversal.cpp, test_traversal_variants.cpp): a region of
// constant gradient, one of heights from a formula, one of the 24 targets, and a random stream of motion.
#pragma once

#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/targets.hpp"
#include "core/engine/traversal.hpp"

namespace ph {

inline Region gradient_region(Rect rect, Gradient g, CurvatureParams params = {}) {
  Region r;
  r.name = "gradient";
  r.rect = rect;
  r.fields.gradient = GradientField(rect.w, rect.h, g);
  r.method = std::make_shared<CurvatureMethod>(params);
  return r;
}

inline Region depth_region(Rect rect, float (*height)(int x, int y), DepthParams params = {}) {
  Region r;
  r.name = "depth";
  r.rect = rect;
  r.fields.depth = DepthField(rect.w, rect.h);
  for (int y = 0; y < rect.h; ++y) {
    for (int x = 0; x < rect.w; ++x) r.fields.depth->at(x, y) = height(x, y);
  }
  r.method = std::make_shared<DepthMethod>(params);
  return r;
}

// One of the 24 targets at `offset` (whole px), with the depth method on its heights or the curvature method on
// its exact gradient, each with its default parameters.
inline Region target_region(const TargetSpec& spec, Vec2 offset, bool depth_method) {
  Region r;
  r.name = spec.name();
  r.rect = {static_cast<int>(offset.x), static_cast<int>(offset.y), spec.size, spec.size};
  if (depth_method) {
    r.fields.depth = target_depth_field(spec);
    r.method = std::make_shared<DepthMethod>(DepthParams{});
  } else {
    r.fields.gradient = target_gradient_field(spec);
    r.method = std::make_shared<CurvatureMethod>(CurvatureParams{});
  }
  return r;
}

// Two overlapping regions of values no map should hold: gradients of 1e6 across and 1e-6 down with a NaN and an
// infinite texel, heights alternating between +-1e30 with a NaN. Draws the gradients from `rng`.
inline std::vector<Region> hostile_regions(std::mt19937_64& rng) {
  Region wild = gradient_region({0, 0, 64, 64}, {0.0f, 0.0f});
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (Gradient& g : wild.fields.gradient->values) g = {u(rng) * 1e6f, u(rng) * 1e-6f};
  wild.fields.gradient->at(3, 3) = {NAN, 1.0f};
  wild.fields.gradient->at(4, 4) = {INFINITY, -INFINITY};
  Region deep = depth_region({32, 32, 64, 64}, [](int x, int y) { return (x * 7 + y * 13) % 5 == 0 ? 1e30f : -1e30f; });
  deep.fields.depth->at(1, 1) = NAN;
  std::vector<Region> regions;
  regions.push_back(std::move(wild));
  regions.push_back(std::move(deep));
  return regions;
}

// A random stream of motor displacements: mostly 1-10 px, some sub-pixel, a few huge flicks.
inline Vec2 random_motion(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double kind = u(rng);
  const double size = kind < 0.2 ? u(rng) * 0.01 : kind < 0.98 ? 1.0 + 9.0 * u(rng) : 1e4 * u(rng);
  const double phi = 2.0 * std::numbers::pi * u(rng);
  return {size * std::cos(phi), size * std::sin(phi)};
}

}  // namespace ph
