#include "core/engine/pipeline.hpp"

#include <algorithm>
#include <cmath>

#include "core/engine/fast_math.hpp"
#include "core/engine/frame_path.hpp"

namespace ph {

namespace {

bool is_motion(const InputEvent& e) { return e.type == ev::kRel && (e.code == ev::kRelX || e.code == ev::kRelY); }

// Sum of the frame's REL_X and REL_Y (a frame normally holds at most one of each).
PH_ALWAYS_INLINE inline void sum_motion(const Frame& frame, std::int64_t& dx, std::int64_t& dy) {
  dx = dy = 0;
  for (const InputEvent& e : frame.events) {
    if (!is_motion(e)) continue;
    (e.code == ev::kRelX ? dx : dy) += e.value;
  }
}

std::int32_t saturate(double v) {
  if (!std::isfinite(v)) return 0;
  return static_cast<std::int32_t>(std::clamp(v, -2147483647.0, 2147483647.0));
}

TimeUs frame_time(const Frame& frame) { return frame.events.empty() ? 0 : frame.events.back().time; }

// Rewrites a frame's motion into `out` (its storage reused): one event per axis that moves, where the input had it
// (X before Y), none for an axis that does not move. An axis whose output equals its input keeps the input's events.
// Inline, as the frame's other steps: in the daemon each call of the frame's path is a cost of its own (docs/
// PERFORMANCE.md, "Against a bare re-emitter").
PH_ALWAYS_INLINE inline void rewrite_motion(const Frame& in, std::int64_t in_x, std::int64_t in_y, std::int32_t out_x,
                                            std::int32_t out_y, std::uint16_t type, std::uint16_t code_x,
                                            std::uint16_t code_y, Frame& out) {
  const bool keep_x = type == ev::kRel && out_x == in_x;
  const bool keep_y = type == ev::kRel && out_y == in_y;
  out.events.clear();
  if (keep_x && keep_y) {
    out.events.insert(out.events.end(), in.events.begin(), in.events.end());
    return;
  }
  bool wrote_x = false, wrote_y = false;
  auto write_x = [&](TimeUs t) {
    if (!wrote_x && (type == ev::kAbs || out_x != 0)) out.events.push_back({t, type, code_x, out_x});
    wrote_x = true;
  };
  auto write_y = [&](TimeUs t) {
    if (!wrote_y && (type == ev::kAbs || out_y != 0)) out.events.push_back({t, type, code_y, out_y});
    wrote_y = true;
  };
  for (const InputEvent& e : in.events) {
    const bool is_x = is_motion(e) && e.code == ev::kRelX, is_y = is_motion(e) && e.code == ev::kRelY;
    // A kept event is that axis' one event: the other axis' rewrite must not write it again.
    if (is_x && keep_x) {
      out.events.push_back(e);
      wrote_x = true;
      continue;
    }
    if (is_y && keep_y) {
      out.events.push_back(e);
      wrote_y = true;
      continue;
    }
    if (is_x) {
      write_x(e.time);
    } else if (is_y) {
      write_x(e.time);  // an axis the input did not move comes first, in code order
      write_y(e.time);
    } else if (e.type == ev::kSyn && e.code == ev::kSynReport) {
      if (!keep_x) write_x(e.time);
      if (!keep_y) write_y(e.time);
      out.events.push_back(e);
    } else {
      out.events.push_back(e);
    }
  }
}

}  // namespace

DeviceDescription output_device(const DeviceDescription& source, const PipelineConfig& config) {
  DeviceDescription out = source;
  out.name = "pseudohaptic " + (source.name.empty() ? std::string("pointer") : source.name);
  out.enable(ev::kSyn, ev::kSyn);
  out.enable(ev::kSyn, ev::kRel);
  out.enable(ev::kRel, ev::kRelX);
  out.enable(ev::kRel, ev::kRelY);
  if (config.mode == OutputMode::absolute) {
    // Never REL_X/REL_Y together with ABS_X/ABS_Y on one device (docs/METHODS.md, "Cursor and output").
    out.codes[ev::kRel].reset(ev::kRelX);
    out.codes[ev::kRel].reset(ev::kRelY);
    if (out.codes[ev::kRel].none()) out.codes[ev::kSyn].reset(ev::kRel);
    out.enable(ev::kSyn, ev::kAbs);
    out.enable(ev::kAbs, ev::kAbsX);
    out.enable(ev::kAbs, ev::kAbsY);
    const Rect d = config.desktop;
    constexpr std::int32_t k = kAbsUnitsPerPixel;
    out.absinfo[ev::kAbsX] = {d.x * k, (d.x + d.w) * k - 1, 0, 0, 0};
    out.absinfo[ev::kAbsY] = {d.y * k, (d.y + d.h) * k - 1, 0, 0, 0};
  }
  return out;
}

Pipeline::Pipeline(std::shared_ptr<const Scene> scene, const PipelineConfig& config)
    : scene_(scene ? std::move(scene) : std::make_shared<const Scene>()),
      config_(config),
      acceleration_(config.acceleration) {
  config_.outputs = pointer_outputs(config_.desktop, std::move(config_.outputs));
  desktop_changed();
  const Rect d = config_.desktop;
  cursor_ = cursor_at(config_.start.value_or(Vec2{d.x + d.w / 2.0, d.y + d.h / 2.0}));
  clamp_to_desktop();
  abs_x_ = static_cast<std::int32_t>(std::floor(cursor_.position.x));
  abs_y_ = static_cast<std::int32_t>(std::floor(cursor_.position.y));
}

void Pipeline::move_cursor_to(Vec2 position) {
  if (!is_finite(position)) return;
  cursor_ = cursor_at(position);
  carry_ = {};
  clamp_to_desktop();
}

void Pipeline::set_desktop(Rect desktop, std::vector<Rect> outputs) {
  if (desktop.w <= 0 || desktop.h <= 0) return;
  config_.desktop = desktop;
  config_.outputs = pointer_outputs(desktop, std::move(outputs));
  desktop_changed();
  clamp_to_desktop();
}

void Pipeline::desktop_changed() {
  const Rect d = config_.desktop;
  // The last pixel's far edge is excluded.
  desktop_lo_ = {static_cast<double>(d.x), static_cast<double>(d.y)};
  desktop_hi_ = {std::nextafter(d.x + d.w, d.x), std::nextafter(d.y + d.h, d.y)};
}

void Pipeline::clamp_to_desktop(std::optional<Vec2> from) {
  const Rect d = config_.desktop;
  if (d.w <= 0 || d.h <= 0 || on_desktop(cursor_.position)) return;
  // The real pointer stops at the desktop's edge, or at its output's; so does the model (the model and the pointer
  // agree again whenever the pointer is pushed to an edge).
  Vec2 p = cursor_.position;
  if (!config_.outputs.empty() && !on_an_output(config_.outputs, p))
    p = stop_on_outputs(config_.outputs, from.value_or(p), p);
  const double x = std::clamp(p.x, desktop_lo_.x, desktop_hi_.x);
  const double y = std::clamp(p.y, desktop_lo_.y, desktop_hi_.y);
  const EffectStates effects = cursor_.effects;  // pushing against the edge is still the same hand
  cursor_ = cursor_at({x, y});
  cursor_.effects = effects;
}

Frame Pipeline::process(const Frame& in, FrameReport* report) {
  Frame out;
  process(in, out, report);
  return out;
}

PH_FRAME_PATH void Pipeline::process(const Frame& in, Frame& out, FrameReport* report) {
  std::int64_t dx = 0, dy = 0;
  sum_motion(in, dx, dy);
  if (report != nullptr) *report = {frame_time(in), saturate(dx), saturate(dy), 0, 0, {}, 1.0, 1.0, false};
  FrameResult moved;
  if (dx != 0 || dy != 0) {
    const Vec2 counts{static_cast<double>(dx), static_cast<double>(dy)};
    const Vec2 motor = acceleration_.apply(counts, frame_time(in)) * config_.pointer_gain;
    const Vec2 from = cursor_.position;
    moved = advance(*scene_, cursor_, motor, frame_time(in));
    // The real pointer stops at the desktop's edge; so does the model. Out of line only where it must move.
    if (!on_desktop(cursor_.position)) clamp_to_desktop(from);
  }
  if (report != nullptr) {
    report->cd_min = moved.cd_min;
    report->cd_max = moved.cd_max;
    report->cursor = cursor_.position;
  }
  if (config_.mode == OutputMode::absolute) {
    emit_absolute(in, dx, dy, report, out);
  } else if (dx == 0 && dy == 0) {
    out.events.assign(in.events.begin(), in.events.end());
  } else {
    emit_relative(in, dx, dy, moved.display, report, out);
  }
}

PH_ALWAYS_INLINE inline void Pipeline::emit_relative(const Frame& in, std::int64_t dx, std::int64_t dy, Vec2 display,
                                                     FrameReport* report, Frame& out) {
  // Back to device counts; the fractional remainder carries to the next frame (evsieve does the same).
  const double gain = config_.pointer_gain;
  const Vec2 want = carry_ + Vec2{display.x / gain, display.y / gain};
  const double rx = round_half_away(want.x), ry = round_half_away(want.y);
  carry_ = {want.x - rx, want.y - ry};
  if (!is_finite(carry_)) carry_ = {};
  const std::int32_t out_x = saturate(rx), out_y = saturate(ry);
  if (report != nullptr) {
    report->out_dx = out_x;
    report->out_dy = out_y;
  }
  rewrite_motion(in, dx, dy, out_x, out_y, ev::kRel, ev::kRelX, ev::kRelY, out);
}

void Pipeline::emit_absolute(const Frame& in, std::int64_t dx, std::int64_t dy, FrameReport* report, Frame& out) {
  const std::int32_t x = static_cast<std::int32_t>(std::floor(cursor_.position.x));
  const std::int32_t y = static_cast<std::int32_t>(std::floor(cursor_.position.y));
  if (report != nullptr) {
    report->out_dx = x - abs_x_;
    report->out_dy = y - abs_y_;
  }
  if (dx == 0 && dy == 0) {
    out.events.assign(in.events.begin(), in.events.end());
    return;
  }
  rewrite_motion(in, dx, dy, abs_value_of_pixel(x), abs_value_of_pixel(y), ev::kAbs, ev::kAbsX, ev::kAbsY, out);
  abs_x_ = x;
  abs_y_ = y;
}

Frame Pipeline::pass_dropped(const Frame& in, FrameReport* report) const {
  if (report != nullptr) {
    std::int64_t dx = 0, dy = 0;
    sum_motion(in, dx, dy);
    *report = {frame_time(in),   saturate(dx), saturate(dy), saturate(dx), saturate(dy),
               cursor_.position, 1.0,          1.0,          true};
  }
  if (config_.mode == OutputMode::relative) return in;
  // The absolute device has no REL_X/REL_Y: the dropped frame keeps everything else.
  Frame out;
  for (const InputEvent& e : in.events) {
    if (!is_motion(e)) out.events.push_back(e);
  }
  if (report != nullptr) report->out_dx = report->out_dy = 0;
  return out;
}

[[gnu::hot]] void FrameProcessor::push_sync(const InputEvent& event, FrameReport* report, bool* frame_done) {
  if (event.code == ev::kSynDropped) dropping_ = true;
  pending_.events.push_back(event);
  if (event.code != ev::kSynReport) return;  // push() hands over only EV_SYN events
  if (dropping_) {
    sink_.write(pipeline_.pass_dropped(pending_, report));
  } else {
    pipeline_.process(pending_, out_, report);  // into a frame kept from frame to frame: no allocation
    sink_.write(out_);
  }
  dropping_ = false;
  pending_.events.clear();
  if (frame_done != nullptr) *frame_done = true;
}

// A frame the stream ends in, its SYN_REPORT never come, is not applied (the daemon would have waited for the
// SYN_REPORT): it passes as a dropped frame does, its motion left out where the output device has none.
void FrameProcessor::finish() {
  if (!pending_.events.empty()) sink_.write(pipeline_.pass_dropped(pending_, nullptr));
  pending_.events.clear();
  dropping_ = false;
}

}  // namespace ph
