// `pseudohaptic replay`: a recorded mouse stream through exactly the pipeline the daemon runs.
#include <fmt/core.h>
#include <fmt/format.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/unique_fd.hpp"
#include "config/daemon_config.hpp"
#include "config/scene_file.hpp"
#include "config/write_all.hpp"
#include "core/engine/default_scene.hpp"
#include "core/lab/replay.hpp"
#include "recording/evemu.hpp"
#include "recording/recording_file.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/finite_check.hpp"
#include "tools/number_tuple.hpp"
#include "tools/progress_line.hpp"
#include "tools/same_path.hpp"

namespace ph::tools {

namespace {

struct ReplayOptions {
  std::string input, output, scene_file, trace;
  std::string method;  // --method: every region's, in place of the scene's
  std::vector<double> start;
  std::vector<std::int32_t> desktop;
  std::string mode = "relative";
  std::string acceleration = "flat";
  double speed = 0.0, mouse_dpi = 1000.0;
  double gain = 1.0;
  std::size_t device = 0;
  bool device_given = false;
  // --as-daemon: the pipeline's settings from the scene's [daemon] table, but for those given as flags.
  bool as_daemon = false;
  bool mode_given = false, acceleration_given = false, speed_given = false, dpi_given = false, gain_given = false;
};

[[noreturn]] void fail_errno(const std::string& what, int error) {
  throw std::runtime_error(fmt::format("{}: {}", what, std::strerror(error)));
}

// All of `text` to `fd` (config/write_all.hpp); false (errno set) on a failure.
bool write_all(int fd, const std::string& text) { return ph::write_all(fd, text.data(), text.size()); }

// One file the command writes: its text is complete in memory before anything is written, and it goes out
// in one of three ways, chosen by what the path is now:
//
// - "-": standard output.
// - A regular file, or a path that does not exist: written to a temporary file beside it, then renamed
//   over it, so that it appears complete or not at all and an old file stays as it was until the rename.
// - Anything else is opened and written as it is, because a rename would replace the node itself: a FIFO,
//   a character device (/dev/null, a terminal), a socket, and a symbolic link. A symbolic link is written
//   through, never renamed over (that would put a file in place of the link) nor resolved to rename over
//   its target: that would need a writable directory where the target lives, would replace the target's
//   inode (its owner, mode and other hard links), and /dev/stdout -> /proc/self/fd/1, when the shell
//   opened a regular file there, would replace the shell's file (losing what `>>` appends to). A link to
//   the file that is already our standard output or error is written to that descriptor, so `>>` appends.
//   When a link leads to a regular file and writing fails (disk full, I/O error: the text is already
//   complete), that file is truncated, so that nothing that looks valid is left.
class OutputFile {
 public:
  explicit OutputFile(std::string path) : path_(std::move(path)) {
    if (path_ == "-") {
      fd_ = STDOUT_FILENO;
      return;
    }
    struct stat st {};
    if (::lstat(path_.c_str(), &st) != 0) {
      if (errno != ENOENT) fail_errno(path_, errno);
      renamed_ = true;  // a new file
    } else if (S_ISREG(st.st_mode)) {
      renamed_ = true;
      replaced_mode_ = st.st_mode & 07777;
    } else if (S_ISLNK(st.st_mode)) {
      struct stat target {};
      struct stat standard {};
      if (::stat(path_.c_str(), &target) == 0) {
        for (int fd : {STDOUT_FILENO, STDERR_FILENO}) {
          if (::fstat(fd, &standard) == 0 && same_file(target, standard)) fd_ = fd;
        }
      }
    }
  }
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile() {
    if (!temp_.empty()) ::unlink(temp_.c_str());
  }

  // Written through a temporary file and a rename (else written directly by commit()).
  bool renamed() const { return renamed_; }

  // Holds the text; a renamed file is written to its temporary file now.
  void stage(std::string text) {
    text_ = std::move(text);
    if (!renamed_) return;
    const std::filesystem::path target(path_);
    const std::filesystem::path dir = target.has_parent_path() ? target.parent_path() : ".";
    UniqueFd fd;
    for (int attempt = 0; !fd; ++attempt) {
      temp_ = (dir / fmt::format(".{}.{}.{}.partial", target.filename().string(), ::getpid(), attempt)).string();
      fd = UniqueFd(::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));  // the umask applies
      if (!fd && (errno != EEXIST || attempt >= 100)) {
        const int error = errno;
        temp_.clear();
        fail_errno(fmt::format("{}: cannot create a temporary file beside it", path_), error);
      }
    }
    // A replaced file keeps its permissions.
    const bool ok = (!replaced_mode_ || ::fchmod(fd.get(), *replaced_mode_) == 0) && write_all(fd.get(), text_);
    const int error = errno;
    if (fd.close() != 0 && ok) fail_errno(fmt::format("{}: write failed", path_), errno);
    if (!ok) fail_errno(fmt::format("{}: write failed", path_), error);
  }

