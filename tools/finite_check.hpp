// A CLI11 check that a number given on the command line is finite. CLI11's Range, PositiveNumber and
// NonNegativeNumber let NaN through (every comparison with it is false), and NaN or infinity in a C/D setting
// or an observer parameter gives output that means nothing without a word; a scene file refuses them too.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace ph::tools {

inline CLI::Validator finite_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        return std::isfinite(value) ? std::string() : "must be a finite number, not " + text;
      },
      "FINITE");
}

}  // namespace ph::tools
