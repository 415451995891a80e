// `pseudohaptic demo`: the paper's Fig. 5 in numbers. Generates the 24 target files if they are missing,
// loads each through the scene loader (as the daemon will) and strokes horizontally through its centre
// with each method.
#include <fmt/core.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/stroke.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/finite_check.hpp"
#include "tools/progress_line.hpp"
#include "tools/stroke_fits.hpp"

namespace ph::tools {

namespace {

// As the XDG base directory specification says: a relative XDG_CACHE_HOME is ignored.
std::filesystem::path default_targets_dir() {
  if (const char* cache = std::getenv("XDG_CACHE_HOME"); cache != nullptr && *cache == '/') {
    return std::filesystem::path(cache) / "pseudohaptic" / "targets";
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    return std::filesystem::path(home) / ".cache" / "pseudohaptic" / "targets";
  }
  return "pseudohaptic-targets";
}

struct Range {
  double lo = 1.0, hi = 1.0;
};

Range stroke_range(const SceneSpec& target_scene, std::string_view method, double step) {
  SceneSpec spec = target_scene;
  spec.regions.front().method = std::string(method);
  const Scene scene = load_scene(spec);
  const Rect r = scene.regions().front().rect;
  StrokeSpec stroke;
  stroke.from = {static_cast<double>(r.x), r.y + r.h / 2.0};
  stroke.to = {static_cast<double>(r.x + r.w), r.y + r.h / 2.0};
  stroke.motor_step_px = step;
  check_stroke_fits(stroke, "--step");
  const StrokeResult result = run_stroke(scene, stroke);
  // Where the C/D stays high the stroke takes up to that many times as many frames: a range of part of the stroke
  // would be said of all of it.
  if (!result.reached) {
    throw std::runtime_error(
        fmt::format("{}: the {} stroke stopped after {} frames, before its end: give a larger "
                    "--step",
                    scene.regions().front().name, method, result.frames));
  }
  return {result.cd_min, result.cd_max};
}

// The scene of target `t` in `folder`, loaded once to see that its files read: a damaged one (a run killed while the
// targets were written, a file edited by hand) is written again, once, and said.
SceneSpec readable_target_scene(const std::filesystem::path& folder, const TargetSpec& t) {
  const std::filesystem::path scene_file = target_file_paths(folder, t).scene;
  try {
    SceneSpec spec = parse_scene_file(scene_file);
    // Loaded as each method the demo runs reads it: the scene's own (curvature) does not read the depth map.
    for (std::string_view method : {CurvatureMethod::kName, DepthMethod::kName}) {
      SceneSpec as = spec;
      for (RegionSpec& r : as.regions) r.method = std::string(method);
      (void)load_scene(as);
    }
    return spec;
  } catch (const std::exception& e) {
    fmt::print(stderr, "pseudohaptic: warning: {}; writing the target {} again\n", e.what(), t.name());
    write_target_files(folder, {t});
    return parse_scene_file(scene_file);
  }
}

}  // namespace

Run add_demo_command(CLI::App& app) {
  auto dir = std::make_shared<std::string>();
  auto step = std::make_shared<double>(2.0);
  app.add_option("--targets", *dir,
                 "Folder of the target files (default: $XDG_CACHE_HOME/pseudohaptic/targets, else "
                 "~/.cache/pseudohaptic/targets); written if missing or unreadable")
      ->check(non_empty_path());
  app.add_option("--step", *step, "Motor travel per frame, px")->check(positive_number())->capture_default_str();
  return [dir, step] {
    const std::filesystem::path folder = dir->empty() ? default_targets_dir() : std::filesystem::path(*dir);
    const auto targets = all_targets();
    if (!target_files_present(folder, targets)) {
      fmt::print(stderr, "writing the 24 targets to {}\n", folder.string());
      ProgressLine writing;
      write_target_files(folder, targets, [&writing](std::size_t done, std::size_t total, const TargetSpec& t) {
        writing.show(fmt::format("[{:2}/{}] {}", done, total, t.name()));
      });
      writing.finish();
    }
    // The table's head goes out with its first row: a --step that no stroke can take leaves no empty table.
    const auto print_head = [] {
      fmt::print("C/D ratio met on a horizontal stroke through the centre of each target\n");
      fmt::print("(below 1: the cursor speeds up, downhill; above 1: it slows down, uphill)\n\n");
      fmt::print("{:<28} {:>19} {:>19}\n", "target", "curvature", "depth");
    };
    std::size_t done = 0;
    ProgressLine measuring;  // on a terminal only: elsewhere the table's rows say as much
    for (const TargetSpec& t : targets) {
      ++done;
      if (measuring.in_place()) measuring.show(fmt::format("[{:2}/{}] {}", done, targets.size(), t.name()));
      const SceneSpec spec = readable_target_scene(folder, t);
      const Range c = stroke_range(spec, CurvatureMethod::kName, *step);
      const Range d = stroke_range(spec, DepthMethod::kName, *step);
      measuring.finish(true);
      if (done == 1) print_head();
      fmt::print("{:<28} {:>8.3f} .. {:>6.3f} {:>8.3f} .. {:>6.3f}\n", t.name(), c.lo, c.hi, d.lo, d.hi);
      std::fflush(stdout);
    }
    fmt::print("\nTrace one of them: pseudohaptic trace --scene {} -o trace.csv\n",
               target_file_paths(folder, targets.front()).scene.string());
    return 0;
  };
}

}  // namespace ph::tools
