// The Floquet route of stability_map (MODELS.md S2; issue 17 item 7) against the simulated
// suppression map at equal resolution: studies/floquet_wheel_speed.toml (10 amplitudes x 10
// frequencies, sinusoidal, each point the Floquet growth rate of the periodic linearisation plus
// the constant-speed root) and studies/suppression_wheel_speed.toml on the same 10 x 10 grid
// (its sinusoidal shape alone, every point a 50-revolution simulation plus S2/S3), both through
// the runner (load_study + run_study, 2 OpenMP threads, plots off, run once in a fresh process
// state), and one Floquet point of each end of the frequency axis. Figures and commands:
// docs/performance.md, "Floquet maps".
//
//   build/ci/tests/bench/floquet_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "study_run_bench.hpp"

namespace {


using chatterlab::bench::source_path;

void run(benchmark::State& state, const chatterlab::Study& study, const std::string& name) {
  chatterlab::bench::run_study_iterations(state, study, "floquet_" + name, 2);
}

void BM_FloquetMap(benchmark::State& state) {
  run(state, chatterlab::load_study(source_path("studies/floquet_wheel_speed.toml")), "floquet");
}

// The simulated map on the Floquet map's grid: the shape axis fixed to sinusoidal.
void BM_SimulatedMapSameGrid(benchmark::State& state) {
  chatterlab::Study study = chatterlab::load_study(source_path("studies/suppression_wheel_speed.toml"));
  for (auto& axis : study.grid)
    if (axis.key == "suppression.shape") axis.values = {chatterlab::Json("sinusoidal")};
  run(state, study, "simulated");
}

// One Floquet point (a = 0.05): its period sets the steps, the delay the monodromy's dimension.
void BM_FloquetPoint(benchmark::State& state) {
  const chatterlab::Study study = chatterlab::load_study(source_path("studies/floquet_wheel_speed.toml"));
  const auto kind = chatterlab::study_kind_registry().at("stability_map").create(chatterlab::ParamValues());
  chatterlab::Json point = study.point_document(0);
  point["suppression"]["amplitude_ratio"] = 0.05;
  point["suppression"]["frequency_hz"] = static_cast<double>(state.range(0)) / 100.0;
  for (auto _ : state) benchmark::DoNotOptimize(kind->run_point(point, chatterlab::PointContext{}));
}

}  // namespace

BENCHMARK(BM_FloquetMap)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_SimulatedMapSameGrid)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_FloquetPoint)->Arg(25)->Arg(2500)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
