// Simulated time per CPU time of the dynamics engine (chatterlab/dynamics.hpp) on one core, on
// the path the `simulate` study kind takes. Two routes (docs/dynamics.md): the fixed-step engine
// (the default: exact exponential propagation of G1's linear form, Runge-Kutta for G5) and the
// adaptive ARKODE reference.
// - G8Chatter60s: issue 25's case, studies/simulate_g8_chatter.toml stretched to 60 s (seven
//   modes, one-sided contact, infeed, random initial surfaces), 1 kHz and 10 kHz output, both
//   routes; the fixed-step cases report their agreement with the reference at rtol 1e-8 over the
//   study's growth phase (growth_err_pct, freq_err_pct, surface_err_pct).
// - G1BothSurfaces: G1 with one mode (250 .. 1000 Hz), bilateral contact, growing: the
//   fixed-step engine at its defaults, and ARKODE at the growth-rate settings of
//   plunge_time_domain.hpp (apply_growth_rate_settings: rtol 1e-2, largest step 1/(3 f_max), 8
//   surface samples per wave of f_max); both report their accuracy (err_root_pct against the
//   certified rightmost root, err_ref_pct against a converged ARKODE run).
// - G1OneSidedContact, G5Torsional: events and restarts, speeds as states; both routes.
// Counter speedup = simulated seconds / CPU seconds of the benchmark thread. Numbers:
// docs/performance.md.
//
//   build/ci/tests/bench/dynamics_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/roots.hpp"
#include "dynamics/route_agreement.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "models/torsional_coupling/torsional_coupling.hpp"

