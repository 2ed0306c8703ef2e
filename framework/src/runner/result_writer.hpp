#pragma once
// Streaming results (docs/architecture.md, "Streaming results"). Rank 0 hands every finished
// point to a GridOrderWriter in whatever order points finish; the writer appends its row of
// results.csv (or of results.h5, runner/results_hdf5.hpp) as soon as every earlier point is in,
// so it holds only the points that finished ahead of an earlier one (and, for HDF5, one row of
// chunks), never the whole grid. It keeps what the end of the run needs:
// one entry per failed point and per notice, and the bounded table the plots draw (every point of
// a small grid; the points on a lattice of every k-th axis value of a large one).
#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "chatterlab/output_files.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "runner/results_hdf5.hpp"
#include "runner/results_io.hpp"
#include "runner/resume.hpp"

namespace chatterlab::runner {

// The most rows a plot table holds: 2^16 = 256 x 256 cells of a two-axis map, a raster finer than
// a plot's cells on screen, and a few MB of plot data and memory whatever the grid size.
inline constexpr std::size_t max_plot_rows = std::size_t{1} << 16;

// Per-axis strides so that the thinned grid (every stride-th value of each axis, first value
// included) has at most max_rows points; the axis with the most remaining values is thinned
// first. All ones when the grid already fits.
std::vector<std::size_t> plot_strides(const Study& study, std::size_t max_rows);

// The study with each grid axis reduced to every strides[a]-th value: what write_artifacts gets
// with a decimated table, so varying_axes() and point_indices() describe the table's rows.
Study decimated_study(const Study& study, const std::vector<std::size_t>& strides);

class GridOrderWriter {
 public:
  // Creates `file` (a temporary name until commit()): results.csv with its header line, or
  // results.h5 with `provenance` (meta.json's header) as an attribute. Throws OutputError.
  GridOrderWriter(const Study& study, std::vector<std::string> output_columns,
                  const std::filesystem::path& file, ResultsFormat format = ResultsFormat::csv,
                  const Json& provenance = Json::object(), std::size_t plot_rows = max_plot_rows);

  // One finished point (each exactly once, from any thread). An output error is kept and thrown
  // by commit(): a grid loop must not unwind from a worker thread.
  void add(std::size_t point, PointResult&& result);

  // The points an earlier session finished (--resume): each is read back from its journal or
  // results.h5 when its row is due, so they are never all in memory. `resumed` must outlive the
  // writer's last add() and commit().
  void take_resumed_points(ResumedPoints* resumed);

  // After every point was added: results.csv into place. Throws OutputError.
  void commit();
  // The run is not valid after all (an input file changed): no results file.
  void abandon() noexcept;
  // The file the results are written to until commit(): what a process that must end at once (a
  // plugin called exit()) removes without waiting for a lock.
  const std::filesystem::path& temporary_path() const { return temporary_path_; }

  // meta.json's failed_points (in grid order) and notices ([{point, notice}], in grid order).
  Json failed_points() const;
  Json notices() const;

  // What write_artifacts gets: the study (grid axes thinned when the table is decimated) and
  // the table. Call once, after commit().
  const Study& plot_study() const { return *plot_study_; }
  ResultTable take_plot_table();

 private:
  // A point ahead of next_: its formatted CSV row, or (HDF5) its result.
  struct Early {
    std::string line;
    PointResult result;
    Json failure, notice;            // meta.json's entries (null: none)
    std::ptrdiff_t plot_row = -1;    // its row of the plot table (-1: not on the lattice)
    std::vector<Json> plot_cells;
    std::string plot_status;
  };
  // Everything of a row that needs no lock (formatting, the plot cells).
  Early prepare_row(std::size_t point, PointResult&& result) const;
  void write_ready();  // appends every row whose predecessors are all written; under mutex_
  void write_buffer();  // the CSV rows formatted so far to the file; under mutex_
  void append(Early&& row);  // the row of point next_; under mutex_
  std::string format_row(std::size_t point, const PointResult& result) const;

  const Study& study_;
  std::vector<std::string> columns_;
  std::ptrdiff_t notice_column_ = -1;
  std::unique_ptr<AtomicFileWriter> file_;    // results.csv
  std::unique_ptr<Hdf5ResultsWriter> hdf5_;   // or results.h5
  std::filesystem::path temporary_path_;
  std::string error_;  // first output error

  mutable std::mutex mutex_;
  std::size_t next_ = 0;               // the next point to write
  std::map<std::size_t, Early> early_;  // points ahead of next_
  ResumedPoints* resumed_ = nullptr;    // earlier sessions' points, read when due
  std::string buffer_;                       // rows written in blocks
  std::map<std::size_t, Json> failed_, notices_;

  std::vector<std::size_t> strides_;  // empty: every point is a plot row
  std::unique_ptr<Study> plot_study_;
  ResultTable plot_table_;
};

}  // namespace chatterlab::runner
