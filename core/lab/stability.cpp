#include "core/lab/stability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/engine/traversal.hpp"
#include "core/lab/cd_profile.hpp"
#include "core/lab/stroke.hpp"

namespace ph {

namespace {

Vec2 side_of(Vec2 m) { return {-m.y, m.x}; }

Vec2 stroke_start(const StrokeSet& s, double lateral) {
  return s.centre - s.direction * (0.5 * s.length) + side_of(s.direction) * lateral;
}

// One stroke through the engine: the C/D it applied (when asked) and the motor travel it took. Counts what went
// wrong into `faults`.
struct Walked {
  std::vector<CdSegment> segments;
  double motor_px = 0.0;
};

Walked walk(const Scene& scene, const Method& method, Vec2 from, Vec2 m, double length_px, double motor_step,
            bool observe, std::size_t& faults) {
  const double lo = method.cd_lower_bound(), hi = method.cd_upper_bound();
  std::vector<StepRecord> steps;
  StrokeSpec spec{from, from + m * length_px, motor_step, 0};
  spec.max_frames = static_cast<std::size_t>(length_px * hi / motor_step) + 100;
  StrokeStepFn on_step;
  if (observe) on_step = [&](std::size_t, const StepRecord& s) { steps.push_back(s); };
  const StrokeResult r = run_stroke(scene, spec, on_step);
  for (const StepRecord& s : steps) {
    if (!std::isfinite(s.cd) || !is_finite(s.entry) || s.cd < lo * (1.0 - 1e-12) || s.cd > hi * (1.0 + 1e-12)) {
      ++faults;
    }
  }
  if (!r.reached || !is_finite(r.end.position) || !std::isfinite(r.motor_px)) ++faults;
  return {observe ? cd_segments(steps, from, m, length_px) : std::vector<CdSegment>{}, r.motor_px};
}

// The cursor after `frames` frames of motor step `step` along m from `from`.
Vec2 walk_frames(const Scene& scene, Vec2 from, Vec2 m, double step, std::size_t frames) {
  CursorState cursor = cursor_at(from);
  for (std::size_t f = 0; f < frames; ++f) advance(scene, cursor, m * step);
  return cursor.position;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

std::size_t add_log_cd_jitter(const CdAlong& cd, double length_px, double& sum2) {
  std::size_t n = 0;
  double previous = std::log(cd(0.5));
  for (double s = 1.5; s <= length_px - 0.5; s += 1.0) {
    const double here = std::log(cd(s));
    sum2 += (here - previous) * (here - previous);
    previous = here;
    ++n;
  }
  return n;
}

double feature_contrast(const CdAlong& cd, double s_feature, double length_px, double window_px, double surround_px) {
  std::vector<double> around;
  for (double off = window_px; off <= surround_px; off += 0.25) {
    for (double s : {s_feature - off, s_feature + off}) {
      if (s >= 0.0 && s <= length_px) around.push_back(std::log(cd(s)));
    }
  }
  const double ref = around.empty() ? 0.0 : median(around);
  double peak = 0.0;
  for (double off = -window_px; off <= window_px + 1e-9; off += 0.05) {
    const double s = s_feature + off;
    if (s >= 0.0 && s <= length_px) peak = std::max(peak, std::abs(std::log(cd(s)) - ref));
  }
  return std::exp(peak);
}

CaseTruth case_truth(const StabilityCase& c, const Method& method, const StabilitySettings& settings) {
  CaseTruth truth;
  const TruthModel model{c.surface.get(), &method};
  const StrokeSet& s = c.strokes;
  for (std::size_t i = 0; i < s.laterals.size(); ++i) {
    const Vec2 from = stroke_start(s, s.laterals[i]);
    const CdAlong cd = [&](double at) { return truth_cd(model, from + s.direction * at, s.direction); };
    truth.travel_px.push_back(truth_motor_travel(model, from, s.direction, s.length, settings.truth));
    truth.jitter_count += add_log_cd_jitter(cd, s.length, truth.jitter_sum2);
    if (i == 0) {
      for (double f : s.features) {
        truth.contrasts.push_back(feature_contrast(cd, f, s.length, settings.window_px, settings.surround_px));
      }
    }
  }
  return truth;
}

StabilityRow measure_stability(const std::vector<StabilityCase>& cases, const std::vector<CaseTruth>& truths,
                               const MethodPtr& method, const EngineOptions& engine,
                               const StabilitySettings& settings) {
  if (cases.empty() || truths.size() != cases.size()) throw std::invalid_argument("one truth per case is needed");
  StabilityRow row;
  CdError cd_err;
  double jitter2 = 0.0, jitter_truth2 = 0.0, travel2 = 0.0, sens2 = 0.0, contrast = 0.0, contrast_truth = 0.0;
  std::size_t jitter_n = 0, jitter_truth_n = 0, travel_n = 0, sens_n = 0, contrast_n = 0;
  std::vector<double> angle_err;  // mean travel error of each case, %
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const StabilityCase& c = cases[k];
    const CaseTruth& truth = truths[k];
    const Scene scene = case_scene(c, method, engine);
    const TruthModel model{c.surface.get(), method.get()};
    const StrokeSet& s = c.strokes;
    const Vec2 m = s.direction;
    const std::vector<Vec2> offsets = {m * settings.offset_px, side_of(m) * settings.offset_px, m * -settings.offset_px,
                                       side_of(m) * -settings.offset_px};
    double err_sum = 0.0;
    for (std::size_t i = 0; i < s.laterals.size(); ++i) {
      const Vec2 from = stroke_start(s, s.laterals[i]);
      const Walked base = walk(scene, *method, from, m, s.length, settings.motor_px_1000hz, true, row.faults);
      ++row.strokes;
      for (const CdSegment& g : base.segments) {
        const double t = truth_cd(model, from + m * (0.5 * (g.s0 + g.s1)), m);
        cd_err.add((g.cd - t) / t, g.s1 - g.s0);
      }
      const CdAlong cd = [&](double at) { return cd_at(base.segments, at); };
      jitter_n += add_log_cd_jitter(cd, s.length, jitter2);
      const double err = 100.0 * (base.motor_px - truth.travel_px[i]) / truth.travel_px[i];
      travel2 += err * err;
      ++travel_n;
      err_sum += err;
      for (int o = 0; o < std::min<int>(settings.offsets, 4); ++o) {
        const Walked moved = walk(scene, *method, from + offsets[static_cast<std::size_t>(o)], m, s.length,
                                  settings.motor_px_1000hz, false, row.faults);
        ++row.strokes;
        const double rel = 100.0 * (moved.motor_px - base.motor_px) / base.motor_px;
        sens2 += rel * rel;
        ++sens_n;
      }
      if (i != 0) continue;
      for (std::size_t f = 0; f < s.features.size(); ++f) {
        contrast += feature_contrast(cd, s.features[f], s.length, settings.window_px, settings.surround_px);
        contrast_truth += truth.contrasts[f];
        ++contrast_n;
      }
      // The same motion at 125 and 1000 Hz: whole long frames, as many short ones.
      const double long_step = settings.motor_px_1000hz * settings.rate_ratio;
      const auto long_frames = static_cast<std::size_t>(std::ceil(base.motor_px / long_step));
      const Vec2 at_low = walk_frames(scene, from, m, long_step, long_frames);
      const Vec2 at_high = walk_frames(scene, from, m, settings.motor_px_1000hz,
                                       long_frames * static_cast<std::size_t>(settings.rate_ratio));
      row.strokes += 2;
      if (!is_finite(at_low) || !is_finite(at_high)) ++row.faults;
      row.rate_px = std::max(row.rate_px, length(at_low - at_high));
    }
    jitter_truth2 += truth.jitter_sum2;
    jitter_truth_n += truth.jitter_count;
    angle_err.push_back(err_sum / static_cast<double>(s.laterals.size()));
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  row.cd_err_rms = cd_err.rms();
  row.jitter_rms = jitter_n > 0 ? std::sqrt(jitter2 / static_cast<double>(jitter_n)) : 0.0;
  row.jitter_truth_rms = jitter_truth_n > 0 ? std::sqrt(jitter_truth2 / static_cast<double>(jitter_truth_n)) : 0.0;
  row.travel_err_pct = travel_n > 0 ? std::sqrt(travel2 / static_cast<double>(travel_n)) : 0.0;
  row.travel_sens_pct = sens_n > 0 ? std::sqrt(sens2 / static_cast<double>(sens_n)) : 0.0;
  for (double e : angle_err) row.iso_pct = std::max(row.iso_pct, std::abs(e - angle_err.front()));
  row.contrast = contrast_n > 0 ? contrast / static_cast<double>(contrast_n) : nan;
  row.contrast_truth = contrast_n > 0 ? contrast_truth / static_cast<double>(contrast_n) : nan;
  return row;
}

}  // namespace ph
