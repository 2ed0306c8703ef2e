// Speed of the nonlinear analyses (MODELS.md N) on 100,000-point series, against the TISEAN
// timings quoted in issue 6 (lyap_spec 66 s Henon / 58 s Lorenz, d2 17 s at a 2 % and 212 s at a
// 20 % radius range, lyap_k 11-20 s over 3 dimensions x 5 radii). Parameters follow TISEAN's
// defaults where the two tools share them (lyap_spec: m = 2, delay 1, 30 neighbours, every
// point a reference; lyap_k: m = 2..4, 5 radii, 50 steps); d2 runs our sampled-reference scheme
// (2000 references x all vectors, dimensions 1..10, all radii at once). Run single-threaded
// (OMP_NUM_THREADS=1) and with 2 threads; docs/performance.md records the figures.
#include <benchmark/benchmark.h>

#include <cmath>

#include "analysis/correlation_dimension/correlation_dimension.hpp"
#include "analysis/lyapunov/lyapunov.hpp"
#include "analysis/lyapunov_spectrum/lyapunov_spectrum.hpp"
#include "analysis/nonlinear_common/test_signals.hpp"

namespace {

using namespace chatterlab;

const std::vector<double>& henon() {
  static const auto x = test_signals::henon(100000);
  return x;
}
const std::vector<double>& lorenz() {
  static const auto x = test_signals::lorenz(100000);
  return x;
}

void BM_LyapSpecHenon(benchmark::State& state) {
  for (auto _ : state) {
    auto s = lyapunov_spectrum(henon(), 2, 1, 0, 1, 30, 100000);
    benchmark::DoNotOptimize(s.exponents);
    state.counters["lambda1"] = s.exponents[0];
  }
}
BENCHMARK(BM_LyapSpecHenon)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_LyapSpecLorenz(benchmark::State& state) {
  for (auto _ : state) {
    auto s = lyapunov_spectrum(lorenz(), 2, 1, 0, 1, 30, 100000);
    benchmark::DoNotOptimize(s.exponents);
  }
}
BENCHMARK(BM_LyapSpecLorenz)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_D2Henon(benchmark::State& state) {
  for (auto _ : state) {
    auto sums = correlation_sums(henon(), 10, 1, 0, std::size_t(state.range(0)));
    benchmark::DoNotOptimize(sums.counts);
  }
}
BENCHMARK(BM_D2Henon)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();

// lyap_k: dimensions 2, 3, 4 x 5 radii (geometric, 0.2 % .. 2 % of the range), 50 steps.
void BM_LyapKHenon(benchmark::State& state) {
  for (auto _ : state) {
    double total = 0;
    for (int m = 2; m <= 4; ++m)
      for (int r = 0; r < 5; ++r) {
        const double radius = 2.6 * 0.002 * std::pow(10.0, r / 4.0);
        auto c = divergence_curves(henon(), m, 1, 0, 50, std::size_t(state.range(0)), radius);
        total += c.kantz_sum[0];
      }
    benchmark::DoNotOptimize(total);
  }
}
BENCHMARK(BM_LyapKHenon)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
