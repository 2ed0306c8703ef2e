#pragma once
// A study file loaded and validated: `chatterlab run STUDY.toml`. See docs/studies.md.
//
//   plugins = ["path/libx.so"]        # optional out-of-tree plugin libraries (relative to the file)
//   [study]  kind = "stability_map"   # which StudyKind runs it; name/description optional
//   [model]  type = "plunge_regenerative", ...parameters...   (component tables, kind-specific)
//   [stability] ...                    # kind settings
//   [grid]   "model.modes.0.damping_ratio" = [0.01, 0.02]      # parameter paths -> values
//            wheel_speed_rpm = { from = 1000, to = 2000, steps = 21, log = false }
//   [run]    point_timeout_s = 600, isolate = false              # optional, how points run
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

struct GridAxis {
  std::string key;          // exactly as written in [grid] (the results.csv column name)
  std::string path;         // resolved dotted path: a bare name means "model.<name>"
  std::vector<Json> values; // expanded values, in order
  SourceLocation where;     // line of the grid key
};

// What a grid costs (docs/studies.md, "Grid size"). Results stream (docs/architecture.md,
// "Streaming results"): rank 0 holds a fixed part, a few bytes of bookkeeping per point and a
// bounded number of rows -- the plots' table (at most runner::max_plot_rows), and the rows of a
// block that finished ahead of an earlier one (at most runner::max_block_points) -- while on disk
// the journal, results.csv and the plots' data grow with the grid. Rows are costed per cell of a
// results.csv row (grid keys + output columns + status), at rates measured on stability_map
// grids, whose certificate column makes them the most expensive per cell of the built-in kinds.
// A kind's own per-point working set (a long profile, a long simulation) comes on top.
struct GridCost {
  // Measured (docs/performance.md, "Study runner at grid scale"): a 9-point linear_dde stability
  // map peaks at 25 MB (program, libraries, HDF5, two threads' working sets), 10-cell rows take
  // about 1100 bytes each while held, the list of points to compute 8 bytes per point and a
  // resume's journal offsets 8 more; on disk 1360 bytes per 10-cell row.
  static constexpr std::uint64_t fixed_memory_bytes = std::uint64_t{40} << 20;
  static constexpr std::uint64_t bookkeeping_bytes_per_point = 16;
  static constexpr std::uint64_t memory_bytes_per_cell = 110;
  static constexpr std::uint64_t disk_bytes_per_cell = 140;
  // Rows held at most: the plots' table and one block of points in flight.
  static constexpr std::uint64_t max_held_rows = 65'536 + 16'384;

  std::size_t points = 0;
  std::size_t cells_per_point = 0;
  std::uint64_t held_rows = 0;            // min(points, plot rows) + min(points, block)
  std::uint64_t held_rows_bytes = 0;      // held_rows x cells x memory_bytes_per_cell
  std::uint64_t disk_bytes_per_point = 0;
  std::uint64_t memory_budget_bytes = 0;  // half of this machine's physical memory
  // The largest grid accepted without --allow-large: the most points whose memory_bytes() fits
  // in memory_budget_bytes.
  std::size_t default_max_points = 0;

  // Peak memory at rank 0 (an estimate within a factor ~2 for the built-in kinds).
  std::uint64_t memory_bytes() const {
    return fixed_memory_bytes + held_rows_bytes + points * bookkeeping_bytes_per_point;
  }
  std::uint64_t disk_bytes() const { return points * disk_bytes_per_point; }
};
GridCost grid_cost(std::size_t points, std::size_t grid_keys, std::size_t output_columns);

struct LoadOptions {
  bool allow_large = false;  // permit grids over GridCost::default_max_points points
};

class InputSnapshot;  // chatterlab/input_files.hpp

struct Study {
  std::filesystem::path file;
  std::string kind;                      // [study] kind
  Json document;                         // the whole study, validated, defaults filled in
  std::vector<GridAxis> grid;            // empty: a single point
  std::vector<std::string> plugin_libraries;  // resolved absolute paths
  std::vector<std::string> output_columns;    // the kind's outputs (results.csv, after the grid)
  std::shared_ptr<const SourceMap> sources;
  // The input files as load_study read them (study file, plugin libraries, data files), with
  // their hashes: run_study reads through this snapshot, so every point sees the same bytes.
  std::shared_ptr<InputSnapshot> inputs;

  std::size_t point_count() const;  // product of axis sizes (1 without a grid)
  // Index -> per-axis value indices; the LAST axis varies fastest (row-major, "grid order").
  std::vector<std::size_t> point_indices(std::size_t point) const;
  // The document with that point's grid values written at their paths, without the [grid] and
  // [run] tables (a point is one set of values; this also keeps the copy cheap for long grids).
  Json point_document(std::size_t point) const;
};

// Reads, parses and validates a study (including the kind's tables and every grid value against
// the declared limits at its path). Loads the named plugin libraries first. Throws InputError with
// "<file>:<line>: ..." messages; touches nothing on disk.
Study load_study(const std::filesystem::path& file, const LoadOptions& options = {});

// The same for a study built in memory (the Python API's run_study(dict)), read as if it were
// the file `origin`: messages start "<origin>: " (no line numbers) and relative paths (plugins,
// data files) resolve against origin's directory, the working directory for a bare name.
Study load_study_document(Json document, const std::filesystem::path& origin, const LoadOptions& options = {});

// Sets a value at a dotted path inside a JSON document ("model.modes.0.damping_ratio").
// Throws InputError when the path does not exist in the document.
void set_at_path(Json& document, const std::string& dotted_path, const Json& value);

}  // namespace chatterlab
