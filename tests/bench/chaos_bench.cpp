// Speed of the nonlinear analyses (MODELS.md N) on 100,000-point series, against the TISEAN
// timings quoted in issue 6 (lyap_spec 66 s Henon / 58 s Lorenz, d2 17 s at a 2 % and 212 s at a
// 20 % radius range, lyap_k 11-20 s over 3 dimensions x 5 radii). Parameters follow TISEAN's
// defaults where the two tools share them (lyap_spec: m = 2, delay 1, 30 neighbours, every
// point a reference; lyap_k: m = 2..4, 5 radii, 50 iterations, every point a reference); d2 runs our sampled-reference scheme
// (2000 references x all vectors, dimensions 1..10, all radii at once) and, like for like, every
// pair within 2 % / 20 % of the range (BM_D2HenonAllPairs). Run single-threaded
// (OMP_NUM_THREADS=1) and with 2 threads; docs/performance.md records the figures.
#include <benchmark/benchmark.h>

#include <algorithm>
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

// TISEAN d2's work with all pairs (-N 0): dimensions 1..10, every pair closer than 2 % (arg 20) or
// 20 % (arg 200) of the range, counted exactly (sorted strips), radii binned 8 per octave.
void BM_D2HenonAllPairs(benchmark::State& state) {
  const double cut = double(state.range(0)) / 1000.0;
  for (auto _ : state) {
    auto sums = correlation_sums_within(henon(), 10, 1, 0, cut);
    benchmark::DoNotOptimize(sums.counts);
    // Ordered pairs closer than the cut in dimensions 2 and 10 (each pair counts for both of its
    // vectors): the work that grows with the cut.
    for (const int d : {2, 10}) {
      double pairs = 0;
      for (std::size_t b = 0; b < CorrelationSums::blocks; ++b)
        for (std::size_t k = 0; CorrelationSums::edge(k) <= cut; ++k)
          pairs += double(sums.counts[(b * 10 + std::size_t(d - 1)) * CorrelationSums::bins + k]);
      state.counters[d == 2 ? "pairs_m2" : "pairs_m10"] = pairs;
    }
  }
}
BENCHMARK(BM_D2HenonAllPairs)->Arg(20)->Arg(200)->Unit(benchmark::kMillisecond)->UseRealTime();

// TISEAN lyap_k's work for "3 dimensions x 5 radii": -m 2 -M 4, its default radii (5, geometric
// from 1/1000 to 1/100 of the data range), 50 iterations (S(k) for k = 0..50), every vector a
// reference point (-n default), Theiler window 0 (-t default), all neighbours within eps.
void lyap_k_scan(benchmark::State& state, const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  std::vector<double> radii;
  for (int r = 0; r < 5; ++r) radii.push_back((*hi - *lo) * 1e-3 * std::pow(10.0, r / 4.0));
  for (auto _ : state) {
    auto scan = kantz_scan(x, 2, 4, 1, 0, 51, 0, radii);
    benchmark::DoNotOptimize(scan.sum);
    const auto curve = scan.curve(2, 2);
    state.counters["slope_m2_eps3"] = (curve[10] - curve[2]) / 8.0;
  }
}
void BM_LyapKHenon(benchmark::State& state) { lyap_k_scan(state, henon()); }
void BM_LyapKLorenz(benchmark::State& state) { lyap_k_scan(state, lorenz()); }
BENCHMARK(BM_LyapKHenon)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LyapKLorenz)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
