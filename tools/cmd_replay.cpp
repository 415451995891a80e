// `pseudohaptic replay`: a recorded mouse stream through exactly the pipeline the daemon runs.
#include <fmt/core.h>
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "config/scene_file.hpp"
#include "core/default_scene.hpp"
#include "core/replay.hpp"
#include "recording/evemu.hpp"
#include "recording/recording_file.hpp"
#include "tools/commands.hpp"

namespace ph::tools {

namespace {

struct ReplayOptions {
  std::string input, output, scene_file, trace;
  std::vector<double> start;
  std::vector<std::int32_t> desktop;
  std::string mode = "relative";
  double gain = 1.0;
};

// Writes all of `text` to `path` or stdout; a file appears complete or not at all.
void write_whole(const std::string& path, const std::string& text) {
  if (path == "-") {
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() || std::fflush(stdout) != 0) {
      throw std::runtime_error("<stdout>: write failed");
    }
    return;
  }
  const std::filesystem::path target(path);
  std::filesystem::path partial = target;
  partial += ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot open for writing", partial.string()));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!out.flush()) throw std::runtime_error(fmt::format("{}: write failed", partial.string()));
  }
  std::filesystem::rename(partial, target);
}

std::string trace_csv(const std::vector<FrameReport>& reports) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out),
                 "time_us,in_dx,in_dy,out_dx,out_dy,cursor_x,cursor_y,cd_min,cd_max,dropped\n");
  for (const FrameReport& r : reports) {
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{:.4f},{:.4f},{:.6g},{:.6g},{}\n", r.time, r.in_dx, r.in_dy,
                   r.out_dx, r.out_dy, r.cursor.x, r.cursor.y, r.cd_min, r.cd_max, r.dropped ? 1 : 0);
  }
  return fmt::to_string(out);
}

int run_replay(const ReplayOptions& o) {
  // Everything is read and checked before anything is written: no partial output that looks valid.
  const Scene scene = o.scene_file.empty() ? default_scene() : load_scene(parse_scene_file(o.scene_file));
  const Recording input = read_recording_file(o.input);
  PipelineConfig config;
  config.pointer_gain = o.gain;
  config.mode = o.mode == "absolute" ? OutputMode::absolute : OutputMode::relative;
  if (o.desktop.size() == 4) config.desktop = {o.desktop[0], o.desktop[1], o.desktop[2], o.desktop[3]};
  if (config.desktop.w <= 0 || config.desktop.h <= 0)
    throw std::invalid_argument("--desktop: width and height must be > 0");
  if (!(o.gain > 0.0) || !std::isfinite(o.gain)) throw std::invalid_argument("--gain must be a finite number > 0");
  if (o.start.size() == 2) config.start = Vec2{o.start[0], o.start[1]};

  std::vector<FrameReport> reports;
  const Recording output = replay(input, scene, config, o.trace.empty() ? nullptr : &reports);
  std::ostringstream text;
  write_evemu(text, output);
  write_whole(o.output, text.str());
  if (!o.trace.empty()) write_whole(o.trace, trace_csv(reports));
  if (o.output != "-") fmt::print(stderr, "replayed {} events into {}\n", input.events.size(), o.output);
  return 0;
}

}  // namespace

Run add_replay_command(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  app.description(
      "Push a recorded mouse stream (evemu or `libinput record`) through the daemon's pipeline and write\n"
      "the stream the daemon would emit, as an evemu recording. Timestamps, the device description and\n"
      "every non-motion event are kept, in order; only REL_X/REL_Y change.");
  app.add_option("INPUT", o->input, "Recording to read (evemu or libinput record YAML); - for standard input")
      ->required();
  app.add_option("OUTPUT", o->output, "evemu recording to write; - for standard output")->required();
  app.add_option("--scene", o->scene_file, "Scene file (default: the embedded default scene, described below)");
  app.add_option("--trace", o->trace,
                 "CSV, one row per frame: time_us,in_dx,in_dy,out_dx,out_dy,cursor_x,cursor_y,cd_min,cd_max,dropped");
  app.add_option("--start", o->start, "X,Y start of the cursor model, screen px (default: the desktop's centre)")
      ->delimiter(',')
      ->expected(2);
  app.add_option("--output-mode", o->mode, "relative: REL_X/REL_Y with fractional carry; absolute: ABS_X/ABS_Y")
      ->check(CLI::IsMember({"relative", "absolute"}))
      ->capture_default_str();
  app.add_option("--desktop", o->desktop,
                 "X,Y,W,H desktop rectangle the cursor model is kept in (default 0,0,1920,1080)")
      ->delimiter(',')
      ->expected(4);
  app.add_option("--gain", o->gain, "Screen px per device count at C/D 1 (the base pointer speed)")
      ->capture_default_str();
  app.footer(
      "The embedded default scene: three targets of the curvature paper in the middle of a 1920x1080 desktop\n"
      "(bump-gaussian-h1-r200 at 135,290; hole-polynomial-h1-r200 at 710,290; bump-linear-h1-r100 at\n"
      "1285,290; 500x500 px each, curvature method).\n"
      "Example: pseudohaptic replay --trace frames.csv mouse.evemu out.evemu");
  return [o] { return run_replay(*o); };
}

}  // namespace ph::tools
