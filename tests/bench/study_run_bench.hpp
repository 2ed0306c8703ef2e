#pragma once
// Timing a whole study through the runner (load_study + run_study: the grid loop, journal and
// results; plots off, they are drawn once per study): shared by the benchmarks of runner,
// suppression and Floquet maps.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"

namespace chatterlab::bench {

// A file of the source tree (studies/..., tests/cli/studies/...).
inline std::filesystem::path source_path(const std::string& relative) {
  return std::filesystem::path(CHATTERLAB_SOURCE_DIR) / relative;
}

// Runs `study` once per iteration into a temporary directory named after `name`, with `threads`
// OpenMP threads; counters `points` and `points_per_s`. A failed grid point fails the benchmark.
inline void run_study_iterations(benchmark::State& state, const Study& study, const std::string& name,
                                 int threads) {
  RunOptions options;
  options.out_dir = std::filesystem::temp_directory_path() / ("chatterlab_bench_" + name);
  options.threads = threads;
  options.progress = false;
  options.plots = false;
  double points = 0;
  for (auto _ : state) {
    const RunSummary summary = run_study(study, options);
    if (summary.failed > 0) state.SkipWithError("grid points failed");
    points += static_cast<double>(summary.points);
  }
  state.counters["points"] = points;
  state.counters["points_per_s"] = benchmark::Counter(points, benchmark::Counter::kIsRate);
  state.counters["threads"] = static_cast<double>(threads);
}

}  // namespace chatterlab::bench
