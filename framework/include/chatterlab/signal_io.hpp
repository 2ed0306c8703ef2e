#pragma once
// Reading measured or simulated data: numeric tables (CSV, or columns separated by blanks, tabs
// or semicolons) and WAV recordings. Shared by every study kind with an `[input] file` (signal
// analysis, surface metrology, error separation, DOE, saved feed plans). Errors are InputError
// naming the file, the line and the column, so a study reading its input in validate() fails
// with exit 2 before anything is written.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace chatterlab {

struct DataTable {
  std::filesystem::path file;
  std::vector<std::string> names;             // header names; "1", "2", ... without a header
  std::vector<std::vector<double>> columns;   // columns[c][row]
  std::optional<double> sample_rate_hz;       // from a WAV header
  // Where rows start a new run of consecutive file lines (text files): {row, 1-based line}, in
  // row order. Rows between two entries follow on consecutive lines, so a table of 10^7 rows
  // costs a handful of entries instead of one line number per row (comments or blank lines
  // between rows add one entry each).
  std::vector<std::pair<std::size_t, std::size_t>> line_runs;

  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  // The 1-based file line of `row` (text files; 0 for WAV files and rows past the end).
  std::size_t source_line(std::size_t row) const;
  // The column named `column` (a header name, or a 1-based index written as digits, e.g. "2").
  // Throws InputError listing the available names when there is no such column.
  const std::vector<double>& column(const std::string& column) const;
  std::size_t column_index(const std::string& column) const;
};

// Text tables: lines empty or starting with '#' are skipped; the first other line is a header if
// any of its fields is not a number; fields are separated by ',' or ';' or blanks/tabs (detected
// from the first data line); every row must have as many fields as the first; values must be
// finite numbers ("nan"/"inf" are errors naming the line). A leading UTF-8 byte-order mark and
// CR line ends are accepted. WAV (".wav", RIFF/WAVE): PCM 8/16/24/32-bit or IEEE float 32/64,
// any number of channels; columns are channels "1".."n", values scaled to [-1, 1) for integer
// PCM, sample_rate_hz set.
DataTable read_data_table(const std::filesystem::path& file);
// The same table without copying it: the run's parsed table itself (shared by every grid point),
// for inputs of 10^7 and more rows where a copy per point would double the memory.
std::shared_ptr<const DataTable> read_shared_data_table(const std::filesystem::path& file);

// One column as a signal, e.g. [input] file + column.
std::vector<double> read_signal_column(const std::filesystem::path& file,
                                       const std::string& column);

}  // namespace chatterlab
