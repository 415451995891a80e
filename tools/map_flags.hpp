// The flags that say how to decode a normal map and a depth map given on the command line (`trace`, `inspect`):
// the scene file's normal_green, normal_encoding, depth_zero and relief_px, with the same defaults.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "config/field_loader.hpp"

namespace ph::tools {

struct MapFlags {
  std::string normal_green = "opengl";
  std::string normal_encoding = "auto";
  double depth_zero = 0.0;
  double relief_px = 100.0;
  std::vector<const CLI::Option*> options;  // as registered, to tell which were given
};

// Registers --normal-green, --normal-encoding, --depth-zero and --relief-px on `app`, into `flags`.
void add_map_flags(CLI::App& app, MapFlags& flags);

// The names of the flags given on the command line, e.g. "--relief-px"; empty when none was.
std::vector<std::string> given_map_flags(const MapFlags& flags);

// Throws std::invalid_argument naming the first flag given for a map that is not: --normal-green or
// --normal-encoding without a normal map, --depth-zero or --relief-px without a depth map. They would change nothing.
void check_map_flags_have_their_map(const MapFlags& flags, bool normal_map, bool depth_map);

// `sources`' decode options as the flags say.
void apply_map_flags(const MapFlags& flags, FieldSources& sources);

}  // namespace ph::tools
