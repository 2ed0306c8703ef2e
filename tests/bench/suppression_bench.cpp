// The suppression map (MODELS.md S1-S3) through the real runner: the shipped 400-point studies
// (load_study + run_study with 2 OpenMP threads, plots off), each run once in a fresh process
// state, so the one-off constant-speed reference and growth-rate table are inside the time; and
// one modulated grid point (simulation + S2/S3/S1) with those caches warm. Figures and commands:
// docs/performance.md, "Suppression".
//
//   build/ci/tests/bench/suppression_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "study_run_bench.hpp"

namespace {


using chatterlab::bench::source_path;

void BM_SuppressionMapStudy(benchmark::State& state, const std::string& name) {
  const chatterlab::Study study = chatterlab::load_study(source_path("studies/" + name + ".toml"));
  chatterlab::bench::run_study_iterations(state, study, "suppression_" + name, 2);
}

// One point of the wheel-speed map (a = 0.1, 1 Hz sinusoidal, 50 revolutions), caches warm.
void BM_SuppressionPoint(benchmark::State& state) {
  const chatterlab::Study study = chatterlab::load_study(source_path("studies/suppression_wheel_speed.toml"));
  const auto kind = chatterlab::study_kind_registry().at("suppression_map").create(chatterlab::ParamValues());
  chatterlab::Json point = study.point_document(0);
  point["suppression"]["amplitude_ratio"] = 0.1;
  point["suppression"]["frequency_hz"] = 1.0;
  kind->run_point(point, chatterlab::PointContext{});  // fills the reference and the table
  for (auto _ : state) benchmark::DoNotOptimize(kind->run_point(point, chatterlab::PointContext{}));
}

}  // namespace

BENCHMARK_CAPTURE(BM_SuppressionMapStudy, wheel_speed, std::string("suppression_wheel_speed"))
    ->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_SuppressionMapStudy, work_speed, std::string("suppression_work_speed"))
    ->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_SuppressionMapStudy, feed, std::string("suppression_feed"))
    ->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_SuppressionPoint)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
