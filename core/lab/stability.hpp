// The metrics of the stability suite (docs/STABILITY.md, "Metrics"): how one method, through one engine variant,
// behaves on one failure mode at one severity (core/lab/failure_modes.hpp), against the same method given the exact
// input (the ground truth of core/lab/ground_truth.hpp), over strokes through the real engine
// (core/lab/stroke.hpp, core/engine/traversal.hpp).
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "core/engine/engine_options.hpp"
#include "core/engine/method.hpp"
#include "core/lab/failure_modes.hpp"
#include "core/lab/ground_truth.hpp"

namespace ph {

struct StabilitySettings {
  double motor_px_1000hz = 2.0;  // motor travel per frame at 1000 Hz: a hand at 2000 px/s
  double rate_ratio = 8.0;       // 125 Hz: frames 8 times as long
  double offset_px = 0.01;       // start offsets for the sensitivity
  int offsets = 4;               // along, against, and across the stroke both ways (2: along and across)
  double window_px = 3.0;        // contrast: the peak within +-window of a feature ...
  double surround_px = 20.0;     // ... against the median C/D from window to surround px away
  TruthTolerance truth{1e-7, 1e-7};
};

// One method and engine variant on one failure mode at one severity, over the case's angles.
struct StabilityRow {
  double cd_err_rms = 0.0;        // relative C/D error against the exact input's, length-weighted RMS
  double jitter_rms = 0.0;        // RMS of the change of ln C/D from one px of the stroke to the next
  double jitter_truth_rms = 0.0;  // the same of the exact input's C/D (the relief's own variation)
  double travel_err_pct = 0.0;    // RMS of the motor travel's error against the exact input's, %
  double travel_sens_pct = 0.0;   // RMS change of a stroke's motor travel when it starts 0.01 px away, %
  double iso_pct = 0.0;           // largest difference of the travel error between an angle and 0 degrees, %
  double rate_px = 0.0;           // largest distance between the cursors after the same motion at 125 and 1000 Hz
  double contrast = 0.0;          // mean of the features' contrasts (NaN for a mode without features)
  double contrast_truth = 0.0;    // the same of the exact input's C/D
  std::size_t faults = 0;         // non-finite values, C/D out of the method's bounds, strokes that never ended
  std::size_t strokes = 0;        // strokes walked
};

// What the exact input gives on one case's strokes, for one method: the same for every engine variant.
struct CaseTruth {
  std::vector<double> travel_px;  // motor travel of each lateral stroke
  double jitter_sum2 = 0.0;       // add_log_cd_jitter over the strokes
  std::size_t jitter_count = 0;
  std::vector<double> contrasts;  // of each feature of the central stroke
};
CaseTruth case_truth(const StabilityCase& c, const Method& method, const StabilitySettings& settings = {});

// Measures `method` through `engine` on the cases (the same mode and severity at several angles; the first angle is
// the reference of the isotropy metric), each with its case_truth.
StabilityRow measure_stability(const std::vector<StabilityCase>& cases, const std::vector<CaseTruth>& truths,
                               const MethodPtr& method, const EngineOptions& engine,
                               const StabilitySettings& settings = {});

// The pieces, for tests. C/D along a stroke as a function of s, px from the stroke's start.
using CdAlong = std::function<double(double s)>;

// Adds to `sum2` the squares of ln cd(s + 1) - ln cd(s) for s = 0.5, 1.5, ... up to length - 0.5; returns how
// many were added.
std::size_t add_log_cd_jitter(const CdAlong& cd, double length_px, double& sum2);

// How far C/D peaks near a feature: exp of the largest |ln cd - ln ref| within +-window px of s_feature (sampled
// every 0.05 px), ref the median C/D from window to surround px away on both sides (every 0.25 px) within
// [0, length]. 1: nothing to find there.
double feature_contrast(const CdAlong& cd, double s_feature, double length_px, double window_px, double surround_px);

}  // namespace ph
