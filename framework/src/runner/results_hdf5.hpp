#pragma once
// results.h5, the HDF5 form of results.csv ([output] format = "hdf5"; docs/studies.md, "HDF5
// results"). One dataset per output column plus `status`, each shaped like the grid (axis 0 = the
// first [grid] key, the last axis varying fastest, as the rows of results.csv), chunked and
// compressed (shuffle + deflate), with the grid axes as HDF5 dimension scales under /grid and the
// study file, the resolved study and the run's provenance (meta.json's header) as attributes.
//
// Cell types, per column, from its first non-null value: numbers -> float64 (null: NaN),
// booleans -> an int8 enum FALSE/TRUE (h5py reads it as bool; null: FALSE, the status says why),
// text -> fixed-length UTF-8 strings, null-padded (fixed length, unlike variable-length strings,
// goes through the compression filters), widened when a longer value arrives. A text value in a
// column of numbers or booleans cannot be stored: commit() then fails (OutputError) and the
// journal, kept, lets `--resume` write CSV instead.
//
// The writer takes points strictly in grid order and writes whole chunks as they fill, so it
// holds at most one row of chunks (runner::hdf5_chunk_points points per column).
//
// The Debian HDF5 build is not thread-safe: one thread at a time may call these functions
// (GridOrderWriter calls them under its mutex).
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "chatterlab/study.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

enum class ResultsFormat { csv, hdf5 };
// [output] format = "auto" writes HDF5 above this many points.
inline constexpr std::size_t auto_hdf5_above_points = 100'000;
// Points per chunk (and per write) of a column dataset: 128 KiB of float64.
inline constexpr std::size_t hdf5_chunk_points = 16'384;

// The study's [output] format (csv when the table is absent).
ResultsFormat results_format(const Study& study);
// [output] keep_journal: false (the default) removes journal/ after a complete hdf5 run.
bool keep_journal(const Study& study);
std::filesystem::path results_path(const std::filesystem::path& out_dir, ResultsFormat format);

class Hdf5ResultsWriter {
 public:
  // Creates the file under a temporary name next to `path`. `provenance` (meta.json's header)
  // becomes the root attribute "meta". Throws OutputError.
  Hdf5ResultsWriter(const Study& study, std::vector<std::string> columns,
                    std::filesystem::path path, const Json& provenance);
  ~Hdf5ResultsWriter();  // abandons an uncommitted file
  Hdf5ResultsWriter(const Hdf5ResultsWriter&) = delete;
  Hdf5ResultsWriter& operator=(const Hdf5ResultsWriter&) = delete;

  // The next point in grid order. Throws OutputError.
  void append(PointResult&& result);
  // After the last point: the dimension scales, then the file into place (fsync, rename).
  void commit();
  void abandon() noexcept;
  const std::filesystem::path& temporary_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// results.h5 read chunk row by chunk row, in grid order: what a --resume streams from (it holds
// one chunk row, runner::hdf5_chunk_points points at most, never the grid). Not thread-safe.
class Hdf5ResultsReader {
 public:
  // Opens `file` and checks it is a chatterlab results.h5. Throws std::runtime_error naming it.
  explicit Hdf5ResultsReader(const std::filesystem::path& file);
  ~Hdf5ResultsReader();
  Hdf5ResultsReader(const Hdf5ResultsReader&) = delete;
  Hdf5ResultsReader& operator=(const Hdf5ResultsReader&) = delete;

  const JournalHeader& header() const;         // fingerprint, points, columns, inputs
  const std::vector<std::size_t>& shape() const;  // the grid's axis sizes ({1} without a grid)
  // The points of the next chunk row (empty after the last point); with `status_only` their
  // outputs are null cells and only the status is read. Throws std::runtime_error.
  std::vector<PointResult> next_chunk_row(bool status_only = false);
  std::size_t position() const;  // the first point of the next chunk row

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// results.h5 read back whole (tests; --resume streams with Hdf5ResultsReader): what a --resume takes over when the journal was removed, and what tests
// compare with results.csv. Cells come back as the journal holds them (numbers as doubles, NaN as
// null, booleans, text); a timeout's elapsed time is not stored (0).
struct Hdf5Results {
  JournalHeader header;             // fingerprint, points, columns, inputs (root attributes)
  std::vector<std::size_t> shape;   // the grid's axis sizes ({1} without a grid)
  std::vector<std::pair<std::size_t, PointResult>> records;  // every point, in grid order
};
// Throws std::runtime_error naming the file when it is not a chatterlab results.h5.
Hdf5Results read_hdf5_results(const std::filesystem::path& file);

}  // namespace chatterlab::runner
