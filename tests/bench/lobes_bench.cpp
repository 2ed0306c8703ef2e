// Lobe diagrams as the stability_lobes study kind traces them (plugins/study_kinds/stability_lobes/
// lobe_tracer.hpp): MODELS.md G1 with the seven G8 machine modes at the G8 delays (wheel 1450 rpm,
// Tg = 41 ms; work 25..85 rpm, Tw = 2.4..0.7 s), the critical contact stiffness over N work speeds
// (issue 18's target: 200 speeds in under 10 s on 2 cores). The tracer spreads its speeds over the
// OpenMP threads (OMP_NUM_THREADS). Numbers: docs/performance.md.
//
//   OMP_NUM_THREADS=2 build/ci/tests/bench/lobes_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <vector>

#include "chatterlab/kit/model.hpp"
#include "study_kinds/stability_lobes/lobe_tracer.hpp"

namespace {

using namespace chatterlab;

std::unique_ptr<Model> g8(double contact_stiffness_n_per_m, double work_speed_rpm, double wheel_speed_rpm) {
  const double f[] = {67.56, 102.44, 184.08, 221.11, 255.01, 275.05, 305.60};
  const double k[] = {5.53e7, 1.27e8, 4.11e8, 5.93e8, 7.88e8, 9.17e8, 1.132e9};
  Json modes = Json::array();
  for (int i = 0; i < 7; ++i) modes.push_back({{"frequency_hz", f[i]}, {"damping_ratio", 0.03}, {"stiffness_n_per_m", k[i]}});
  return kit::build_model({{"type", "plunge_regenerative"},
                           {"wheel_speed_rpm", wheel_speed_rpm},
                           {"work_speed_rpm", work_speed_rpm},
                           {"contact_stiffness_n_per_m", contact_stiffness_n_per_m},
                           {"wheel_wear_stiffness_n_per_m", 6.3e10},
                           {"work_removal_stiffness_n_per_m", 2.0e7},
                           {"modes", modes}});
}

// Critical kc over state.range(0) work speeds from 25 to 85 rpm (the default study's range).
void BM_LobesG8WorkSpeed(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  std::vector<double> speeds;
  for (int i = 0; i < n; ++i) speeds.push_back(25.0 + 60.0 * i / (n - 1));
  lobes::TraceSettings settings;
  settings.parameter_min = 1e5;
  settings.parameter_max = 1e9;
  settings.max_frequency_hz = 1250.0;
  double lobes_traced = 0.0, limits = 0.0;
  for (auto _ : state) {
    const lobes::LobeDiagram d = lobes::trace_lobes([](double kc, double v) { return g8(kc, v, 1450.0); }, speeds, settings);
    lobes_traced = static_cast<double>(d.lobes.size());
    limits = 0.0;
    for (const auto& at : d.at) limits += at.limit ? 1.0 : 0.0;
    benchmark::DoNotOptimize(d.envelope.data());
  }
  state.counters["speeds"] = n;
  state.counters["lobes"] = lobes_traced;
  state.counters["speeds_with_limit"] = limits;
}
BENCHMARK(BM_LobesG8WorkSpeed)->Arg(50)->Arg(200)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1)->Repetitions(3);

}  // namespace

BENCHMARK_MAIN();
