// A stroke that cannot finish within the frames a stroke may take (core/lab/stroke.hpp) stops part way, and what it
// measured would be said of the whole stroke: refused before it runs, naming the option that makes it shorter.
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <string_view>

#include "core/lab/stroke.hpp"

namespace ph::tools {

// Throws std::invalid_argument when even at C/D 1 `stroke` would take more than its max_frames; `larger` says what
// to give instead (e.g. "--step").
inline void check_stroke_fits(const StrokeSpec& stroke, std::string_view larger) {
  const double frames_at_cd_1 =
      std::hypot(stroke.to.x - stroke.from.x, stroke.to.y - stroke.from.y) / stroke.motor_step_px;
  if (frames_at_cd_1 > static_cast<double>(stroke.max_frames)) {
    throw std::invalid_argument(
        fmt::format("the stroke would take {:.3g} frames of {:g} px at C/D 1, more than the {} a stroke may take: "
                    "give a larger {}",
                    frames_at_cd_1, stroke.motor_step_px, stroke.max_frames, larger));
  }
}

}  // namespace ph::tools
