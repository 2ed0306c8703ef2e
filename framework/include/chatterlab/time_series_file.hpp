#pragma once
// Time-series files of a simulation (the `simulate` study's timeseries.csv / timeseries.npy),
// written so that output never dominates a long run: every k-th sample only (decimation, no
// filter: the file holds exact samples at the sample rate / k), and a binary format for long
// runs. docs/dynamics.md ("Output files") documents both formats.
//
// .npy (NumPy format version 1.0): one structured array of `rows` records, one little-endian
// float64 field per column named by the header, so
//     x = numpy.load("timeseries.npy"); x["t_s"], x["displacement_m"]
//     pandas.DataFrame(numpy.load("timeseries.npy"))
// read it directly. CSV: the header line, then one line per row, numbers in shortest round-trip
// form (chatterlab/output_files.hpp).
#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace chatterlab {

enum class TimeSeriesFormat { csv, npy };
const char* to_string(TimeSeriesFormat format);
TimeSeriesFormat parse_time_series_format(const std::string& name);  // std::invalid_argument

// Writes the columns (all of one length) to dir/<stem>.csv or .npy atomically (nothing partial
// on failure: chatterlab/output_files.hpp), keeping rows 0, k, 2k, ... (k = decimation >= 1).
// Returns the file name written. std::invalid_argument for unequal columns, a header of another
// size or k = 0; std::runtime_error naming the file if it cannot be written.
std::string write_time_series(const std::filesystem::path& dir, const std::string& stem,
                              const std::vector<std::string>& header,
                              const std::vector<std::span<const double>>& columns, TimeSeriesFormat format,
                              std::size_t decimation = 1);

// The bytes of such a .npy file (for tests and for writers that stream elsewhere).
std::string npy_bytes(const std::vector<std::string>& header, const std::vector<std::span<const double>>& columns,
                      std::size_t decimation = 1);

}  // namespace chatterlab
