// Checks of a daemon with absolute output and its adaptive acceleration against the offline model
// (ph::Pipeline), frame by frame: the end-to-end checks (daemon_e2e.cpp) and the demo
// (demo/daemon_demo.cpp) share them. Inside the VM.
#pragma once

#include <fmt/format.h>
#include <linux/input.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "control/client.hpp"
#include "control/protocol.hpp"
#include "core/engine/pipeline.hpp"
#include "tests/vm/e2e_support.hpp"

namespace ph::e2e {

constexpr auto kFrameTimeout = 5s;  // a frame through the daemon (TCG is 10-50x slower than native)

// The failures and notes of one case.
class Check {
 public:
  // Records `what` (expected ..., got ...) when !ok; the first few are printed, the rest counted.
  bool expect(bool ok, const std::string& what) {
    if (!ok) {
      if (failures_.size() < kShown) failures_.push_back(what);
      ++failed_;
    }
    return ok;
  }
  void note(const std::string& text) { notes_ += (notes_.empty() ? "" : "; ") + text; }

  bool ok() const { return failed_ == 0; }
  std::size_t failed() const { return failed_; }
  std::string failures() const {
    std::string text;
    for (const std::string& f : failures_) text += (text.empty() ? "" : "\n    ") + f;
    if (failed_ > failures_.size()) text += fmt::format("\n    ... and {} more", failed_ - failures_.size());
    return text;
  }
  const std::string& notes() const { return notes_; }

 private:
  static constexpr std::size_t kShown = 4;
  std::vector<std::string> failures_;
  std::size_t failed_ = 0;
  std::string notes_;
};

// The daemon's cursor model, as `cursor` on the control socket reports it.
inline ph::Vec2 daemon_cursor(ph::control::Client& control) {
  const ph::control::Reply reply = control.request("cursor", 10s);
  const std::optional<ph::Vec2> at = reply.ok ? ph::control::parse_cursor(reply.text) : std::nullopt;
  if (!at) throw Fatal("'cursor' on the control socket answered: " + reply.text);
  return *at;
}

inline std::int32_t pixel_of(double coordinate) { return static_cast<std::int32_t>(std::floor(coordinate)); }

// Checks a daemon with absolute output and its default adaptive acceleration against the offline model.
// The acceleration depends on the time between frames, which the kernel stamps (CLOCK_MONOTONIC, when
// the frame's SYN_REPORT is written into the test mouse); the test reads the clock just before and just
// after each send, and the model is fed the time before. What is checked, and why so:
// - every event other than ABS_X/ABS_Y exactly, in its frame and order;
// - the emitted position is a pixel centre (ABS value 2p + 1) within 1 px, per axis, of the pixels the
//   model gives for the candidate times: this frame at either clock reading (the kernel's stamp lies
//   between them; a guest descheduled there widens the range by what it changes), and the shortest time
//   between frames, the frame before stamped after its send and this one before its own. 1 px: the stamp is known to
//   tens of microseconds at best, and a position near a pixel edge moves across it with errors far below a pixel;
// - when the emitted pixel differs from the model's, the model is moved to the daemon's own model
//   (`cursor` on the control socket), so that timing errors never accumulate;
// - the kernel drops an ABS value equal to the axis' current one, so a frame may come out with one axis,
//   or not at all: when the model's pixel is within 2 px of the current one on both axes and the frame
//   has nothing else, or when the guest stalled over 2 ms between the guess and the send's end (the
//   frame may then be slow enough to move no pixel), the daemon's model is asked whether anything is to
//   come before reading.
class AbsoluteFollower {
 public:
  AbsoluteFollower(ph::Pipeline& model, ph::control::Client& control) : model_(model), control_(control) {}