  // Renames the temporary file over the path, or writes the text where the path leads.
  void commit() {
    if (renamed_) {
      if (::rename(temp_.c_str(), path_.c_str()) != 0) fail_errno(fmt::format("{}: cannot replace it", path_), errno);
      temp_.clear();
      return;
    }
    if (fd_ >= 0) {  // standard output, or a link to the standard output or error
      if (fd_ == STDOUT_FILENO) std::fflush(stdout);
      if (!write_all(fd_, text_)) fail_errno(fmt::format("{}: write failed", name()), errno);
      return;
    }
    UniqueFd fd(::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOCTTY, 0666));
    if (!fd) fail_errno(fmt::format("{}: cannot open for writing", path_), errno);
    const bool ok = write_all(fd.get(), text_);
    const int error = errno;
    if (!ok) {
      struct stat st {};
      if (::fstat(fd.get(), &st) == 0 && S_ISREG(st.st_mode)) (void)!::ftruncate(fd.get(), 0);  // nothing valid
    }
    if (fd.close() != 0 && ok) fail_errno(fmt::format("{}: write failed", path_), errno);
    if (!ok) fail_errno(fmt::format("{}: write failed", path_), error);
  }

 private:
  std::string name() const { return path_ == "-" ? "<stdout>" : path_; }

  std::string path_;
  std::string text_;
  std::string temp_;  // the staged temporary file, removed unless renamed
  bool renamed_ = false;
  std::optional<mode_t> replaced_mode_;
  int fd_ = -1;  // a descriptor of ours to write to directly
};

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

// The note printed when the device replayed may not be the one meant.
void note_device(const std::string& input, const Recording& recording, const RecordingInfo& info, bool given) {
  const bool pointer = recording.device.has(ev::kRel, ev::kRelX) && recording.device.has(ev::kRel, ev::kRelY);
  if (!given && info.device_index != 0) {
    fmt::print(stderr,
               "pseudohaptic: {}: device 0 has no REL_X/REL_Y; replaying device {} of {}, \"{}\", the first that has "
               "them (--device N picks another)\n",
               input, info.device_index, info.device_count, recording.device.name);
  } else if (!pointer) {
    fmt::print(stderr,
               "pseudohaptic: {}: device {} (\"{}\") has no REL_X/REL_Y in its description (evemu's B: 02 line, "
               "libinput record's codes): nothing to rescale, every event passes through{}\n",
               input, info.device_index, recording.device.name,
               info.device_count > 1
                   ? fmt::format(" (the file has {} devices; --device N picks another)", info.device_count)
                   : "");
  }
}

struct ReplayScene {
  Scene scene;            // empty for the embedded default scene, which is laid out once the desktop is known
  DaemonSettings daemon;  // its [daemon] table, or the defaults (the embedded scene's too)
  bool embedded = false;
};

// The embedded default scene laid out for the replay's desktop, as the daemon lays it out for its own; `method`, where
// given, in every region.
Scene embedded_scene(const std::string& method, const Rect& desktop) {
  if (method.empty()) return default_scene(desktop);
  return default_scene(make_default_method(builtin_methods(), method), desktop);
}

// The scene file's scene (or, without one, a note to lay out the embedded default), with a warning per map with invalid
// texels (repaired) or stretched out of proportion, per region whose normal map and depth map hold the relief at
// different scales, and per region whose gravity wells found no pattern. `method`, where given, replaces every region's
// (with the region's own parameters for it where its file has them).
ReplayScene load_replay_scene(const std::string& scene_file, const std::string& method) {
  if (scene_file.empty()) return {Scene{}, DaemonSettings{}, true};
  SceneSpec spec = parse_scene_file(scene_file);
  if (!method.empty()) {
    for (RegionSpec& region : spec.regions) region.method = method;
  }
  SceneLoadReport report;
  std::optional<Scene> scene;
  try {
    scene.emplace(load_scene(spec, &report));
  } catch (const ConfigError& e) {
    // The file's own method may have been fine: where --method changed a region's, say whose the method was.
    const bool changed = std::any_of(spec.regions.begin(), spec.regions.end(),
                                     [](const RegionSpec& r) { return r.method != r.method_in_file; });
    if (!changed) throw;
    throw ConfigError(fmt::format("{} (the method --method {} gives every region)", e.what(), method));
  }
  for (const std::string& w : load_warnings(spec, report, *scene)) fmt::print(stderr, "pseudohaptic: warning: {}\n", w);
  return {std::move(*scene), spec.daemon, false};
}

