#pragma once
// Runs a loaded study over its grid: OpenMP threads inside a process, MPI ranks across processes
// (`mpirun -np N chatterlab run ...` writes a results.csv byte-identical to one process).
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/study.hpp"

namespace chatterlab {

struct RunOptions {
  std::filesystem::path out_dir;        // default chosen by the CLI: out/<study file stem>
  int threads = 0;                      // 0: OpenMP default
  bool resume = false;                  // keep finished points of an interrupted run
  std::optional<bool> progress;         // default: a progress bar iff stderr is a terminal
  bool plots = true;                    // false: results.csv + meta.json only (benchmarks)
};

struct RunSummary {
  std::size_t points = 0;
  std::size_t failed = 0;
  std::size_t resumed = 0;  // points taken over from an earlier run
  struct Notice {
    std::size_t point = 0;
    std::string text;
  };
  std::vector<Notice> notices;  // the kind's `notice` column, non-empty cells (also meta.json)
  int exit_code() const { return failed == 0 ? 0 : 1; }
};

// Throws InputError before writing anything when the output directory is unusable.
RunSummary run_study(const Study& study, const RunOptions& options);

}  // namespace chatterlab
