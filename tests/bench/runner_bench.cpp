// Grid points per second of stability_map studies through the real runner (load_study +
// run_study: OpenMP loop, journal, results.csv, meta.json; plots off, they are drawn once per
// study and would only add a constant), with 1 and 2 threads: the OpenMP speedup of the grid
// loop. Figures and commands: docs/performance.md, "Study runner".
//
//   build/release/tests/bench/runner_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "study_run_bench.hpp"

namespace {

namespace fs = std::filesystem;

fs::path bench_dir() {
  fs::path dir = fs::temp_directory_path() / "chatterlab_runner_bench";
  fs::create_directories(dir);
  return dir;
}

// The DDE-BIFTOOL oscillator x'' + 0.1 x' + 1.3 x = b x(t - tau), delays up to 60 time units:
// 40 gains x 250 delays (10,000 points: long enough that the fixed cost of a run, writing its
// files, does not hide the speedup of the grid loop).
constexpr const char* dde_study = R"(
[study]
kind = "stability_map"
[model]
type = "linear_dde"
a0 = [[0.0, 1.0], [-1.3, -0.1]]
delayed = [{ delay_s = 10.0, matrix = [[0.0, 0.0], [0.3, 0.0]] }]
[stability]
max_frequency_hz = 1.0
[grid]
"model.delayed.0.matrix.1.0" = { from = 0.01, to = 0.6, steps = 40 }
"model.delayed.0.delay_s" = { from = 1.0, to = 60.0, steps = 250 }
)";

// Loaded once per study file.
const chatterlab::Study& study(const fs::path& file) {
  static std::map<fs::path, chatterlab::Study> loaded;
  auto it = loaded.find(file);
  if (it == loaded.end()) it = loaded.emplace(file, chatterlab::load_study(file)).first;
  return it->second;
}

void run_grid(benchmark::State& state, const std::string& name, const fs::path& file) {
  chatterlab::bench::run_study_iterations(state, study(file), "runner_" + name, static_cast<int>(state.range(0)));
}

// MODELS.md G1 at grinding scale: work period Tw = 60/55 s against the 305.6 Hz mode's 3.3 ms
// (ratio ~330); work 40..70 rpm x wheel 1300..1600 rpm, 15 x 20 points (the CLI resume study).
void BM_StabilityMapPlunge(benchmark::State& state) {
  run_grid(state, "plunge", chatterlab::bench::source_path("tests/cli/studies/resume_grid.toml"));
}
void BM_StabilityMapLinearDde(benchmark::State& state) {
  fs::path file = bench_dir() / "linear_dde.toml";
  std::ofstream(file) << dde_study;
  run_grid(state, "linear_dde", file);
}

BENCHMARK(BM_StabilityMapPlunge)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);
BENCHMARK(BM_StabilityMapLinearDde)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);

}  // namespace

BENCHMARK_MAIN();
