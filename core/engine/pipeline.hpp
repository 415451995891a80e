// Everything between an event source and an event sink, shared by the daemon and the replay tool:
// frames are assembled up to SYN_REPORT, their motion goes through the engine, and the frame is
// re-emitted with every other event unchanged, in order (docs/METHODS.md, "Cursor and output").
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/engine/acceleration.hpp"
#include "core/engine/desktop_outputs.hpp"
#include "core/engine/device.hpp"
#include "core/engine/event.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/traversal.hpp"

namespace ph {

// Where frames come from and go to: a live device or a recording (docs/DESIGN.md, "One source, one sink").
class EventSource {
 public:
  virtual ~EventSource() = default;
  virtual std::optional<InputEvent> next() = 0;  // nullopt at the end
};

class EventSink {
 public:
  virtual ~EventSink() = default;
  virtual void write(const Frame& frame) = 0;
};

enum class OutputMode { relative, absolute };

// Absolute output: ABS_X/ABS_Y count half pixels of the desktop, and a position is emitted as the centre
// of the pixel the cursor model is in. Desktops scale the axis range onto the desktop, the outputs' bounding box
// or X's root window (libinput: (v - min) * width / (max - min + 1)), and X rounds the result down after losing up to
// 1/65536 of it; a pixel centre lands on its pixel under both (docs/SERVICE.md, "Absolute output").
inline constexpr std::int32_t kAbsUnitsPerPixel = 2;
inline std::int32_t abs_value_of_pixel(std::int32_t pixel) { return pixel * kAbsUnitsPerPixel + 1; }

struct PipelineConfig {
  double pointer_gain = 1.0;   // screen px per device count at C/D 1 (the base pointer speed)
  AccelSettings acceleration;  // before the C/D; the default (flat, speed 0, 1000 dpi) is the identity
  OutputMode mode = OutputMode::relative;
  Rect desktop{0, 0, 1920, 1080};
  // Where on the desktop the pointer may be (core/engine/desktop_outputs.hpp): the outputs where they do not cover
  // it; empty: all of it.
  std::vector<Rect> outputs;
  std::optional<Vec2> start;  // cursor model's start; default: the desktop's centre
};

// What one frame did, for traces.
struct FrameReport {
  TimeUs time = 0;
  std::int32_t in_dx = 0, in_dy = 0;    // device counts
  std::int32_t out_dx = 0, out_dy = 0;  // relative mode: emitted counts; absolute: change of ABS_X/ABS_Y
  Vec2 cursor;                          // model position after the frame
  double cd_min = 1.0, cd_max = 1.0;
  bool dropped = false;  // a frame after SYN_DROPPED, passed through unchanged
};

// The description of the device the pipeline emits through, derived from the source's.
DeviceDescription output_device(const DeviceDescription& source, const PipelineConfig& config);

class Pipeline {
 public:
  // The pipeline shares the scene, so a reload can swap it while the old one finishes its frame.
  Pipeline(std::shared_ptr<const Scene> scene, const PipelineConfig& config);

  // A new scene (config reload); the cursor model stays where it is.
  void set_scene(std::shared_ptr<const Scene> scene) { scene_ = std::move(scene); }

  // The desktop's real cursor is elsewhere (a warp, another pointer, the session helper's first word):
  // the model moves there, clamped to the desktop, and any effect in progress starts over.
  void move_cursor_to(Vec2 position);
  // A new desktop layout (the session helper): the desktop and where on it its outputs are (pointer_outputs); the
  // model is clamped into them. Absolute output needs new virtual devices for a new desktop's ranges:
  // output_device() with config() describes them.
  void set_desktop(Rect desktop, std::vector<Rect> outputs = {});

  // Rescales one complete frame (ending in SYN_REPORT). Frames without motion come back unchanged.
  Frame process(const Frame& in, FrameReport* report = nullptr);
  // The same into `out` (its events replaced; its storage reused, so a frame kept for this allocates nothing).
  void process(const Frame& in, Frame& out, FrameReport* report = nullptr);

  // A frame that follows SYN_DROPPED: passed through as it is (less REL_X/REL_Y in absolute mode); its
  // motion is not applied to the model.
  Frame pass_dropped(const Frame& in, FrameReport* report = nullptr) const;

  const CursorState& cursor() const { return cursor_; }
  const PipelineConfig& config() const { return config_; }

 private:
  // dx, dy: the frame's summed REL_X/REL_Y counts, as process() found them.
  void emit_relative(const Frame& in, std::int64_t dx, std::int64_t dy, Vec2 display, FrameReport* report, Frame& out);
  void emit_absolute(const Frame& in, std::int64_t dx, std::int64_t dy, FrameReport* report, Frame& out);
  void desktop_changed();  // the bounds of the desktop below, for clamp_to_desktop()
  // Whether p lies in the model's range (inline: the frame's path asks it before it calls clamp_to_desktop()).
  bool on_desktop(Vec2 p) const {
    return p.x >= desktop_lo_.x && p.x <= desktop_hi_.x && p.y >= desktop_lo_.y && p.y <= desktop_hi_.y &&
           (config_.outputs.empty() || on_an_output(config_.outputs, p));
  }
  // The model stopped where the pointer stops: at the edge of the output it moved from (`from`; none: the nearest).
  void clamp_to_desktop(std::optional<Vec2> from = std::nullopt);

  std::shared_ptr<const Scene> scene_;
  PipelineConfig config_;
  CursorState cursor_;
  PointerAcceleration acceleration_;
  Vec2 desktop_lo_, desktop_hi_;        // the model's range: the desktop, less its last pixels' far edges
  Vec2 carry_;                          // fractional remainder of relative output, per axis
  std::int32_t abs_x_ = 0, abs_y_ = 0;  // last emitted absolute position
};

// Groups events into frames and hands them through the pipeline to a sink. SYN_DROPPED: the events up to
// and including the next SYN_REPORT form a dropped frame (the kernel's rule; a live source resynchronises
// through libevdev before they get here). Events after the last SYN_REPORT pass as a dropped frame's (finish()).
class FrameProcessor {
 public:
  FrameProcessor(Pipeline& pipeline, EventSink& sink) : pipeline_(pipeline), sink_(sink) {}

  // Inline up to the frame's end: the events before it only join the frame.
  void push(const InputEvent& event, FrameReport* report = nullptr, bool* frame_done = nullptr) {
    if (frame_done != nullptr) *frame_done = false;
    if (event.type == ev::kSyn) [[unlikely]] {
      push_sync(event, report, frame_done);
      return;
    }
    pending_.events.push_back(event);
  }
  void finish();

 private:
  void push_sync(const InputEvent& event, FrameReport* report, bool* frame_done);

  Pipeline& pipeline_;
  EventSink& sink_;
  Frame pending_;
  Frame out_;  // the processed frame, its storage kept from frame to frame
  bool dropping_ = false;
};

}  // namespace ph
