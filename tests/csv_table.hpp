// The CSV files the tool writes, read back for the tests: comma-separated cells, a quoted cell holding commas or
// doubled quotes, an empty last cell kept (a trace row with no region ends in a comma).
#pragma once

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/file_bytes.hpp"

namespace ph {

struct CsvTable {
  std::string header;                          // the first line, as written
  std::vector<std::vector<std::string>> rows;  // the cells of each later line
};

inline std::vector<std::string> csv_cells(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"') {
      if (quoted && i + 1 < line.size() && line[i + 1] == '"') {
        cells.back() += '"';
        ++i;
      } else {
        quoted = !quoted;
      }
    } else if (c == ',' && !quoted) {
      cells.emplace_back();
    } else {
      cells.back() += c;
    }
  }
  return cells;
}

inline CsvTable parse_csv(const std::string& text) {
  CsvTable table;
  std::istringstream in(text);
  std::getline(in, table.header);
  for (std::string line; std::getline(in, line);) table.rows.push_back(csv_cells(line));
  return table;
}

inline CsvTable read_csv(const std::filesystem::path& path) { return parse_csv(read_file_text(path)); }

// Each row as a map from the header's names to its cells; cells beyond the header's are left out.
inline std::vector<std::map<std::string, std::string>> named_rows(const CsvTable& table) {
  const std::vector<std::string> names = csv_cells(table.header);
  std::vector<std::map<std::string, std::string>> rows;
  for (const std::vector<std::string>& cells : table.rows) {
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < names.size() && i < cells.size(); ++i) row[names[i]] = cells[i];
    rows.push_back(std::move(row));
  }
  return rows;
}

// A cell that is a whole finite number.
inline bool finite_number(const std::string& s) {
  std::size_t used = 0;
  try {
    const double v = std::stod(s, &used);
    return used == s.size() && std::isfinite(v);
  } catch (...) {
    return false;
  }
}

}  // namespace ph
