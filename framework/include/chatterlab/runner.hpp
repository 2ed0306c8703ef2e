#pragma once
// Runs a loaded study over its grid: OpenMP threads inside a process, MPI ranks across processes
// (`mpirun -np N chatterlab run ...` writes a results.csv byte-identical to one process), and,
// for untrusted plugins or a time limit per point, worker processes. What a run guarantees
// (inputs read once and checked, the output directory locked, the journal on disk within 0.1 s,
// exit codes) is in docs/studies.md, "Running a study".
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {

// One of N slices of a grid (`--shard I/N`, I from 1): the points p with p % N == I - 1, so a
// cost that varies along the grid spreads evenly over the shards. `chatterlab merge` combines
// the N output directories into the single run's result (chatterlab/shards.hpp).
struct ShardSpec {
  std::size_t index = 1;
  std::size_t count = 1;
};

struct RunOptions {
  std::filesystem::path out_dir;        // default chosen by the CLI: out/<study file stem>
  int threads = 0;                      // 0: OpenMP default
  bool resume = false;                  // keep finished points of an interrupted run
  bool retry_failed = false;            // with resume: recompute failed and timed-out points
  std::optional<bool> progress;         // default: a progress bar iff stderr is a terminal
  bool plots = true;                    // false: results.csv + meta.json only (benchmarks)
  // Points in worker processes (--isolate, or [run] isolate = true): a crashing plugin fails
  // only its point.
  bool isolate = false;
  // Time limit per point (--point-timeout; else [run] point_timeout_s): a point still running
  // then is killed and recorded as timeout. Implies worker processes.
  std::optional<double> point_timeout_s;
  // The executable started as a worker process (`<it> __worker ...`, which must call
  // run_point_worker). Default: this process's own executable.
  std::filesystem::path worker_executable = "/proc/self/exe";
  // Only this shard of the grid: the output directory then holds its journal and a meta.json
  // (state shard_complete), no results.csv or plots, until `chatterlab merge`.
  std::optional<ShardSpec> shard;
  // Called after each point this process computes, from whichever thread computed it (so it must
  // be thread-safe and quick), with the points it has done so far and the points the run
  // computes (all MPI ranks together); once with (0, total) before the first. The Python API's progress display polls it.
  std::function<void(std::size_t points_done, std::size_t points_total)> on_point_done;
};

struct RunSummary {
  std::size_t points = 0;
  std::size_t failed = 0;     // points not ok (timed-out points included)
  std::size_t timed_out = 0;  // of which stopped at the time limit
  std::size_t resumed = 0;    // points taken over from an earlier run
  std::string output_error;   // "" or why an output file could not be written (meta.json too)
  std::filesystem::path results_file;  // results.csv or results.h5 ([output] format); empty for a shard
  // 0 every point ok, 1 some points failed or timed out, 3 an output could not be written.
  // (2, bad input, is thrown as InputError before anything is written.)
  int exit_code() const { return !output_error.empty() ? 3 : failed == 0 ? 0 : 1; }
  struct Notice {
    std::size_t point = 0;
    std::string text;
  };
  std::vector<Notice> notices;  // the kind's `notice` column, non-empty cells (also meta.json)
};

// Throws InputError before writing anything when the study or the output directory is unusable
// (the directory is locked by another run, a resume does not match, an input file changed), and
// InputError after stopping the run when an input file changes while it goes (meta.json then
// says so; results.csv is not written).
RunSummary run_study(const Study& study, const RunOptions& options);

// The results.h5 ([output] format = "hdf5") that a run of `study` wrote, read back as the runner
// assembled it for results.csv: every point in grid order, the grid values from `study`, a failed
// point's outputs null. The Python API's run_study returns it as its table. Throws InputError
// naming the file when it cannot be read, is not a chatterlab results.h5, or another study wrote it.
ResultTable read_results_h5(const Study& study, const std::filesystem::path& results_h5);

// The body of a worker process: `chatterlab __worker FD PID` calls it (main() before anything
// else, MPI included). Returns the process exit code.
int run_point_worker(int argc, char** argv);

}  // namespace chatterlab
