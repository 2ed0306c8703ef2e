// Root finding per grid point, as the stability_map study kind does it: build the model from its
// parameter table (ParamValues), take its characteristic function, find the certified rightmost
// root. Items per second = grid points per second on one core. Numbers: docs/performance.md.
//
//   build/release/tests/bench/roots_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cstddef>
#include <string>
#include <vector>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/roots.hpp"
#include "derived/g1_written_once.hpp"
#include "models/linear_dde/linear_dde.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"

namespace {

using namespace chatterlab;

// The band searched when a benchmark gives none: this multiple of the model's natural frequency
// scale, as the stability_map study kind does by default (kit::default_band_multiple).
constexpr double kBandMultiple = 4.0;

// Runs one grid point per iteration over `tables`, cycling; reports points/s, evaluations per
// point and the fraction certified.
template <class ModelType>
void run_points(benchmark::State& state, const std::vector<Json>& tables, double band_hz) {
  std::size_t index = 0;
  double evaluations = 0.0, certified = 0.0, points = 0.0;
  for (auto _ : state) {
    ModelType model{ParamValues(tables[index])};
    index = (index + 1) % tables.size();
    auto characteristic = model.characteristic();
    RootSearchOptions options;
    options.max_frequency_hz =
        band_hz > 0.0 ? band_hz : kBandMultiple * characteristic->natural_frequency_scale_hz();
    RightmostRoot root = find_rightmost_root(*characteristic, options);
    benchmark::DoNotOptimize(root.root);
    evaluations += root.function_evaluations;
    certified += root.certified ? 1.0 : 0.0;
    points += 1.0;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["evals_per_point"] = evaluations / points;
  state.counters["certified_fraction"] = certified / points;
}

// DDE-BIFTOOL-style oscillator x'' + 2 zeta x' + x = -sum_k K_k (x - x(t - tau_k)), zeta = 0.05,
// as a grid over the total gain K in [0.1, 0.5] (64 points), one or two delays up to tau_max.
std::vector<Json> oscillator_grid(double tau_max, bool two_delays) {
  std::vector<Json> tables;
  for (int i = 0; i < 64; ++i) {
    double gain = 0.1 + 0.4 * i / 63.0;
    double k1 = two_delays ? 0.6 * gain : gain, k2 = gain - k1;
    Json delayed = Json::array();
    delayed.push_back({{"delay_s", tau_max}, {"matrix", {{0.0, 0.0}, {k1, 0.0}}}});
    if (two_delays) delayed.push_back({{"delay_s", tau_max / 2.3}, {"matrix", {{0.0, 0.0}, {k2, 0.0}}}});
    tables.push_back({{"a0", {{0.0, 1.0}, {-(1.0 + gain), -0.1}}}, {"delayed", delayed}});
  }
  return tables;
}

void BM_LinearDdeOneDelay(benchmark::State& state) {
  run_points<LinearDde>(state, oscillator_grid(static_cast<double>(state.range(0)), false), 0.0);
}
BENCHMARK(BM_LinearDdeOneDelay)->Arg(10)->Arg(30)->Arg(60)->ArgName("tau_max");

void BM_LinearDdeTwoDelays(benchmark::State& state) {
  run_points<LinearDde>(state, oscillator_grid(static_cast<double>(state.range(0)), true), 0.0);
}
BENCHMARK(BM_LinearDdeTwoDelays)->Arg(10)->Arg(30)->Arg(60)->ArgName("tau_max");

// The neuron system of DDE-BIFTOOL's tutorial (demo1, Shayer and Campbell 2000) linearised at its
// trivial equilibrium (tanh' = 1): x1' = -kappa x1 + beta x1(t - tau_s) + a12 x2(t - tau2),
// x2' = -kappa x2 + beta x2(t - tau_s) + a21 x1(t - tau1), kappa 0.5, beta -1, a12 1,
// tau1 = tau2 = 0.2: two states, three delays. The tutorial's Hopf plane a21 in [0, 4] x tau_s in
// [0, 10] as a 100 x 100 grid (a21 the fast axis, as a stability_map [grid] runs it), default
// band (4 x the natural frequency scale).
std::vector<Json> neuron_grid() {
  std::vector<Json> tables;
  for (int j = 0; j < 100; ++j)
    for (int i = 0; i < 100; ++i) {
      const double a21 = 0.04 * (i + 1), tau_s = 0.1 * (j + 1);
      tables.push_back({{"a0", {{-0.5, 0.0}, {0.0, -0.5}}},
                        {"delayed", {{{"delay_s", 0.2}, {"matrix", {{0.0, 0.0}, {a21, 0.0}}}},
                                     {{"delay_s", 0.2}, {"matrix", {{0.0, 1.0}, {0.0, 0.0}}}},
                                     {{"delay_s", tau_s}, {"matrix", {{-1.0, 0.0}, {0.0, -1.0}}}}}}});
    }
  return tables;
}

void BM_LinearDdeNeuronGrid(benchmark::State& state) { run_points<LinearDde>(state, neuron_grid(), 0.0); }
BENCHMARK(BM_LinearDdeNeuronGrid);

// MODELS.md G8: wheel 1450 rpm, work 55 rpm (Tw = 1.09 s; Tw / structural period = 74..333), the
// seven measured modes; a grid of wheel speed 1350..1550 rpm x contact stiffness 1e6..1e8 N/m
// (stable and chattering points). Band in Hz from the benchmark argument; 0 = the default band,
// 4 x 305.6 Hz = 1222 Hz (about 1330 work-lattice roots in the upper half plane).
std::vector<Json> g8_grid() {
  const double frequencies_hz[] = {67.56, 102.44, 184.08, 221.11, 255.01, 275.05, 305.60};
  Json modes = Json::array();
  for (double f : frequencies_hz)
    modes.push_back({{"frequency_hz", f}, {"damping_ratio", 0.05}, {"stiffness_n_per_m", 2.0e8}});
  std::vector<Json> tables;
  for (int i = 0; i < 8; ++i)
    for (double contact : {1e6, 1e7, 3e7, 1e8})
      tables.push_back({{"wheel_speed_rpm", 1350.0 + 200.0 * i / 7.0},
                        {"work_speed_rpm", 55.0},
                        {"contact_stiffness_n_per_m", contact},
                        {"wheel_wear_stiffness_n_per_m", 5.0e9},
                        {"work_removal_stiffness_n_per_m", 5.0e7},
                        {"modes", modes},
                        {"wheel_regeneration", true},
                        {"work_regeneration", true}});
  return tables;
}

void BM_PlungeRegenerativeG8(benchmark::State& state) {
  run_points<PlungeRegenerative>(state, g8_grid(), static_cast<double>(state.range(0)));
}
BENCHMARK(BM_PlungeRegenerativeG8)->Arg(0)->Arg(1222)->Arg(3000)->ArgName("band_hz")->Unit(benchmark::kMillisecond);

// The same G1 physics written once (docs/derived_stability.md): the derived route (Jacobian by
// AD, characteristic matrix of the delay-differential-algebraic system) on the same grid, against
// the hand-written fast path above at equal bands (issue 17: within 3x).
class DerivedPlunge final : public DerivedModel<test_support::G1Equations> {
 public:
  explicit DerivedPlunge(const ParamValues& values) : DerivedModel(equations_of(values.json())) {}
  static test_support::G1Equations equations_of(const Json& t) {
    test_support::G1Equations eqs;
    eqs.kc = t.at("contact_stiffness_n_per_m").get<double>();
    eqs.kg = t.at("wheel_wear_stiffness_n_per_m").get<double>();
    eqs.kw = t.at("work_removal_stiffness_n_per_m").get<double>();
    eqs.wheel_rpm = t.at("wheel_speed_rpm").get<double>();
    eqs.work_rpm = t.at("work_speed_rpm").get<double>();
    eqs.modes.clear();
    for (const Json& m : t.at("modes"))
      eqs.modes.push_back({m.at("frequency_hz").get<double>(), m.at("damping_ratio").get<double>(),
                           m.at("stiffness_n_per_m").get<double>()});
    return eqs;
  }
};

void BM_DerivedG8(benchmark::State& state) {
  run_points<DerivedPlunge>(state, g8_grid(), static_cast<double>(state.range(0)));
}
BENCHMARK(BM_DerivedG8)->Arg(1222)->Arg(3000)->ArgName("band_hz")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
