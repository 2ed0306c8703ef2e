// Reading a study's result files (CSV tables, whole text files, numbers in cells), shared by
// compare_study_outputs (references) and check_study_claims (the claims in study headers).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace study_files {

inline std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// One CSV record: fields separated by commas, double quotes around a field that holds commas or
// quotes ("" inside is one quote), a trailing \r dropped.
inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.push_back(cell);
      cell.clear();
    } else if (c != '\r') {
      cell += c;
    }
  }
  cells.push_back(cell);
  return cells;
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> columns;  // columns[c][row]

  // Index of a column by name, or -1.
  int column(const std::string& name) const {
    for (std::size_t c = 0; c < header.size(); ++c)
      if (header[c] == name) return static_cast<int>(c);
    return -1;
  }
  std::size_t rows() const { return columns.empty() ? 0 : columns[0].size(); }
};

// A CSV table with a header line; '#' comment lines and blank lines are skipped; short rows are
// padded with empty cells.
inline Table read_csv(const std::filesystem::path& file) {
  std::istringstream in(read_text(file));
  Table table;
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    auto cells = split_csv_line(line);
    if (first) {
      table.header = cells;
      table.columns.resize(cells.size());
      first = false;
      continue;
    }
    cells.resize(table.header.size());
    for (std::size_t c = 0; c < cells.size(); ++c) table.columns[c].push_back(cells[c]);
  }
  return table;
}

// The whole text is a number (strtod's syntax: also "nan", "inf").
inline bool parse_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

}  // namespace study_files
