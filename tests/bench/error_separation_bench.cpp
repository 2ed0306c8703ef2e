// Error separation (MODELS.md E1-E4) on one revolution of N samples: the frequency-domain method
// (FFT of S, R = S/G, one inverse FFT per probe for the spindle motion) and the time recursion,
// O(N log N) and O(N); the band optimiser of the probe angles (every three-probe layout on a
// one-degree grid, N = 360) and the lost-spectrum report of a degraded layout. Items per second
// = samples per second. Numbers: docs/performance.md.
//
//   build/ci/tests/bench/error_separation_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <numeric>
#include <vector>

#include "study_kinds/error_separation/error_separation.hpp"

namespace {

using namespace chatterlab::error_separation;

// Three probes at 0, p, 2p samples (p coprime with N, about 97 degrees) reading a part with a
// few harmonics and a moving spindle.
struct Setup {
  ProbeLayout layout;
  std::vector<std::vector<double>> probes;
};

Setup make_setup(std::size_t n) {
  Setup s;
  auto p = static_cast<std::size_t>(static_cast<double>(n) * 97.0 / 360.0);
  while (std::gcd(p, n) != 1) ++p;
  for (std::size_t q = 0; q < 3; ++q)
    s.layout.angles_rad.push_back(2 * std::numbers::pi * static_cast<double>(q * p) / static_cast<double>(n));
  s.layout.weights = three_point_weights(s.layout.angles_rad);
  for (double phi : s.layout.angles_rad) {
    std::vector<double> y(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double th = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n) + phi;
      y[i] = 2 * std::cos(3 * th) + 0.5 * std::sin(18 * th) + 0.1 * std::cos(400 * th) +
             std::cos(2 * th - phi) * std::cos(phi);
    }
    s.probes.push_back(std::move(y));
  }
  return s;
}

void BM_Frequency(benchmark::State& state) {
  const Setup s = make_setup(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(separate_frequency(s.probes, s.layout, {}));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_TimeRecursion(benchmark::State& state) {
  const Setup s = make_setup(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(separate_time_recursion(s.probes, s.layout, {}));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

// Probe angles for the band 2..50 (N = 360, phi2 <= 180 deg): what every error_separation run
// reports (and proposes for a degraded layout).
void BM_OptimiseAnglesForBand(benchmark::State& state) {
  for (auto _ : state) {
    const AngleOptimum best = optimise_three_point_angles(360, 50, std::numbers::pi, 1e-6, 2);
    benchmark::DoNotOptimize(best.worst.q);
    state.counters["layouts"] = static_cast<double>(best.layouts_checked);
  }
}

// What a [0, 90, 180] layout loses at N samples: the probes' spectra and the lost share.
void BM_LostSpectrum(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Setup s = make_setup(n);
  s.layout.angles_rad = {0.0, std::numbers::pi / 2, std::numbers::pi};
  s.layout.weights = three_point_weights(s.layout.angles_rad);
  const auto lost = suppressed_harmonics(s.layout, static_cast<int>(n / 2), 1e-6);
  for (auto _ : state) benchmark::DoNotOptimize(lost_spectrum(s.probes, lost, 2, static_cast<int>(n / 2)).lost_share);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

}  // namespace

BENCHMARK(BM_OptimiseAnglesForBand)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LostSpectrum)->Arg(4096)->Arg(65536)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frequency)->Arg(4096)->Arg(65536)->Arg(1 << 20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TimeRecursion)->Arg(4096)->Arg(65536)->Arg(1 << 20)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
