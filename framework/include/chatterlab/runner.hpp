#pragma once
// Runs a loaded study over its grid: OpenMP threads inside a process, MPI ranks across processes
// (`mpirun -np N chatterlab run ...` writes a results.csv byte-identical to one process).
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>

#include "chatterlab/study.hpp"

namespace chatterlab {

struct RunOptions {
  std::filesystem::path out_dir;        // default chosen by the CLI: out/<study file stem>
  int threads = 0;                      // 0: OpenMP default
  bool resume = false;                  // keep finished points of an interrupted run
  std::optional<bool> progress;         // default: a progress bar iff stderr is a terminal
  bool plots = true;                    // false: results.csv + meta.json only (benchmarks)
  // Called after each point this process computes, from whichever thread computed it (so it must
  // be thread-safe and quick), with the points done so far and the points this process computes;
  // once with (0, total) before the first. The Python API's progress display polls it.
  std::function<void(std::size_t points_done, std::size_t points_total)> on_point_done;
};

struct RunSummary {
  std::size_t points = 0;
  std::size_t failed = 0;
  std::size_t resumed = 0;  // points taken over from an earlier run
  int exit_code() const { return failed == 0 ? 0 : 1; }
};

// Throws InputError before writing anything when the output directory is unusable.
RunSummary run_study(const Study& study, const RunOptions& options);

}  // namespace chatterlab
