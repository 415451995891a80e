// Options that take a few numbers in one argument, separated by commas: "X,Y", "X,Y,Z", "X,Y,W,H". CLI11's
// delimiter(',')->expected(N) makes such an option one that takes up to N arguments, and when it stands before
// the positional arguments and another option follows them, it takes the positionals too ("--start: At Most 2
// required but received 4"). Declared here, the option takes exactly one argument wherever it stands, and the
// numbers are split from it and checked here, each error naming the option and the form it expects.
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <functional>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

namespace ph::tools {

// `text` cut at every comma; an empty part stays (and is not a number).
inline std::vector<std::string> split_at_commas(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t comma = text.find(','); comma != std::string::npos; comma = text.find(',', start)) {
    parts.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  parts.push_back(text.substr(start));
  return parts;
}

// What an option of `form` ("X,Y") takes, for its error: "expected X,Y (two numbers separated by a comma)".
inline std::string expected_form(const std::string& form, std::size_t count, bool integers) {
  constexpr std::array<const char*, 5> kWords = {"no", "one", "two", "three", "four"};
  const std::string how_many = count < kWords.size() ? kWords[count] : std::to_string(count);
  return "expected " + form + " (" + how_many + (integers ? " integers" : " numbers") + " separated by " +
         (count == 2 ? "a comma" : "commas") + ")";
}

// One number of a tuple: an integer in decimal (CLI11 would read "010" as octal and "0x10" as hex), any other number
// as CLI11 reads it.
template <typename T>
bool parse_tuple_number(const std::string& text, T& value) {
  if constexpr (std::is_integral_v<T>) {
    const char* end = text.data() + text.size();
    const auto [stop, error] = std::from_chars(text.data(), end, value, 10);
    return !text.empty() && stop == end && error == std::errc();
  } else {
    return CLI::detail::lexical_cast(text, value);
  }
}

// The numbers of `text`, one per letter of `form`, each passed by every validator of `each` (a range, finite);
// a CLI::ValidationError that names `name` otherwise, which the tool reports as it reports CLI11's own.
template <typename T>
std::vector<T> parse_number_tuple(const std::string& name, const std::string& form, const std::string& text,
                                  const std::vector<CLI::Validator>& each) {
  const std::size_t count = static_cast<std::size_t>(std::count(form.begin(), form.end(), ',')) + 1;
  const std::vector<std::string> parts = split_at_commas(text);
  std::vector<T> values(parts.size());
  bool numbers = parts.size() == count;
  for (std::size_t i = 0; numbers && i < parts.size(); ++i) numbers = parse_tuple_number(parts[i], values[i]);
  if (!numbers) throw CLI::ValidationError(name, expected_form(form, count, std::is_integral_v<T>));
  for (const std::string& part : parts) {
    for (const CLI::Validator& validator : each) {
      if (std::string error = validator(part); !error.empty()) throw CLI::ValidationError(name, error);
    }
  }
  return values;
}

// Registers option `name` on `app`, taking one argument of the numbers `form` names ("X,Y"), into `values`; `each`
// checks every number as ->check() would, and `whole` the numbers together (its message, or empty where they go).
template <typename T>
CLI::Option* add_number_tuple(CLI::App& app, const std::string& name, std::vector<T>& values, const std::string& form,
                              const std::string& description, std::vector<CLI::Validator> each = {},
                              std::function<std::string(const std::vector<T>&)> whole = {}) {
  CLI::Option* option = app.add_option_function<std::string>(
      name,
      [&values, name, form, each = std::move(each), whole = std::move(whole)](const std::string& text) {
        values = parse_number_tuple<T>(name, form, text, each);
        if (whole) {
          if (std::string problem = whole(values); !problem.empty()) throw CLI::ValidationError(name, problem);
        }
      },
      description);
  return option->type_name(form);
}

}  // namespace ph::tools