namespace {

using namespace chatterlab;

// The tests' reference case (plunge_time_domain.hpp) with its mode at frequency_hz.
PlungeRegenerativeParameters one_mode(double frequency_hz) {
  PlungeRegenerativeParameters p = reference_g1_case();
  p.modes = {{frequency_hz, 0.05, 5e7}};
  return p;
}

// Linear (bilateral) contact for 1 s at 10 kHz, never stopped as diverging: a growing run.
SimulationSettings bilateral_one_second() {
  SimulationSettings s;
  s.duration_s = 1.0;
  s.sample_rate_hz = 10000.0;
  s.one_sided_contact = false;
  s.divergence_limit_m = 1e6;
  return s;
}

// One-sided contact (events, restarts, a bounded response rather than a growth rate): rtol 1e-3.
constexpr double kOneSidedRelativeTolerance = 1e-3;

// The timed loop: totals over every iteration, and the first status other than "completed".
struct RunTotals {
  double simulated_s = 0.0, steps = 0.0, rhs_evaluations = 0.0, contact_events = 0.0;
  std::string failure;
};

RunTotals timed_runs(benchmark::State& state, const TimeDomainModel& model, const SimulationSettings& settings) {
  RunTotals totals;
  for (auto _ : state) {
    SimulationResult r = simulate(model, settings);
    benchmark::DoNotOptimize(r.displacement_m.data());
    totals.simulated_s += r.end_time_s;
    totals.steps += static_cast<double>(r.steps);
    totals.rhs_evaluations += static_cast<double>(r.rhs_evaluations);
    totals.contact_events += static_cast<double>(r.contact_events);
    if (r.status != "completed" && totals.failure.empty()) totals.failure = r.status;
  }
  state.counters["speedup"] = benchmark::Counter(totals.simulated_s, benchmark::Counter::kIsRate);
  state.counters["steps_per_sim_s"] = totals.steps / totals.simulated_s;
  return totals;
}

void run(benchmark::State& state, const TimeDomainModel& model, SimulationSettings settings) {
  const RunTotals totals = timed_runs(state, model, settings);
  state.counters["rhs_per_step"] = totals.rhs_evaluations / totals.steps;
}

// Settings overridable from the environment for tolerance studies (not used by the recorded
// figures): CHAT_RTOL, CHAT_SPW (surface samples per wave), CHAT_MSPW (max steps per wave);
// CHAT_FIT_START_S moves the accuracy counters' fit window (default 0.5 s).
void environment_overrides(SimulationSettings& s) {
  if (const char* e = std::getenv("CHAT_RTOL")) s.relative_tolerance = std::atof(e);
  if (const char* e = std::getenv("CHAT_SPW")) s.samples_per_wave = std::atof(e);
  if (const char* e = std::getenv("CHAT_MSPW")) s.max_steps_per_wave = std::atof(e);
  if (const char* e = std::getenv("CHAT_FSPW")) s.fixed_steps_per_wave = std::atof(e);
}

// Accuracy of the benchmark's own settings, outside the timed loop: the growth rate fitted over
// two work revolutions after the start-up, 0.5 .. 0.5 + 2 Tw s (whole work revolutions: the work
// lattice's roots 1/Tw apart make the envelope beat with the work period), against (1) the
// certified rightmost root of D(s) (eq 2-16) and (2) a converged reference run (rtol 1e-8, 4x
// denser surfaces and steps) fitted over the same window, i.e. the integration error alone.
void accuracy_counters(benchmark::State& state, const PlungeRegenerativeParameters& p,
                       const SimulationSettings& s) {
  PlungeTimeDomain model(p);
  PlungeCharacteristic characteristic(p);
  RootSearchOptions options;
  options.max_frequency_hz = 3000.0;
  const double root = find_rightmost_root(characteristic, options).root.real();
  const char* start_override = std::getenv("CHAT_FIT_START_S");  // for studies of the window
  const double start_s = start_override ? std::atof(start_override) : 0.5;
  const double end_s = start_s + 2.0 * 60.0 / p.work_speed_rpm;
  auto growth = [&](SimulationSettings settings) {
    settings.duration_s = end_s;
    SimulationResult r = simulate(model, settings);
    return fit_envelope(r.t_s, r.displacement_m, start_s, end_s).growth_rate_per_s;
  };
  const double fitted = growth(s), converged = growth(converged_reference_settings(s));
  state.counters["growth_per_s"] = fitted;
  state.counters["err_root_pct"] = 100.0 * (fitted / root - 1.0);
  state.counters["err_ref_pct"] = 100.0 * (fitted / converged - 1.0);
  state.counters["ref_vs_root_pct"] = 100.0 * (converged / root - 1.0);
}

// Linear (bilateral) contact, growing; args: mode frequency [Hz], route (0 the fixed-step engine
// at its defaults, 1 ARKODE at the growth-rate settings).
void G1BothSurfaces(benchmark::State& state) {
  const PlungeRegenerativeParameters p = one_mode(static_cast<double>(state.range(0)));
  PlungeTimeDomain model(p);
  SimulationSettings s = bilateral_one_second();
  if (state.range(1) == 1) apply_growth_rate_settings(s);
  environment_overrides(s);
  state.SetLabel(to_string(s.integrator));
  run(state, model, s);
  if (!std::getenv("CHAT_NO_ACCURACY")) accuracy_counters(state, p, s);
}
BENCHMARK(G1BothSurfaces)
    ->ArgsProduct({{250, 500, 750, 1000}, {0, 1}})
    ->ArgNames({"mode_hz", "reference"})
    ->Unit(benchmark::kMillisecond);

// One-sided contact with infeed: contact events and restarts included; arg = route (0 fixed
// step, 1 ARKODE at rtol 1e-3).
void G1OneSidedContact(benchmark::State& state) {
  PlungeTimeDomain model(one_mode(250.0));
  SimulationSettings s;
  s.duration_s = 2.0;
  s.sample_rate_hz = 10000.0;
  s.infeed_rate_m_per_s = 1e-5;
  s.integrator = state.range(0) == 0 ? TimeIntegrator::fixed_step : TimeIntegrator::explicit_runge_kutta;
  s.relative_tolerance = kOneSidedRelativeTolerance;
  state.SetLabel(to_string(s.integrator));
  run(state, model, s);
}
BENCHMARK(G1OneSidedContact)->Arg(0)->Arg(1)->ArgName("reference")->Unit(benchmark::kMillisecond);

}  // namespace
namespace {
// One chain at a time (G3 wheel-only; workpiece-only), for comparison of the cost per chain.
void G1OneChain(benchmark::State& state) {
  auto p = one_mode(250.0);
  (state.range(0) == 0 ? p.work_regeneration : p.wheel_regeneration) = false;
  PlungeTimeDomain model(p);
  SimulationSettings s = bilateral_one_second();
  apply_growth_rate_settings(s);
  state.SetLabel(state.range(0) == 0 ? "wheel only" : "work only");
  run(state, model, s);
}
BENCHMARK(G1OneChain)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// G5 at its example parameters (speeds as states, one-sided contact, infeed 15 um/s, 1 um random
// initial waviness); arg = -log10(rtol) of the ARKODE route: 6 (its default) and 4 (the force
// rms and the end state agree with 1e-6 to 1e-4 relative: docs/models/torsional_coupling.md); 0 = the
// fixed-step engine (Runge-Kutta).
void G5Torsional(benchmark::State& state) {
  Json params = TorsionalCoupling::info().example_params;
  TorsionalCoupling plugin{ParamValues(params)};
  auto model = plugin.time_domain();
  SimulationSettings s;
  s.duration_s = 0.5;
  s.sample_rate_hz = 10000.0;
  s.infeed_rate_m_per_s = 15e-6;
  s.initial_waviness_m = 1e-6;
  if (state.range(0) > 0) {
    s.integrator = TimeIntegrator::explicit_runge_kutta;
    s.relative_tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  }
  state.SetLabel(to_string(s.integrator));
  run(state, *model, s);
}
BENCHMARK(G5Torsional)->Arg(0)->Arg(6)->Arg(4)->Unit(benchmark::kMillisecond);
// ------------------------------------------------------------------ G8, 60 s (issue 25)

// The study's [simulation]: plunge infeed 15 um/s from rest, 1 um random initial surfaces
// (seed 7), one-sided contact, snapshots at 2 s and the end, divergence limit 0.01 m.
SimulationSettings g8_settings(double duration_s, double sample_rate_hz, TimeIntegrator integrator) {
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = sample_rate_hz;
  s.infeed_rate_m_per_s = 15e-6;
  s.disturbance = {0.0, 0.0};
  s.initial_waviness_m = 1e-6;
  s.seed = 7;
  s.snapshot_times_s = {2.0, duration_s};
  s.divergence_limit_m = 0.01;
  s.integrator = integrator;
  return s;
}

// The engine on the 60 s case; args: output sample rate [Hz], route (0 fixed step, 1 the ARKODE
// reference at its default rtol 1e-6). Counters: speedup (simulated s per CPU s), steps and
// contact events per simulated s; outside the timed loop, for the fixed-step route, its accuracy
// against the reference at rtol 1e-8 over the study's growth phase (3 s: growth fitted over
// 1.2..3.0 s, dominant frequency there, work surface at the 2 s snapshot).
void G8Chatter60s(benchmark::State& state) {
  const double rate = static_cast<double>(state.range(0));
  const TimeIntegrator integrator =
      state.range(1) == 0 ? TimeIntegrator::fixed_step : TimeIntegrator::explicit_runge_kutta;
  PlungeTimeDomain model(g8_grinder());
  SimulationSettings s = g8_settings(60.0, rate, integrator);
  environment_overrides(s);
  state.SetLabel(to_string(integrator));
  const RunTotals totals = timed_runs(state, model, s);
  if (!totals.failure.empty()) state.SkipWithError(totals.failure.c_str());
  state.counters["events_per_sim_s"] = totals.contact_events / totals.simulated_s;
  if (integrator != TimeIntegrator::fixed_step || std::getenv("CHAT_NO_ACCURACY")) return;
  SimulationSettings reference = g8_settings(3.0, rate, TimeIntegrator::explicit_runge_kutta);
  if (const char* e = std::getenv("CHAT_SPW")) reference.samples_per_wave = std::atof(e);
  reference.relative_tolerance = 1e-8;
  const SimulationResult a = simulate(model, reference);
  SimulationSettings fixed = g8_settings(3.0, rate, TimeIntegrator::fixed_step);
  environment_overrides(fixed);
  const SimulationResult b = simulate(model, fixed);
  const dynamics_detail::RouteAgreement agreement = dynamics_detail::route_agreement(a, b, 1.2, 3.0);
  state.counters["growth_err_pct"] = 100.0 * agreement.growth_error;
  state.counters["freq_err_pct"] = 100.0 * agreement.frequency_error;
  state.counters["surface_err_pct"] = 100.0 * agreement.surface_error;
}
BENCHMARK(G8Chatter60s)
    ->Args({1000, 0})
    ->Args({10000, 0})
    ->Args({1000, 1})
    ->Args({10000, 1})
    ->ArgNames({"output_hz", "reference"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