// The pipeline's settings: the flags'; with --as-daemon, the [daemon] table's as the daemon takes them
// (daemon/configuration.cpp) wherever no flag is given. A desktop of "auto" is the default rectangle: a replay
// has no screens to ask.
PipelineConfig replay_config(const ReplayOptions& o, const DaemonSettings& daemon) {
  const OutputMode flag_mode = o.mode == "absolute" ? OutputMode::absolute : OutputMode::relative;
  PipelineConfig config;
  config.mode = flag_mode;
  if (o.as_daemon) {
    DaemonSettings settings = daemon;
    // An acceleration the table leaves out follows the output mode, so the mode a flag gives goes in first.
    if (o.mode_given) settings.output = flag_mode;
    config = pipeline_config_of(settings, settings.desktop.value_or(config.desktop));
  }
  if (!o.as_daemon || o.acceleration_given)
    config.acceleration.profile = o.acceleration == "adaptive" ? AccelProfile::adaptive : AccelProfile::flat;
  if (!o.as_daemon || o.speed_given) config.acceleration.speed = o.speed;
  if (!o.as_daemon || o.dpi_given) config.acceleration.dpi = o.mouse_dpi;
  if (!o.as_daemon || o.gain_given) config.pointer_gain = o.gain;
  if (o.desktop.size() == 4) config.desktop = {o.desktop[0], o.desktop[1], o.desktop[2], o.desktop[3]};
  if (o.start.size() == 2) config.start = Vec2{o.start[0], o.start[1]};
  return config;
}

