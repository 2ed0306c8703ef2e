// Feed planner timings (docs/performance.md, section "Feed planner"): a 3000-segment plan of
// MODELS.md P3 problem 2 (knots, inverse kinematics, integerisation, smoothing passes,
// certificate), the replay of all its machine states for the error analysis, the wheel
// interference check at every one of those states, the geometry analysis (interval branch and
// bound), the plan to the 5 um tolerance of the fillet part, the smoothing spline of a measured
// table (GCV), the evaluation of f, f', f'' (syntax tree against muparser with finite
// differences), and the controller export with its read-back.
#include <benchmark/benchmark.h>

#include <muParser.h>

#include <cmath>
#include <numbers>
#include <random>

#include "chatterlab/kinematics.hpp"
#include "planner/controller_export.hpp"
#include "planner/expression.hpp"
#include "planner/replay.hpp"
#include "planner/smoothing_spline.hpp"
#include "planner/tolerance.hpp"
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

// The geometry analysis of problem 2 on [0, 600] at the default resolution (what validation
// runs once per study).
void BM_GeometryAnalysisProblem2(benchmark::State& state) {
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  for (auto _ : state) {
    const GeometryAnalysis a = g->analyse(default_geometry_resolution_mm);
    benchmark::DoNotOptimize(a.max_concave_curvature_per_mm);
    state.counters["evaluations"] = static_cast<double>(a.evaluations);
    if (!a.singularities.empty()) state.SkipWithError("problem 2 has no singularity");
  }
}
BENCHMARK(BM_GeometryAnalysisProblem2)->Unit(benchmark::kMillisecond);

// f, f', f'' at one point: the syntax tree's forward derivatives (what the planner uses) and the
// previous route, seven muparser evaluations for 6th-order central differences.
void BM_EvaluateJetTree(benchmark::State& state) {
  const Expression e = Expression::parse(problem2);
  double x = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(e.jet(x));
    x = x < 600.0 ? x + 0.01 : 0.0;
  }
}
BENCHMARK(BM_EvaluateJetTree);

void BM_EvaluateMuparserSevenPointStencil(benchmark::State& state) {
  mu::Parser parser;
  double v = 0.0, x = 0.0;
  parser.DefineVar("x", &v);
  parser.SetExpr(problem2);
  const double h = 0.06;
  for (auto _ : state) {
    double f[7];
    for (int i = 0; i < 7; ++i) {
      v = x + (i - 3) * h;
      f[i] = parser.Eval();
    }
    const double d1 = (-f[0] + 9 * f[1] - 45 * f[2] + 45 * f[4] - 9 * f[5] + f[6]) / (60 * h);
    benchmark::DoNotOptimize(d1);
    x = x < 600.0 ? x + 0.01 : 0.0;
  }
}
BENCHMARK(BM_EvaluateMuparserSevenPointStencil);

// The fillet of docs/planner.md ("Plans to a tolerance") on [0, 300] with a 5 mm edge arc:
// segmentation, schedule, replay (and any refinement rounds) to 5 um.
void BM_PlanFilletToTolerance(benchmark::State& state) {
  auto kinematics = machine();
  auto g = expression_generatrix("130 - 8*exp(-((x-150)/10)^2)", 0.0, 300.0);
  const auto contact = wheel_contact({true, 40.0, 5.0, 180.0});
  for (auto _ : state) {
    const TolerancePlan p = plan_to_tolerance(*g, *kinematics, constraints(), ToleranceSettings{}, nullptr, contact);
    benchmark::DoNotOptimize(p.errors.total.max_abs_mm);
    if (!p.met) state.SkipWithError("tolerance not met");
  }
}
BENCHMARK(BM_PlanFilletToTolerance)->Unit(benchmark::kMillisecond);

// Smoothing spline by GCV of problem 2 measured every 2 mm (301 points) and every 0.2 mm
// (3001 points), 2 um noise.
void BM_CrossValidatedSpline(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<double> x, y;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (std::size_t i = 0; i < n; ++i) {
    x.push_back(600.0 * static_cast<double>(i) / static_cast<double>(n - 1));
    y.push_back(30 * std::exp(-x.back() / 400) * std::sin((x.back() + 25 * std::numbers::pi) / 100) + 130 + noise(rng));
  }
  for (auto _ : state) {
    const SmoothingSpline s = cross_validated_spline(x, y);
    benchmark::DoNotOptimize(s.lambda);
  }
}
BENCHMARK(BM_CrossValidatedSpline)->Arg(301)->Arg(3001)->Unit(benchmark::kMillisecond);

// program.ngc and steps.csv of the 3000-segment plan, written and read back (257,880 steps).
void BM_ControllerExport3000Segments(benchmark::State& state) {
  auto kinematics = machine();
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  const Schedule s = plan_feed(*g, *kinematics, constraints(), 0.2);
  for (auto _ : state) {
    const ControllerExport out = export_plan(s.plan, {}, 1e6);
    benchmark::DoNotOptimize(out.events.data());
    if (!out.exact()) state.SkipWithError("round trip not exact");
  }
}
BENCHMARK(BM_ControllerExport3000Segments)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