  // Sends `in` through `mouse` and checks what comes out of `out` (a virtual device of this daemon).
  // Returns what came out, nullopt when nothing did. `shadow`, when given, is fed the same frame.
  // `report`, when given, gets the model's report of the frame.
  std::optional<Frame> through(Check& check, TestMouse& mouse, EventReader& out, const Frame& in,
                               const std::string& label, ph::Pipeline* shadow = nullptr,
                               ph::FrameReport* report = nullptr) {
    timed_ = false;
    if (!has_motion(in)) return through_unchanged(check, mouse, out, in, label, shadow, report);
    const Axes before = current_axes(out);
    // Whether something is sure to come out, from the model fed the time now (the send is next).
    ph::Pipeline guess = model_;
    const ph::TimeUs t_guess = monotonic_us();
    guess.process(stamped(in, t_guess));
    const bool others = delivers_something(without_motion(in));
    bool certain = others || std::abs(guess_value_x(guess) - before.x) >= 3 * ph::kAbsUnitsPerPixel ||
                   std::abs(guess_value_y(guess) - before.y) >= 3 * ph::kAbsUnitsPerPixel;
    const ph::TimeUs t_before = monotonic_us();
    sent_at_ = Clock::now();
    mouse.send(in);
    const ph::TimeUs t_after = monotonic_us();
    // A guest stalled between the guess and the send's end (a busy host) makes the guess's time wrong:
    // the frame may be slow enough not to move a pixel. Then the daemon's model decides.
    constexpr ph::TimeUs kStallUs = 2000;
    if (!others && t_after - t_guess > kStallUs) {
      certain = false;
      ++stalled_;
    }
    std::optional<Frame> got;
    if (certain) {
      got = out.next_frame(kFrameTimeout);
      read_at_ = Clock::now();
      timed_ = got.has_value();
    }
    ph::Pipeline late = model_;
    // The shortest time between frames the kernel may have stamped: the frame before stamped at the end
    // of its send, this one at the start of its own. The model's state had the frame before fed the time
    // before its send; this candidate has it fed the time after, from the same position.
    std::optional<ph::Pipeline> shortest;
    if (previous_) {
      shortest = previous_->state;
      shortest->process(stamped(previous_->frame, previous_->after));
      shortest->move_cursor_to(model_.cursor().position);
      shortest->process(stamped(in, t_before));
    }
    previous_ = Previous{model_, in, t_after};
    const Frame expected = untimed(model_.process(stamped(in, t_before), report));
    late.process(stamped(in, t_after));
    if (shadow != nullptr) shadow->process(stamped(in, t_before));
    std::optional<ph::Vec2> daemon_at;
    if (!certain) {
      ++asked_;
      daemon_at = daemon_cursor(control_);
      const bool moves = ph::abs_value_of_pixel(pixel_of(daemon_at->x)) != before.x ||
                         ph::abs_value_of_pixel(pixel_of(daemon_at->y)) != before.y;
      if (moves) got = out.next_frame(kFrameTimeout);
      if (!moves && others) check.expect(false, label + ": internal: expected the frame's other events");
    }
    ++frames_;
    if (certain && !got) {
      check.expect(
          false, fmt::format("{}: sent [{}], expected [{}] within 1 px, got nothing within {} s{}", label, describe(in),
                             describe(expected), kFrameTimeout.count(), out.gone() ? " (device gone)" : ""));
      return std::nullopt;
    }
    Axes emitted = before;
    if (got) {
      check.expect(same_events(without_motion(*got), without_motion(expected)),
                   fmt::format("{}: sent [{}], expected [{}] (offline model), got [{}]: events other than the "
                               "position differ",
                               label, describe(in), describe(expected), describe(*got)));
      for (auto [code, axis] : {std::pair{ev::kAbsX, &emitted.x}, std::pair{ev::kAbsY, &emitted.y}}) {
        const std::optional<std::int32_t> v = value_in(*got, ev::kAbs, code);
        if (!v) continue;
        check.expect(*v % ph::kAbsUnitsPerPixel == 1, fmt::format("{}: {} {} is not a pixel centre (2p + 1)", label,
                                                                  event_name({0, ev::kAbs, code, 0}), *v));
        *axis = *v;
      }
    }
    const ph::Texel early_px = ph::texel_at(model_.cursor().position), late_px = ph::texel_at(late.cursor().position);
    const ph::Texel short_px = shortest ? ph::texel_at(shortest->cursor().position) : early_px;
    const ph::Texel at{(emitted.x - 1) / ph::kAbsUnitsPerPixel, (emitted.y - 1) / ph::kAbsUnitsPerPixel};
    const bool within = at.x >= std::min({early_px.x, late_px.x, short_px.x}) - 1 &&
                        at.x <= std::max({early_px.x, late_px.x, short_px.x}) + 1 &&
                        at.y >= std::min({early_px.y, late_px.y, short_px.y}) - 1 &&
                        at.y <= std::max({early_px.y, late_px.y, short_px.y}) + 1;
    check.expect(within, fmt::format("{}: sent [{}], the cursor came out at pixel ({}, {}) [{}], the offline model "
                                     "puts it at ({}, {}) (or ({}, {}) with the time after the send, ({}, {}) with "
                                     "the frame before stamped after its send): more than 1 px apart",
                                     label, describe(in), at.x, at.y, got ? describe(*got) : "nothing", early_px.x,
                                     early_px.y, late_px.x, late_px.y, short_px.x, short_px.y));
    if (early_px != late_px || early_px != short_px) ++widened_;
    if (at != early_px) {
      ++off_pixel_;
      max_off_px_ = std::max({max_off_px_, std::abs(at.x - early_px.x), std::abs(at.y - early_px.y)});
      if (!daemon_at) daemon_at = daemon_cursor(control_);
      max_gap_ = std::max(max_gap_, ph::length(*daemon_at - model_.cursor().position));
      model_.move_cursor_to(*daemon_at);
    }
    return got;
  }

