// Chatter monitors (MODELS.md C1-C3) over 1 s of an 8 kHz signal (the synthetic stable -> chatter
// transition of monitor::TransitionSignal), through the plugins as chatter_monitor runs them.
// Items per second = signal samples per second on one core: how far ahead of real time a monitor
// runs. Numbers: docs/performance.md, "Chatter monitoring".
//
//   build/release/tests/bench/chatter_monitor_bench
#include <benchmark/benchmark.h>

#include "shared/monitoring/monitor_common.hpp"
#include "analysis/window_features/window_features.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/registry.hpp"

namespace {

using namespace chatterlab;

SampledSeries transition() {
  monitor::TransitionSignal spec;
  SampledSeries s;
  s.set_samples(spec.samples());
  s.sample_interval = 1.0 / spec.sample_rate_hz;
  return s;
}

void run_analysis(benchmark::State& state, const char* name, const Json& params) {
  const SampledSeries s = transition();
  auto analysis = analysis_registry().at(name).create(ParamValues(params));
  for (auto _ : state) benchmark::DoNotOptimize(analysis->analyse(s, Json::object()));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(s.values.size()));
}

// C1: features of consecutive 10-sample windows.
void BM_WindowFeatures(benchmark::State& state) {
  const SampledSeries s = transition();
  for (auto _ : state) benchmark::DoNotOptimize(feature_series(s.values, 10, 10, s.sample_interval));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(s.values.size()));
}

// C2: train on the book's 150 + 150 samples, then score every 10-sample window.
void BM_BpNetworkTrainAndScore(benchmark::State& state) {
  run_analysis(state, "bp_network",
               {{"window_samples", 10}, {"stable_s", {0.1, 0.1186875}}, {"onset_s", {0.7, 0.7186875}},
                {"train_fraction", 2.0 / 3.0}, {"eta0", 2.0}, {"alpha", 1e-4},
                {"target_error", 0.02}, {"max_epochs", 50000}, {"seed", 1}, {"biases", false},
                {"alarm_output", 0.5}, {"persistence_windows", 5}});
}

// C3: the RBF density criterion on the latest 50 samples every 10 samples.
void BM_RbfDensity(benchmark::State& state) {
  run_analysis(state, "rbf_density",
               {{"window_samples", 50}, {"hop_samples", 10}, {"nodes", 3}, {"rho", 0.2},
                {"persistence_windows", 10}});
}

BENCHMARK(BM_WindowFeatures)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BpNetworkTrainAndScore)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RbfDensity)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
