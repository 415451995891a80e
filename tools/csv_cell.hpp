// Text cells of the CSV files the tool writes (RFC 4180): in double quotes with inner quotes doubled, so that a
// comma or a line break in a name or a description stays in its cell.
#pragma once

#include <string>
#include <string_view>

namespace ph::tools {

inline std::string csv_quoted(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// The text as it is where it needs no quotes (no comma, quote or line break), else csv_quoted.
inline std::string csv_cell(std::string_view text) {
  return text.find_first_of(",\"\r\n") == std::string_view::npos ? std::string(text) : csv_quoted(text);
}

}  // namespace ph::tools