int run_replay(const ReplayOptions& o) {
  if (o.output == "-" && o.trace == "-") throw std::invalid_argument("OUTPUT and --trace cannot both be - (stdout)");
  // The replay would be renamed over the recording it was made from, or one file over the other.
  if (same_path(o.input, o.output))
    throw std::invalid_argument(
        fmt::format("OUTPUT {} is the recording INPUT: write the replay to another file", o.output));
  if (o.input == "-" && is_standard_input(o.output))
    throw std::invalid_argument(
        fmt::format("OUTPUT {} is the file standard input reads: write the replay to another file", o.output));
  if (o.input == "-" && !o.trace.empty() && is_standard_input(o.trace))
    throw std::invalid_argument(
        fmt::format("--trace {} is the file standard input reads: write the trace to another file", o.trace));
  if (!o.trace.empty() && same_path(o.input, o.trace))
    throw std::invalid_argument(
        fmt::format("--trace {} is the recording INPUT: write the trace to another file", o.trace));
  if (!o.trace.empty() && same_output(o.output, o.trace))
    throw std::invalid_argument(fmt::format("--trace {} is OUTPUT too: give each its own file", o.trace));
  // On a terminal, what it is doing: an hour at 1000 Hz (3.6 million events) takes seconds a step.
  ProgressLine progress;
  const auto stage = [&progress](const std::string& what) {
    if (progress.in_place()) progress.show("replay: " + what);
  };
  // Erased before anything else is said, an error included.
  const std::unique_ptr<ProgressLine, void (*)(ProgressLine*)> erase_progress(
      &progress, [](ProgressLine* line) { line->finish(true); });
  // Everything is read and checked before anything is written: no partial output that looks valid.
  ReplayScene loaded = load_replay_scene(o.scene_file, o.method);
  RecordingInfo info;
  stage("reading " + (o.input == "-" ? std::string("<stdin>") : o.input));
  const Recording input = read_recording_file(o.input, o.device_given ? o.device : kFirstPointerDevice, &info);
  progress.finish(true);
  const PipelineConfig config = replay_config(o, loaded.daemon);
  if (config.start && !(std::isfinite(config.start->x) && std::isfinite(config.start->y)))
    throw std::invalid_argument("--start: X and Y must be finite numbers");
  if (loaded.embedded) loaded.scene = embedded_scene(o.method, config.desktop);
  const Scene& scene = loaded.scene;
  // What the replay's cursor cannot reach changes nothing: said, as the daemon says it of its desktop.
  for (const std::string& note : off_desktop_notes(scene, config.desktop))
    fmt::print(stderr, "pseudohaptic: warning: {}\n", note);
  note_device(o.input == "-" ? "<stdin>" : o.input, input, info, o.device_given);

  std::vector<FrameReport> reports;
  const std::size_t total = input.events.size();
  const auto replayed = [&stage, total](std::size_t done) {
    stage(fmt::format("{} % of {} events", done * 100 / std::max<std::size_t>(total, 1), total));
  };
  const Recording output = replay(input, scene, config, o.trace.empty() ? nullptr : &reports,
                                  progress.in_place() ? std::function<void(std::size_t)>(replayed) : nullptr);
  // Standard output may be the terminal the progress line is on: the line goes before anything is written there.
  const bool to_stdout = o.output == "-" || o.trace == "-";
  if (!to_stdout) stage("writing " + o.output);
  std::ostringstream text;
  write_evemu(text, output);
  if (to_stdout) progress.finish(true);

  // Both texts go to their temporary files first; then what is written directly (it can fail: a FIFO's
  // reader gone, a full disk), then the renames (which practically cannot), the output last each time. A
  // failure anywhere leaves the output uncommitted unless it was the output's own commit, and the
  // destructors remove the temporary files.
  OutputFile out(o.output);
  std::optional<OutputFile> trace;
  if (!o.trace.empty()) trace.emplace(o.trace);
  out.stage(text.str());
  if (trace) trace->stage(trace_csv(reports));
  for (const bool renamed : {false, true}) {
    if (trace && trace->renamed() == renamed) trace->commit();
    if (out.renamed() == renamed) out.commit();
  }
  progress.finish(true);
  if (o.output != "-") fmt::print(stderr, "replayed {} events into {}\n", input.events.size(), o.output);
  // A recording with nothing to rescale gives its input back: said, since it is most likely not the one meant.
  const bool moved = std::any_of(input.events.begin(), input.events.end(), [](const InputEvent& e) {
    return e.type == ev::kRel && (e.code == ev::kRelX || e.code == ev::kRelY);
  });
  // Motion is applied when its frame ends: motion without a SYN_REPORT passes unapplied, as an unfinished last
  // frame does.
  const bool framed = std::any_of(input.events.begin(), input.events.end(),
                                  [](const InputEvent& e) { return e.type == ev::kSyn && e.code == ev::kSynReport; });
  if (!moved) {
    fmt::print(stderr, "pseudohaptic: warning: {} holds {}: nothing was rescaled\n",
               o.input == "-" ? "<stdin>" : o.input, input.events.empty() ? "no events" : "no REL_X/REL_Y motion");
  } else if (!framed) {
    fmt::print(stderr,
               "pseudohaptic: warning: {} holds no SYN_REPORT, which ends a frame: no frame ended, nothing was "
               "rescaled\n",
               o.input == "-" ? "<stdin>" : o.input);
  }
  return 0;
}

}  // namespace

