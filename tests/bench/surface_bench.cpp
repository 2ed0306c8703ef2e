// Surface evaluation of long profiles through the real code path (evaluate_surface_profile, the
// function the `surface` study kind calls): filter + W parameters (+ MOTIF for open, + four
// reference circles, the 15/50/150/500 UPR table and Wz|f for closed profiles). Target: a
// 1,000,000-point profile filtered and evaluated in under 1 s. Numbers: docs/performance.md.
//
//   build/ci/tests/bench/surface_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>

#include "shared/metrology/surface.hpp"

namespace {

using namespace chatterlab;
using namespace chatterlab::surface;

// Open: 0.5 um spacing (500 mm of profile at 1e6 points), waviness + roughness + noise.
SampledSeries open_profile(std::size_t n) {
  SampledSeries s;
  s.sample_interval = 0.0005;
  s.sample_unit = "mm";
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<double> values;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i) * s.sample_interval;
    values.push_back(1.5 * std::sin(2 * std::numbers::pi * x / 4.0) +
                     0.3 * std::sin(2 * std::numbers::pi * x / 0.05) + noise(rng));
  }
  s.set_samples(std::move(values));
  return s;
}

// Closed: one revolution of n samples with 26 forced lobes and a chatter band.
SampledSeries closed_profile(std::size_t n) {
  SampledSeries s;
  s.closed = true;
  s.sample_unit = "deg";
  s.sample_interval = 360.0 / static_cast<double>(n);
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<double> values;
  for (std::size_t i = 0; i < n; ++i) {
    const double th = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
    values.push_back(4 * std::cos(th) + 2.13 * std::cos(26 * th) + 1.56 * std::cos(895 * th) +
                     noise(rng));
  }
  s.set_samples(std::move(values));
  return s;
}

void BM_OpenGaussian(benchmark::State& state) {
  const SampledSeries s = open_profile(static_cast<std::size_t>(state.range(0)));
  SurfaceSettings settings;
  settings.cutoff_mm = 0.8;
  for (auto _ : state) benchmark::DoNotOptimize(evaluate_surface_profile(s, settings));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_OpenGaussian)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_OpenRobustGaussian(benchmark::State& state) {
  const SampledSeries s = open_profile(static_cast<std::size_t>(state.range(0)));
  SurfaceSettings settings;
  settings.cutoff_mm = 0.8;
  settings.filter = FilterType::robust_gaussian;
  Json summary;
  for (auto _ : state) {
    summary = evaluate_surface_profile(s, settings).summary;
    benchmark::DoNotOptimize(summary);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.counters["reweighting_passes"] = summary["filter"]["iterations"].get<double>();
}
BENCHMARK(BM_OpenRobustGaussian)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_ClosedGaussianRoundness(benchmark::State& state) {
  const SampledSeries s = closed_profile(static_cast<std::size_t>(state.range(0)));
  SurfaceSettings settings;
  settings.cutoff_upr = 150;
  settings.wheel_speed_rpm = 1450;
  settings.work_speed_rpm = 55;
  for (auto _ : state) benchmark::DoNotOptimize(evaluate_surface_profile(s, settings));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ClosedGaussianRoundness)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
