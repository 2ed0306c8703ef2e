// Feed planner timings (docs/performance.md, section "Feed planner"): a 3000-segment plan of
// MODELS.md P3 problem 2 (knots, inverse kinematics, integerisation, smoothing passes,
// certificate), the replay of all its machine states for the error analysis, and the wheel
// interference check at every one of those states.
#include <benchmark/benchmark.h>

#include "chatterlab/kinematics.hpp"
#include "planner/replay.hpp"
#include "planner/setup.hpp"
#include "planner/wheel_limits.hpp"
#include "planner/scheduler.hpp"

namespace {

using namespace chatterlab;
using namespace chatterlab::planner;

std::unique_ptr<Kinematics> machine() {
  return kinematics_registry().at("three_table_revolution").create(ParamValues(p2_machine_params()));
}

FeedConstraints constraints() { return p2_constraints(); }

constexpr const char* problem2 = "30*exp(-x/400)*sin((x + 25*_pi)/100) + 130";

void BM_Plan3000Segments(benchmark::State& state) {
  auto kinematics = machine();
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  for (auto _ : state) {
    Schedule s = plan_feed(*g, *kinematics, constraints(), 0.2);
    benchmark::DoNotOptimize(s.plan.segments.data());
    if (!s.certificate.ok || s.plan.segments.size() != 3000) state.SkipWithError("bad plan");
  }
}
BENCHMARK(BM_Plan3000Segments)->Unit(benchmark::kMillisecond);

void BM_ReplayErrors3000Segments(benchmark::State& state) {
  auto kinematics = machine();
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  const Schedule s = plan_feed(*g, *kinematics, constraints(), 0.2);
  for (auto _ : state) {
    ProfileErrors e = replay_errors(s, *g, *kinematics);
    benchmark::DoNotOptimize(e.total.max_abs_mm);
  }
}
BENCHMARK(BM_ReplayErrors3000Segments)->Unit(benchmark::kMillisecond);

void BM_InterferenceAlongPlan3000Segments(benchmark::State& state) {
  auto kinematics = machine();
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  const Schedule s = plan_feed(*g, *kinematics, constraints(), 0.2);
  const WheelSection wheel{true, 40.0, 20.0, 180.0};  // the problem 2 study's profiled wheel
  for (auto _ : state) {
    const Interference hit = check_interference_along_plan(s, *g, *kinematics, wheel);
    benchmark::DoNotOptimize(hit.depth_mm);
    if (hit.states_checked < 250000 || hit.contacts_with_interference != 0) state.SkipWithError("bad check");
  }
}
BENCHMARK(BM_InterferenceAlongPlan3000Segments)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
