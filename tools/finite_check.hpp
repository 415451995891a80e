// CLI11 checks that a number given on the command line is finite (and, for the second, above 0). CLI11's Range,
// PositiveNumber and NonNegativeNumber let NaN through (every comparison with it is false), and NaN or infinity
// in a C/D setting or an observer parameter gives output that means nothing without a word; a scene file
// refuses them too. The messages read as trace's own checks of its stroke options do.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>

namespace ph::tools {

// A number, finite, and above 0 where `above_zero`; `description` is what --help shows after the type.
inline CLI::Validator finite_check(bool above_zero, std::string description) {
  return CLI::Validator(
      [above_zero](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (above_zero && !(value > 0.0 && std::isfinite(value))) return "must be a finite number > 0, not " + text;
        return std::isfinite(value) ? std::string() : "must be a finite number, not " + text;
      },
      std::move(description));
}

// Finite; says nothing in --help (the option's own range, where it has one, does).
inline CLI::Validator finite_number() { return finite_check(false, ""); }

// Finite and from `lo` to `hi`, said as such ("must be a finite number from 0.01 to 100, not 0"): CLI11's Range says
// "Value 0 not in range 0.010000 to 100.000000".
inline CLI::Validator finite_from(double lo, double hi) {
  const auto g = [](double v) {
    std::ostringstream s;
    s << std::setprecision(15) << v;  // every digit of a bound like 1048576 (the default 6 would round it)
    return s.str();
  };
  return CLI::Validator(
      [lo, hi, range = g(lo) + " to " + g(hi)](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        return value >= lo && value <= hi ? std::string() : "must be a finite number from " + range + ", not " + text;
      },
      "in [" + g(lo) + " - " + g(hi) + "]");
}

// Finite and above 0 (CLI11's PositiveNumber says of 0 that it is "not in range 0.000000 to" DBL_MAX written out).
inline CLI::Validator positive_number() { return finite_check(true, "> 0"); }

}  // namespace ph::tools
