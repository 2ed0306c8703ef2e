// Time-series files (chatterlab/time_series_file.hpp).
#include "chatterlab/time_series_file.hpp"

#include <fmt/format.h>

#include <bit>
#include <cstring>
#include <stdexcept>

#include "chatterlab/output_files.hpp"

namespace chatterlab {

namespace {

void check_shape(const std::vector<std::string>& header, const std::vector<std::span<const double>>& columns,
                 std::size_t decimation) {
  if (decimation == 0) throw std::invalid_argument("time series: decimation must be >= 1");
  if (header.size() != columns.size())
    throw std::invalid_argument(fmt::format("time series: {} names for {} columns", header.size(), columns.size()));
  for (std::size_t c = 1; c < columns.size(); ++c)
    if (columns[c].size() != columns[0].size())
      throw std::invalid_argument(fmt::format("time series: column '{}' has {} rows, '{}' {}", header[c],
                                              columns[c].size(), header[0], columns[0].size()));
}

std::size_t kept_rows(const std::vector<std::span<const double>>& columns, std::size_t decimation) {
  const std::size_t rows = columns.empty() ? 0 : columns[0].size();
  return (rows + decimation - 1) / decimation;
}

}  // namespace

const char* to_string(TimeSeriesFormat format) { return format == TimeSeriesFormat::csv ? "csv" : "npy"; }

TimeSeriesFormat parse_time_series_format(const std::string& name) {
  if (name == "csv") return TimeSeriesFormat::csv;
  if (name == "npy") return TimeSeriesFormat::npy;
  throw std::invalid_argument("unknown time-series format '" + name + "' (valid: csv, npy)");
}

std::string npy_bytes(const std::vector<std::string>& header, const std::vector<std::span<const double>>& columns,
                      std::size_t decimation) {
  static_assert(std::endian::native == std::endian::little, "the .npy writer stores native little-endian doubles");
  check_shape(header, columns, decimation);
  const std::size_t rows = kept_rows(columns, decimation);
  // Header: a Python dict literal, padded with spaces and ended by '\n' so that the data start
  // at a multiple of 64 bytes (NumPy format 1.0: magic, version, little-endian uint16 length).
  std::string descr = "[";
  for (const std::string& name : header) {
    if (name.find_first_of("'\\") != std::string::npos)
      throw std::invalid_argument("time series: column name '" + name + "' contains a quote or backslash");
    descr += fmt::format("('{}', '<f8'), ", name);
  }
  descr += "]";
  std::string dict = fmt::format("{{'descr': {}, 'fortran_order': False, 'shape': ({},), }}", descr, rows);
  const std::size_t preamble = 10;  // magic (6) + version (2) + length (2)
  std::size_t total = preamble + dict.size() + 1;
  dict.append((64 - total % 64) % 64, ' ');
  dict += '\n';
  if (dict.size() > 65535) throw std::invalid_argument("time series: too many columns for a .npy header");
  std::string out;
  out.reserve(preamble + dict.size() + rows * columns.size() * sizeof(double));
  out += "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(dict.size() & 0xff);
  out += static_cast<char>(dict.size() >> 8);
  out += dict;
  // Records: the row's value of each column in order.
  const std::size_t record = columns.size() * sizeof(double);
  const std::size_t offset = out.size();
  out.resize(offset + rows * record);
  char* p = out.data() + offset;
  for (std::size_t r = 0; r < rows; ++r)
    for (const std::span<const double>& column : columns) {
      std::memcpy(p, &column[r * decimation], sizeof(double));
      p += sizeof(double);
    }
  return out;
}

std::string write_time_series(const std::filesystem::path& dir, const std::string& stem,
                              const std::vector<std::string>& header,
                              const std::vector<std::span<const double>>& columns, TimeSeriesFormat format,
                              std::size_t decimation) {
  check_shape(header, columns, decimation);
  const std::string name = stem + "." + to_string(format);
  if (format == TimeSeriesFormat::npy) {
    write_file_atomically(dir / name, npy_bytes(header, columns, decimation));
    return name;
  }
  std::vector<std::vector<double>> kept(columns.size());
  const std::size_t rows = kept_rows(columns, decimation);
  for (std::size_t c = 0; c < columns.size(); ++c) {
    kept[c].reserve(rows);
    for (std::size_t r = 0; r < rows; ++r) kept[c].push_back(columns[c][r * decimation]);
  }
  write_file_atomically(dir / name, csv_text(header, kept));
  return name;
}

}  // namespace chatterlab
