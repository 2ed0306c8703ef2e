// Simulated time per CPU time of the dynamics engine (chatterlab/dynamics.hpp) on one core, on
// the path the `simulate` study kind takes: MODELS.md G1 with both regenerative surfaces and one
// structural mode, with the default integrator (ARKODE ERKStep, Dormand-Prince 5(4)) at rtol
// 1e-3, which still gives the 1 % root agreement for the growing G1 response (0.16 % off:
// PlungeTimeDomainAccuracy.SimulationAgreesWithTheRightmostRoot checks it at 1e-3; the engine
// default stays 1e-6 for decaying responses, docs/dynamics.md). Counter speedup = simulated
// seconds / CPU seconds of the benchmark thread. Numbers: docs/performance.md.
//
//   build/ci/tests/bench/dynamics_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>

#include "chatterlab/dynamics.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "models/torsional_coupling/torsional_coupling.hpp"

namespace {

using namespace chatterlab;

PlungeRegenerativeParameters one_mode(double frequency_hz) {
  PlungeRegenerativeParameters p;
  p.wheel_speed_rpm = 1450.0;
  p.work_speed_rpm = 55.0;
  p.contact_stiffness_n_per_m = 1e8;
  p.wheel_wear_stiffness_n_per_m = 1e9;
  p.work_removal_stiffness_n_per_m = 2e8;
  p.modes = {{frequency_hz, 0.05, 5e7}};
  return p;
}

// The G1 cases' tolerance (see the header comment).
constexpr double kG1RelativeTolerance = 1e-3;

void run(benchmark::State& state, const TimeDomainModel& model, SimulationSettings settings) {
  double simulated = 0.0, steps = 0.0;
  for (auto _ : state) {
    SimulationResult r = simulate(model, settings);
    benchmark::DoNotOptimize(r.displacement_m.data());
    simulated += r.end_time_s;
    steps += static_cast<double>(r.steps);
  }
  state.counters["speedup"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
  state.counters["steps_per_sim_s"] = steps / simulated;
}

// Linear (bilateral) contact, the growth-rate agreement setting; arg = mode frequency [Hz].
void G1BothSurfaces(benchmark::State& state) {
  PlungeTimeDomain model(one_mode(static_cast<double>(state.range(0))));
  SimulationSettings s;
  s.duration_s = 1.0;
  s.sample_rate_hz = 10000.0;
  s.one_sided_contact = false;
  s.divergence_limit_m = 1e6;
  s.relative_tolerance = kG1RelativeTolerance;
  run(state, model, s);
}
BENCHMARK(G1BothSurfaces)->Arg(250)->Arg(1000)->Unit(benchmark::kMillisecond);

// One-sided contact with infeed: contact events and restarts included.
void G1OneSidedContact(benchmark::State& state) {
  PlungeTimeDomain model(one_mode(250.0));
  SimulationSettings s;
  s.duration_s = 2.0;
  s.sample_rate_hz = 10000.0;
  s.infeed_rate_m_per_s = 1e-5;
  s.relative_tolerance = kG1RelativeTolerance;
  run(state, model, s);
}
BENCHMARK(G1OneSidedContact)->Unit(benchmark::kMillisecond);

}  // namespace
namespace {
// One chain at a time (G3 wheel-only; workpiece-only), for comparison of the cost per chain.
void G1OneChain(benchmark::State& state) {
  auto p = one_mode(250.0);
  (state.range(0) == 0 ? p.work_regeneration : p.wheel_regeneration) = false;
  PlungeTimeDomain model(p);
  SimulationSettings s;
  s.duration_s = 1.0;
  s.sample_rate_hz = 10000.0;
  s.one_sided_contact = false;
  s.divergence_limit_m = 1e6;
  s.relative_tolerance = kG1RelativeTolerance;
  state.SetLabel(state.range(0) == 0 ? "wheel only" : "work only");
  run(state, model, s);
}
BENCHMARK(G1OneChain)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// G5 at its example parameters (speeds as states, one-sided contact, infeed 15 um/s, 1 um random
// initial waviness); arg = -log10(rtol): 6 (the engine default) and 4 (the force rms and the end
// state agree with 1e-6 to 1e-4 relative: docs/performance.md).
void G5Torsional(benchmark::State& state) {
  Json params = TorsionalCoupling::info().example_params;
  TorsionalCoupling plugin{ParamValues(params)};
  auto model = plugin.time_domain();
  SimulationSettings s;
  s.duration_s = 0.5;
  s.sample_rate_hz = 10000.0;
  s.infeed_rate_m_per_s = 15e-6;
  s.initial_waviness_m = 1e-6;
  s.relative_tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  run(state, *model, s);
}
BENCHMARK(G5Torsional)->Arg(6)->Arg(4)->Unit(benchmark::kMillisecond);
}  // namespace

BENCHMARK_MAIN();
