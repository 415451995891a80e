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

// A whole number from 0 to `largest`, written in decimal; says nothing in --help. Written back without leading zeros,
// since CLI11 then reads "010" as octal.
inline CLI::Validator whole_number(std::uint64_t largest = std::numeric_limits<std::uint64_t>::max()) {
  return CLI::Validator(
      [largest](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, value, 10);
        if (text.empty() || stop != end || error != std::errc() || value > largest) {
          return "must be a whole number from 0 to " + std::to_string(largest) + ", not " +
                 (text.empty() ? "''" : text);
        }
        text = std::to_string(value);
        return {};
      },
      "");
}

}  // namespace ph::tools
