// Where on a desktop of several outputs (monitors) the pointer may be. The desktop's rectangle is what absolute
// axes span (its bounding box, or X's root window); where the outputs do not cover it all (monitors of different
// sizes, side by side) the pointer cannot enter the rest, and the cursor model must not either, or what is felt
// leaves what is seen. docs/SERVICE.md, "Absolute output (the default)".
#pragma once

#include <cstddef>
#include <vector>

#include "core/engine/geometry.hpp"

namespace ph {

// At most this many outputs are told apart (a layout line holds them all); a desktop of more is taken whole.
inline constexpr std::size_t kMaxOutputs = 16;

// Whether `output` is a rectangle of at least one pixel that lies within `desktop`.
bool output_within(const Rect& output, const Rect& desktop);

// Whether `p` lies on one of `outputs` (each [x, x + w) x [y, y + h)).
bool on_an_output(const std::vector<Rect>& outputs, Vec2 p);

// Where the pointer stops that moved from `from` toward `to`, which lies on no output, as X's RandR stops it: on the
// output it came from, at that output's edge (each axis clamped into it). Coming from no output (a layout that
// changed under it, a position set from outside), at the nearest point of the nearest output, as wlroots puts it (X
// leaves such a pointer where it is until it moves onto an output). The far edges are
// excluded as a pixel's are: the point stays within the last pixel. `outputs` not empty.
Vec2 stop_on_outputs(const std::vector<Rect>& outputs, Vec2 from, Vec2 to);

// Whether the union of `outputs` is all of `area` (then the outputs say nothing the area does not).
bool outputs_cover(const std::vector<Rect>& outputs, Rect area);

// Whether the outputs form one piece, each touching (or overlapping) another by an edge or a corner, as X's RandR
// tells it (RRComputeContiguity): X stops the pointer at their edges only then, and lets it roam the whole root
// window otherwise.
bool outputs_contiguous(const std::vector<Rect>& outputs);

// The outputs the pointer is bounded by on `desktop`: `outputs` as given, or none (the desktop whole) where they cover
// it, do not touch one another (outputs_contiguous: X lets the pointer roam the root window then, and the model,
// stopped at the edge of the output it left, would never cross a gap), are more than kMaxOutputs, or one is empty or
// reaches past the desktop.
std::vector<Rect> pointer_outputs(Rect desktop, std::vector<Rect> outputs);

}  // namespace ph
