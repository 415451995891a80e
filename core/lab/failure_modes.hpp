// The failure modes of the stability suite (docs/STABILITY.md, "The failure modes"): surfaces on which a method
// can break, each swept over a severity, as the maps a user would give the daemon (normal and depth maps, float
// or 8/16-bit, clean, noisy or made by a normal-map generator) and as the exact surface they were made from, for
// the ground truth (core/lab/ground_truth.hpp).
//
// Every case is built at an angle: the relief and the strokes across it turn together, so the strokes meet the same
// profile at every angle and only the texel grid turns under them (the isotropy metric compares the angles). The
// modes about regions (thin strips, borders, overlaps) keep their axis-aligned rectangles and turn the strokes only.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/engine/engine_options.hpp"
#include "core/engine/field.hpp"
#include "core/engine/geometry.hpp"
#include "core/engine/method.hpp"
#include "core/engine/scene.hpp"
#include "core/lab/ground_truth.hpp"

namespace ph {

struct FailureMode {
  std::string name;      // "jump", "terraces", ...
  std::string family;    // "C-1 step", "C0 kink", "high frequency", "quantisation", "noise", "grazing", "regions"
  std::string severity;  // what the severity is, with its unit: "height (px)", "period (px)", ...
  std::vector<double> severities;        // the full run's, mildest first (bits: most first)
  std::vector<double> small_severities;  // --small
  bool has_features = false;             // a step or kink the contrast metric looks at
  std::string description;
};

// Every mode, in the order the charts show them.
const std::vector<FailureMode>& failure_modes();

// One region's maps as the loader hands them on: decoded unit normals and heights (px), both always given.
struct CaseMap {
  Rect rect;
  NormalImage normals;
  DepthField depth;
  double gradient_rounding = 0.0;  // of the normals as stored (RegionFields::gradient_rounding)
  double depth_rounding = 0.0;     // of the heights as stored (RegionFields::depth_rounding)
};

// Where a case's strokes run: `length` px along `direction`, centred on centre + lateral x (-direction.y,
// direction.x) for each lateral offset; the first lateral is the central stroke, whose features lie at `features`
// (px from its start).
struct StrokeSet {
  Vec2 centre;
  Vec2 direction;
  double length = 0.0;
  std::vector<double> laterals;
  std::vector<double> features;
};

struct StabilityCase {
  std::string mode;
  double severity = 0.0;
  double angle_deg = 0.0;
  std::vector<CaseMap> maps;                       // one per region; later ones on top
  std::shared_ptr<const AnalyticSurface> surface;  // what the maps were made from: the exact input
  StrokeSet strokes;
};

// The size of the canvas (the relief's square, px) and of the strokes; the reliefs scale with the canvas.
struct CaseGeometry {
  std::int32_t size = 256;
  double stroke_px = 160.0;
  std::vector<double> laterals{0.37, -17.3, 23.1};  // off the texel grid, so strokes meet texels at various phases
};

// Throws std::invalid_argument for an unknown mode name.
StabilityCase make_case(const std::string& mode, double severity, double angle_deg, const CaseGeometry& geometry);

// The fields a method with `needs` reads, as the loader builds them from a normal map and a depth map
// (config/field_loader.cpp): the gradient from the normals, the depth as given (also to a method that reads it only
// where it is given). What a method derives from them (Method::prepare) is derived when case_scene builds the Scene.
RegionFields case_fields(const CaseMap& map, FieldNeeds needs);

// The case's scene with one method in every region and the engine variant selected.
Scene case_scene(const StabilityCase& c, const MethodPtr& method, const EngineOptions& engine);

}  // namespace ph
