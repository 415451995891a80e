// How the engine turns a frame's motor displacement into cursor motion: the exact per-texel integral of
// docs/METHODS.md, "The traversal" (the default), or one of the cheaper schemes measured against it, and how
// the methods read the fields. docs/METHODS.md ("Traversal variants") describes each and its error bound.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ph {

enum class Traversal {
  exact,           // Amanatides-Woo walk, one C/D per texel segment (docs/METHODS.md, "The traversal")
  unit_steps,      // steps of 1 px of display along the motion, as the paper words it
  frame_midpoint,  // one C/D per frame, from the frame's midpoint
  direction_lut,   // exact texel walk, C/D from a per-texel table of quantised directions
};

enum class Sampling {
  nearest,   // a texel's stored value
  bilinear,  // the field interpolated at the position the step samples (not for direction_lut)
};

struct EngineOptions {
  Traversal traversal = Traversal::exact;
  Sampling sampling = Sampling::nearest;
  int lut_directions = 16;  // direction_lut only: 8 or 16

  // The exact walk with nearest sampling: the engine's default and its fast path.
  bool is_default() const { return traversal == Traversal::exact && sampling == Sampling::nearest; }
  bool operator==(const EngineOptions&) const = default;
};

// Empty when valid; otherwise what is wrong.
std::string validate(const EngineOptions& options);

// Names as config files and the accuracy tool spell them: "exact", "unit_steps", "frame_midpoint",
// "direction_lut"; "nearest", "bilinear". parse_* return nullopt for any other name.
std::string_view name_of(Traversal traversal);
std::string_view name_of(Sampling sampling);
std::optional<Traversal> parse_traversal(std::string_view name);
std::optional<Sampling> parse_sampling(std::string_view name);

// Every value, in declaration order (for loops over variants).
inline constexpr Traversal kAllTraversals[] = {Traversal::exact, Traversal::unit_steps, Traversal::frame_midpoint,
                                               Traversal::direction_lut};
inline constexpr Sampling kAllSamplings[] = {Sampling::nearest, Sampling::bilinear};

// Every valid combination worth measuring, default first: exact, unit_steps and frame_midpoint with each
// sampling, then direction_lut with 8 and 16 directions (8 entries).
std::vector<EngineOptions> all_engine_variants();

// A short label for charts and benchmarks: "exact", "unit_steps+bilinear", "direction_lut16".
std::string label_of(const EngineOptions& options);

}  // namespace ph