  // The last frame's times, when it was one whose output was waited for at once (for latency).
  bool timed() const { return timed_; }
  double last_us() const { return std::chrono::duration<double, std::micro>(read_at_ - sent_at_).count(); }

  std::string summary() const {
    return fmt::format(
        "{} motion frames: {} came out at another pixel than the model's (by {} px at most; the model then moved "
        "to the daemon's, {:.3f} px away at most), {} where the candidate times gave different pixels, {} where "
        "the daemon's model was asked whether a position was to come ({} of them after the guest stalled over 2 ms "
        "around the send)",
        frames_, off_pixel_, max_off_px_, max_gap_, widened_, asked_, stalled_);
  }

 private:
  struct Axes {
    std::int32_t x = 0, y = 0;
  };

  static std::int32_t guess_value_x(const ph::Pipeline& p) {
    return ph::abs_value_of_pixel(pixel_of(p.cursor().position.x));
  }
  static std::int32_t guess_value_y(const ph::Pipeline& p) {
    return ph::abs_value_of_pixel(pixel_of(p.cursor().position.y));
  }

  // The kernel's current ABS_X/ABS_Y of the virtual device: every earlier frame has been read by now.
  static Axes current_axes(const EventReader& out) {
    input_absinfo x{}, y{};
    if (::ioctl(out.fd(), EVIOCGABS(ABS_X), &x) < 0 || ::ioctl(out.fd(), EVIOCGABS(ABS_Y), &y) < 0) {
      throw Fatal("EVIOCGABS on " + out.node() + ": " + errno_text(errno));
    }
    return {x.value, y.value};
  }

  // A frame without motion comes out unchanged (the model agrees, and keeps its time).
  std::optional<Frame> through_unchanged(Check& check, TestMouse& mouse, EventReader& out, const Frame& in,
                                         const std::string& label, ph::Pipeline* shadow, ph::FrameReport* report) {
    const ph::TimeUs t = monotonic_us();
    sent_at_ = Clock::now();
    mouse.send(in);
    const Frame expected = untimed(model_.process(stamped(in, t), report));
    if (shadow != nullptr) shadow->process(stamped(in, t));
    check.expect(same_events(expected, in), label + ": the offline model changed a frame without motion");
    if (!delivers_something(expected)) return std::nullopt;
    std::optional<Frame> got = out.next_frame(kFrameTimeout);
    read_at_ = Clock::now();
    timed_ = got.has_value();
    check.expect(got && same_events(*got, expected),
                 fmt::format("{}: sent [{}], expected it unchanged, got [{}]", label, describe(in),
                             got ? describe(*got) : "nothing"));
    return got;
  }

  // The motion frame before, with the model's state before it and the clock after its send.
  struct Previous {
    ph::Pipeline state;
    Frame frame;
    ph::TimeUs after = 0;
  };

  ph::Pipeline& model_;
  ph::control::Client& control_;
  std::optional<Previous> previous_;
  Clock::time_point sent_at_, read_at_;
  bool timed_ = false;
  int frames_ = 0, off_pixel_ = 0, max_off_px_ = 0, widened_ = 0, asked_ = 0, stalled_ = 0;
  double max_gap_ = 0.0;
};

}  // namespace ph::e2e
