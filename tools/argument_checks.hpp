// CLI11 checks of arguments that are not numbers in a range: a path given as "" (which the file system would
// answer with "No such file or directory" or "Invalid argument []"), and a whole number that must not be negative
// (CLI11 reads "-1" into an unsigned option as its largest value, without a word). The messages read as those of
// tools/finite_check.hpp.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdint>
#include <limits>
#include <string>
#include <system_error>

namespace ph::tools {

// A path that is not empty; says nothing in --help.
inline CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "is empty: give a path" : std::string(); }, "");
}

// A whole number from `smallest` to `largest`, written in decimal; --help shows the range where it is not every
// unsigned 64-bit number. Written back without leading zeros, since CLI11 then reads "010" as octal: register it with
// ->transform(), since ->check() throws the rewrite away.
inline CLI::Validator whole_number(std::uint64_t smallest = 0,
                                   std::uint64_t largest = std::numeric_limits<std::uint64_t>::max()) {
  const std::string range = std::to_string(smallest) + " to " + std::to_string(largest);
  const bool every = smallest == 0 && largest == std::numeric_limits<std::uint64_t>::max();
  return CLI::Validator(
      [smallest, largest, range](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, value, 10);
        if (text.empty() || stop != end || error != std::errc() || value < smallest || value > largest)
          return "must be a whole number from " + range + ", not " + (text.empty() ? "''" : text);
        text = std::to_string(value);
        return {};
      },
      every ? "" : "in [" + std::to_string(smallest) + " - " + std::to_string(largest) + "]");
}

}  // namespace ph::tools
