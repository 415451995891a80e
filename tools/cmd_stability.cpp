// `pseudohaptic stability OUTDIR [--small] [--mode NAME]...`: where each method fails (docs/STABILITY.md). Every
// failure mode of core/lab/failure_modes.hpp, swept over its severity, at several angles, through every method of
// the registry and the engine variants worth showing, with the metrics of core/lab/stability.hpp; CSV for
// tools/stability_charts.py.
//
// Full run: canvas 256 px, strokes 160 px at three lateral offsets, angles 0, 30 and 45 degrees, start offsets
// 0.01 px four ways, variants exact, exact+bilinear, unit_steps and direction_lut16 (all with the methods' default
// parameters). --small: canvas 64 px, strokes 40 px, one stroke per angle, angles 0 and 45, two offsets, two
// severities a mode, exact and exact+bilinear: a few seconds, for CI.
#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/engine/engine_options.hpp"
#include "core/lab/failure_modes.hpp"
#include "core/lab/stability.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/csv_cell.hpp"
#include "tools/csv_file.hpp"
#include "tools/measured.hpp"
#include "tools/output_folder.hpp"

namespace ph::tools {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct StabilityOptions {
  std::string outdir;
  bool small = false;
  std::vector<std::string> modes;  // empty: all
};

struct SuiteConfig {
  CaseGeometry geometry;
  std::vector<double> angles_deg;
  std::vector<EngineOptions> engines;
  StabilitySettings settings;
};

SuiteConfig make_suite_config(bool small) {
  SuiteConfig c;
  const EngineOptions exact{}, bilinear{Traversal::exact, Sampling::bilinear, 16};
  if (small) {
    c.geometry = {64, 40.0, {0.37}};
    c.angles_deg = {0.0, 45.0};
    c.engines = {exact, bilinear};
    c.settings.offsets = 2;
  } else {
    c.angles_deg = {0.0, 30.0, 45.0};
    c.engines = {exact,
                 bilinear,
                 {Traversal::unit_steps, Sampling::nearest, 16},
                 {Traversal::direction_lut, Sampling::nearest, 16}};
  }
  return c;
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A number for the CSV; an empty cell for NaN (a metric the mode does not have).
std::string cell(double v) { return std::isnan(v) ? std::string() : fmt::format("{:.6g}", v); }

void write_modes(const fs::path& path, const std::vector<const FailureMode*>& modes) {
  CsvFile f(path, false);  // a file of the run's OutputSet, which stages it
  f.print("mode,family,severity,has_features,description\n");
  for (const FailureMode* m : modes) {
    f.print("{},{},{},{},{}\n", m->name, csv_quoted(m->family), csv_quoted(m->severity), m->has_features ? 1 : 0,
            csv_quoted(m->description));
  }
  f.close();
}

int run_stability(const StabilityOptions& o) {
  const Clock::time_point t_start = Clock::now();
  const fs::path outdir(o.outdir);
  const SuiteConfig config = make_suite_config(o.small);
  std::vector<const FailureMode*> modes;
  for (const FailureMode& m : failure_modes()) {
    if (o.modes.empty() || std::find(o.modes.begin(), o.modes.end(), m.name) != o.modes.end()) modes.push_back(&m);
  }
  for (const std::string& name : o.modes) {
    if (std::none_of(modes.begin(), modes.end(), [&](const FailureMode* m) { return m->name == name; })) {
      std::string all;
      for (const FailureMode& m : failure_modes()) all += (all.empty() ? "" : ", ") + m.name;
      // A value of the command line that is not one of the modes: refused as the command line (exit 2 or more).
      throw CLI::ValidationError("--mode", fmt::format("unknown mode '{}' (modes: {})", name, all));
    }
  }
  prepare_output_folder(outdir, {"stability.csv", "modes.csv"});
  const std::vector<MethodPtr> methods = measured_methods();

  // Both files are replaced together at the end: a run that fails or is cut short leaves them as they were, not new
  // modes beside old rows (tools/output_folder.hpp).
  OutputSet files(outdir);
  CsvFile f(files.stage("stability.csv"), false);
  f.print(
      "mode,family,severity,method,variant,traversal,sampling,cd_err_rms,jitter_rms,jitter_truth_rms,"
      "travel_err_pct,travel_sens_pct,iso_pct,rate_px,contrast,contrast_truth,faults,strokes\n");
  std::size_t rows = 0, faults = 0;
  for (std::size_t i = 0; i < modes.size(); ++i) {
    const FailureMode& mode = *modes[i];
    const Clock::time_point t_mode = Clock::now();
    const std::vector<double>& severities = o.small ? mode.small_severities : mode.severities;
    for (double severity : severities) {
      std::vector<StabilityCase> cases;
      for (double angle : config.angles_deg) cases.push_back(make_case(mode.name, severity, angle, config.geometry));
      for (const MethodPtr& method : methods) {
        std::vector<CaseTruth> truths;
        for (const StabilityCase& c : cases) truths.push_back(case_truth(c, *method, config.settings));
        for (const EngineOptions& engine : config.engines) {
          const StabilityRow r = measure_stability(cases, truths, method, engine, config.settings);
          f.print("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", mode.name, csv_quoted(mode.family),
                  cell(severity), method->name(), label_of(engine), label_of({engine.traversal}),
                  name_of(engine.sampling), cell(r.cd_err_rms), cell(r.jitter_rms), cell(r.jitter_truth_rms),
                  cell(r.travel_err_pct), cell(r.travel_sens_pct), cell(r.iso_pct), cell(r.rate_px), cell(r.contrast),
                  cell(r.contrast_truth), r.faults, r.strokes);
          ++rows;
          faults += r.faults;
        }
      }
    }
    fmt::print(stderr, "stability: [{}/{}] {:<13} {} severities x {} angles x {} methods x {} variants in {:.1f} s\n",
               i + 1, modes.size(), mode.name, severities.size(), config.angles_deg.size(), methods.size(),
               config.engines.size(), seconds_since(t_mode));
  }
  f.close();
  write_modes(files.stage("modes.csv"), modes);
  files.commit();
  fmt::print("wrote {} rows to {} in {:.1f} s; {} faults (NaN, C/D out of bounds, strokes that never ended)\n", rows,
             (outdir / "stability.csv").string(), seconds_since(t_start), faults);
  return faults == 0 ? 0 : 1;
}

}  // namespace

Run add_stability_command(CLI::App& app) {
  auto o = std::make_shared<StabilityOptions>();
  app.description(
      "Run the failure-mode suite: steps, kinks, gratings, quantised and noisy maps, grazing slopes, thin,\n"
      "bordering and overlapping regions, each swept over its severity, through every method and the engine\n"
      "variants worth showing, against the method's own C/D on the exact input; write OUTDIR/stability.csv\n"
      "(one row per mode, severity, method and variant) and OUTDIR/modes.csv for tools/stability_charts.py.\n"
      "Exits 1 if any stroke met a NaN, a C/D out of its method's bounds or never ended.");
  app.add_option("OUTDIR", o->outdir, "Folder for the CSV files (created if needed)")
      ->required()
      ->check(non_empty_path());
  app.add_flag("--small", o->small, "Small canvas, two severities a mode, two variants (under a second; for CI)");
  app.add_option("--mode", o->modes, "Run only this failure mode (repeatable; default: all)")
      ->allow_extra_args(false);  // one name per --mode: OUTDIR after it stays OUTDIR
  return [o] { return run_stability(*o); };
}

}  // namespace ph::tools