Run add_replay_command(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  app.description(
      "Push a recorded mouse stream (evemu or `libinput record`) through the daemon's pipeline and write\n"
      "the stream the daemon would emit, as an evemu recording. Timestamps and every non-motion event are\n"
      "kept, in order; with relative output the device description too, and only REL_X/REL_Y change (with\n"
      "--output-mode absolute the description is the daemon's absolute device's and motion is ABS_X/ABS_Y).\n"
      "Without --as-daemon the pipeline runs with the flags' defaults (relative output, no acceleration),\n"
      "not the daemon's.");
  app.add_option("INPUT", o->input, "Recording to read (evemu or libinput record YAML); - for standard input")
      ->required()
      ->check(non_empty_path());
  app.add_option("OUTPUT", o->output, "evemu recording to write; - for standard output")
      ->required()
      ->check(non_empty_path());
  app.add_option("--device", o->device,
                 "Device of a libinput record file to replay, from 0 (default: device 0, or the first with "
                 "REL_X/REL_Y when device 0 has none; an evemu file holds one)")
      ->transform(whole_number(0, 65535))
      ->each([o](const std::string&) { o->device_given = true; });
  app.add_option("--scene", o->scene_file, "Scene file (default: the embedded default scene, described below)")
      ->check(non_empty_path());
  std::vector<std::string> methods;
  const MethodRegistry registry = builtin_methods();
  for (const auto& entry : registry.entries()) methods.push_back(entry->name);
  app.add_option("--method", o->method,
                 "C/D method for every region of the scene, in place of its own (none: C/D 1, the baseline); to "
                 "replay one recording under each method")
      ->check(CLI::IsMember(methods));
  app.add_option("--trace", o->trace,
                 "CSV, one row per frame: time_us,in_dx,in_dy,out_dx,out_dy,cursor_x,cursor_y,cd_min,cd_max,dropped")
      ->check(non_empty_path());
  add_number_tuple(app, "--start", o->start, "X,Y",
                   "Start of the cursor model, screen px (default: the desktop's centre)", {finite_number()});
  app.add_flag("--as-daemon", o->as_daemon,
               "Run the pipeline as the daemon would with the scene file: output mode, acceleration, speed, "
               "mouse_dpi, pointer_speed and desktop from its [daemon] table, or the daemon's defaults (absolute "
               "output, adaptive acceleration) where it has none; each flag below given beside it wins. A desktop "
               "of \"auto\" is 0,0,1920,1080");
  app.add_option("--output-mode", o->mode, "relative: REL_X/REL_Y with fractional carry; absolute: ABS_X/ABS_Y")
      ->check(CLI::IsMember({"relative", "absolute"}))
      ->capture_default_str()
      ->each([o](const std::string&) { o->mode_given = true; });
  app.add_option("--acceleration", o->acceleration,
                 "Pointer acceleration before the C/D, as the daemon's [daemon] acceleration (flat at speed 0 is "
                 "none)")
      ->check(CLI::IsMember({"flat", "adaptive"}))
      ->capture_default_str()
      ->each([o](const std::string&) { o->acceleration_given = true; });
  app.add_option("--speed", o->speed, "Acceleration speed setting, -1 to 1 (as the desktop's slider)")
      ->check(finite_number())
      ->check(CLI::Range(-1.0, 1.0))
      ->capture_default_str()
      ->each([o](const std::string&) { o->speed_given = true; });
  app.add_option("--mouse-dpi", o->mouse_dpi, "The recorded mouse's resolution, for the adaptive profile")
      ->check(finite_number())
      ->check(CLI::Range(kMinMouseDpi, kMaxMouseDpi))
      ->capture_default_str()
      ->each([o](const std::string&) { o->dpi_given = true; });
  // As a scene file's desktop: larger ones overflowed absolute output's axis ranges. Checked with the other
  // options, before the recording and the scene are read.
  add_number_tuple<std::int32_t>(app, "--desktop", o->desktop, "X,Y,W,H",
                                 "Desktop rectangle the cursor model is kept in (default 0,0,1920,1080)", {},
                                 [](const std::vector<std::int32_t>& d) -> std::string {
                                   if (is_valid_desktop(Rect{d[0], d[1], d[2], d[3]})) return "";
                                   return fmt::format("W and H must be from 1 to {}, X and Y within ±{}",
                                                      kMaxDesktopCoordinate, kMaxDesktopCoordinate);
                                 });
  app.add_option("--gain", o->gain, "Screen px per device count at C/D 1 (the base pointer speed)")
      ->check(finite_from(kMinPointerSpeed, kMaxPointerSpeed))  // the scene file's pointer_speed's range
      ->capture_default_str()
      ->each([o](const std::string&) { o->gain_given = true; });
  app.footer(
      "The embedded default scene: three targets of the curvature paper in the middle of the desktop, as the\n"
      "daemon lays them out (on 1920x1080: bump-gaussian-h1-r200 at 135,290; hole-polynomial-h1-r200 at\n"
      "710,290; bump-linear-h1-r100 at 1285,290; 500x500 px each, curvature method; on a narrower desktop\n"
      "as many as fit).\n"
      "OUTPUT and --trace: a regular file (or a new one) is written to a temporary file beside it and renamed\n"
      "over it, so it appears complete or not at all; a FIFO, a device or a symbolic link is written through.\n"
      "Example: pseudohaptic replay --trace frames.csv mouse.evemu out.evemu");
  return [o] { return run_replay(*o); };
}

}  // namespace ph::tools
