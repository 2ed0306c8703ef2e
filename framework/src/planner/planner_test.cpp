// Feed planner (MODELS.md P): generatrix derivatives against analytic ones, smoothness checks, the
// P8 first-segment rates, certified schedules (problems 1 and 2 of P3 in 3000 s, error <= 5 um),
// smoothness at reversals, edge-radius limit against a known curvature, wear dwell of the sweep
// laws, the saved-plan reader, and bad-input messages.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/planner/plan.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "planner/plan_io.hpp"
#include "planner/replay.hpp"
#include "planner/setup.hpp"
#include "planner/scheduler.hpp"
#include "planner/wear.hpp"
#include "unit/planner_test_support.hpp"
#include "planner/wheel_limits.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::planner {
namespace {

namespace fs = std::filesystem;
using chatterlab::testing::TempDir;

constexpr const char* problem1 = "-7/18000*(600 - x)^2 + 0.45*(600 - x)";
constexpr const char* problem2 = "30*exp(-x/400)*sin((x + 25*_pi)/100) + 130";

std::unique_ptr<Kinematics> seed_machine() {
  return kinematics_registry().at("three_table_revolution").create(ParamValues(p2_machine_params()));
}

FeedConstraints seed_constraints() { return p2_constraints(); }

// A disc tool's deviation is the signed distance from the profile to its centre minus its
// radius: centres placed a known distance along the exact normal of problem 1's parabola (and a
// circle, where the distance to the centre of curvature is known in closed form) read back to
// 1e-9 mm, where the first-order foot point at the centre's own x errs by millimetres.
TEST(Generatrix, DiscToolDeviationIsTheDistanceToItsCentreMinusItsRadius) {
  auto parabola = expression_generatrix(problem1, 0.0, 600.0);
  for (const double x0 : {0.0, 150.0, 420.0, 600.0})
    for (const double offset : {-0.01, 0.0, 0.003, 0.5}) {
      const GeneratrixValue v = parabola->evaluate(x0);
      const double norm = std::sqrt(1.0 + v.d1 * v.d1), distance = 200.0 + offset;
      const ToolInPart disc{x0 - distance * v.d1 / norm, v.f + distance / norm, 200.0};
      EXPECT_NEAR(tool_deviation_mm(disc, *parabola), offset, 1e-9) << "x0 = " << x0;
      const GeneratrixValue at_centre = parabola->evaluate(disc.x_mm);
      if (x0 == 420.0) {  // what the first-order foot point would say: millimetres off
        EXPECT_GT(std::abs((disc.y_mm - at_centre.f) / std::sqrt(1.0 + at_centre.d1 * at_centre.d1) - 200.0 - offset), 1.0);
      }
    }
  // A circle of radius 500 centred at (300, -400): a disc centred at the circle's centre + (0, 700)
  // stands 700 - 500 - R off it.
  auto circle = expression_generatrix("sqrt(500^2 - (x - 300)^2) - 400", 100.0, 500.0);
  EXPECT_NEAR(tool_deviation_mm({300.0 + 700.0 * std::sin(0.3), -400.0 + 700.0 * std::cos(0.3), 150.0}, *circle),
              50.0, 1e-9);
  EXPECT_NEAR(tool_deviation_mm({300.0, 100.002, 0.0}, *circle), 0.002, 1e-12);  // a point tool
}

TEST(Generatrix, DerivativesMatchAnalyticOnes) {
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  for (double x : {0.0, 54.04, 123.4, 368.2, 600.0}) {
    const double e = std::exp(-x / 400), arg = (x + 25 * std::numbers::pi) / 100;
    const double f = 30 * e * std::sin(arg) + 130;
    const double d1 = 30 * e * (-std::sin(arg) / 400 + std::cos(arg) / 100);
    const double d2 = 30 * e * (std::sin(arg) / 160000 - 2 * std::cos(arg) / 40000 - std::sin(arg) / 10000);
    const GeneratrixValue v = g->evaluate(x);
    EXPECT_NEAR(v.f, f, 1e-13 * f);  // muparser rounds differently
    EXPECT_NEAR(v.d1, d1, 1e-10) << x;
    EXPECT_NEAR(v.d2, d2, 1e-8 * std::abs(d2) + 1e-10) << x;
  }
  auto p = expression_generatrix(problem1, 0.0, 600.0);
  EXPECT_NEAR(p->evaluate(0.0).d1, 1.0 / 60, 1e-11);  // seed 000: a1 = 1/60
  EXPECT_NEAR(p->evaluate(300.0).d2, -7.0 / 9000, 1e-10);
}

TEST(Generatrix, SplineReproducesACubicInsideAndIsNatural) {
  std::vector<double> x, y;
  for (int i = 0; i <= 20; ++i) {
    x.push_back(i * 5.0);
    y.push_back(100 + 0.1 * x.back());
  }
  auto s = spline_generatrix(x, y);
  EXPECT_NEAR(s->evaluate(37.5).f, 103.75, 1e-12);
  EXPECT_NEAR(s->evaluate(37.5).d1, 0.1, 1e-12);
  EXPECT_NEAR(s->evaluate(0.0).d2, 0.0, 1e-12);
  EXPECT_THROW(spline_generatrix({0, 1, 1}, {1, 2, 3}), std::invalid_argument);
}

std::string smooth_error(const std::string& expression, double a, double b) {
  try {
    check_smooth(*expression_generatrix(expression, a, b));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Generatrix, DiscontinuitiesKinksAndDomainAreReported) {
  EXPECT_EQ(smooth_error(problem2, 0, 600), "");
  const std::string jump = smooth_error("x < 300 ? 100 : 103", 0, 600);
  EXPECT_NE(jump.find("f jumps by 3"), std::string::npos) << jump;
  EXPECT_NE(jump.find("at x = 300"), std::string::npos) << jump;
  // Kinks on and off the old 4096-cell check grid (600/4096 = 0.146 mm): all found (geometry_test).
  for (const double c : {300.0, 250.0}) {
    const std::string kink = smooth_error(fmt::format("100 + abs(x - {})", c), 0, 600);
    EXPECT_NE(kink.find("slope f' jumps by 2"), std::string::npos) << kink;
    const auto at = kink.find("at x = ");
    ASSERT_NE(at, std::string::npos) << kink;
    EXPECT_NEAR(std::stod(kink.substr(at + 7)), c, 1e-6) << kink;
  }
  const std::string domain = smooth_error("sqrt(x)", 0, 100);
  EXPECT_NE(domain.find("not finite"), std::string::npos) << domain;
  EXPECT_THROW(expression_generatrix("x +* 2", 0, 1), std::invalid_argument);
}

TEST(ThreeTableRevolution, ForwardInvertsInverse) {
  auto machine = seed_machine();
  std::vector<double> q(3);
  for (const ToolContact contact : {ToolContact{}, ToolContact{7.5, 0, 0}, ToolContact{3.0, 0.5, 0.2}}) {
    machine->inverse({123.0, 140.0, 1.0, -0.3}, contact, q);
    const ToolInPart t = machine->forward(q, contact);
    EXPECT_NEAR(t.x_mm, 123.0, 1e-12);
    EXPECT_NEAR(t.y_mm, 140.0, 1e-12);
  }
  machine->inverse({123.0, 140.0, 1.0, -0.3}, {}, q);
  EXPECT_NEAR(q[2], 90.0, 1e-12);  // z_g = -R f'
  // Tilting the contact by phi turns the upper table by -phi: tan theta = tan(atan f' - phi).
  machine->inverse({123.0, 140.0, 1.0, -0.3}, {0, 0, 0.1}, q);
  EXPECT_NEAR(q[2], -300.0 * std::tan(std::atan(-0.3) - 0.1), 1e-12);
  EXPECT_THROW(machine->inverse({0, 1, 0.0, 1.0}, {}, q), std::domain_error);
}

// MODELS.md P8: constant axial speed 0.2 mm/s, 1 s segments: first rates -54, 12, 14 (problem 1)
// and -27, 40, 55 (problem 2). Both from the scheduler's first segment.
TEST(FeedPlanner, FirstSegmentRatesOfSeed000) {
  auto machine = seed_machine();
  const std::pair<const char*, std::vector<std::int64_t>> cases[] = {{problem1, {-54, 12, 14}},
                                                                      {problem2, {-27, 40, 55}}};
  for (const auto& [expression, rates] : cases) {
    auto g = expression_generatrix(expression, 0.0, 600.0);
    // Uniform knots: every segment is the seed's 0.2 mm in 1 s.
    const Schedule uniform = plan_feed(*g, *machine, seed_constraints(), 0.2, nullptr, false);
    EXPECT_EQ(uniform.plan.segments.front().pulses, rates) << expression;
    EXPECT_NEAR(uniform.plan.segments.front().duration_s, 1.0, 1e-9);
    EXPECT_NEAR(uniform.plan.total_time_s(), 3000.0, 1e-6);
    // Chosen knots leave the first one in place.
    const Schedule s = plan_feed(*g, *machine, seed_constraints(), 0.2);
    EXPECT_EQ(s.plan.segments.front().pulses, rates) << expression;
    EXPECT_NEAR(s.plan.segments.front().duration_s, 1.0, 1e-9);
  }
}

TEST(FeedPlannerAccuracy, ProblemsOneAndTwoIn3000sWithin5um) {
  auto machine = seed_machine();
  for (const char* expression : {problem1, problem2}) {
    auto g = expression_generatrix(expression, 0.0, 600.0);
    const Schedule s = plan_feed(*g, *machine, seed_constraints(), 0.2);
    EXPECT_TRUE(s.certificate.ok) << (s.certificate.violations.empty() ? "" : s.certificate.violations[0]);
    EXPECT_LE(s.plan.total_time_s(), 3000.0 + 1e-6);
    EXPECT_NEAR(s.lower_bound_s, 3000.0, 1e-6);
    EXPECT_LE(s.certificate.max_position_drift_steps, 0.5 + 1e-9);
    for (double rate : s.certificate.max_pulse_rate_hz) EXPECT_LE(rate, 100.0);
    const ProfileErrors e = replay_errors(s, *g, *machine);
    EXPECT_LE(e.total.max_abs_mm, 0.005) << expression;
    // Linearisation over 0.2 mm chords is far below a step; quantisation dominates.
    EXPECT_LT(e.linearisation.max_abs_mm, 1e-4);
    EXPECT_GT(e.quantisation.max_abs_mm, 1e-4);
  }
}

// Slow motors make the pulse-rate bound bind where the slope is steep, and a triangle wear sweep
// turns the lower table's rate abruptly at each turn: the plan must brake and speed up within the
// smoothness rule, and stay certified after integerisation.
TEST(FeedPlanner, SmoothnessBindsAndIsCertified) {
  Json slow = p2_machine_params();
  slow["max_pulse_rate_hz"] = 60.0;
  auto machine = kinematics_registry().at("three_table_revolution").create(ParamValues(slow));
  auto g = expression_generatrix(problem2, 0.0, 600.0);
  const Schedule s =
      plan_feed(*g, *machine, seed_constraints(), 0.2, sweep_function({"triangle", 10.0, 80.0, 5}, 0.0));
  EXPECT_TRUE(s.certificate.ok) << (s.certificate.violations.empty() ? "" : s.certificate.violations[0]);
  EXPECT_GT(s.plan.total_time_s(), s.lower_bound_s + 10.0);  // smoothness costs time here
  EXPECT_GT(s.lower_bound_s, 3000.0);                 // the rate bound binds somewhere
  EXPECT_GT(s.certificate.reversals, 0u);             // the lower table reverses (P8)
  EXPECT_NEAR(s.certificate.max_relative_rate_change, 0.1, 1e-6);
  // Greatest solution: shortening any binding segment by 1 % breaks a constraint.
  Schedule faster = s;
  std::size_t broken = 0, tried = 0;
  for (std::size_t k = 1; k + 1 < s.plan.segments.size(); k += 97) {
    faster.plan.segments[k].duration_s *= 0.99;
    broken += certify(faster, seed_constraints()).ok ? 0 : 1;
    ++tried;
    faster.plan.segments[k].duration_s = s.plan.segments[k].duration_s;
  }
  EXPECT_EQ(broken, tried);
}

TEST(FeedPlanner, PeriodicScheduleAlsoLinksTheLastSegmentToTheFirst) {
  // One motor, 100 pulses per segment, the third segment capped at 0.1 segments/s (10 pulses/s).
  // delta = 0.1, f_ss = 10: segment 1 may run at 10 + 10 = 20 pulses/s, segment 0 (before it) at
  // max(20 / 0.9, 20 + 10) = 30; periodic (segment 0 also follows segment 2) only at 20.
  FeedPlan plan;
  plan.motors = {{"c", 1.0, 100.0, ""}};
  const std::vector<std::vector<double>> targets{{0.0}, {100.0}, {200.0}, {300.0}};
  quantise_targets(plan, targets);
  const std::vector<double> cap{1e9, 1e9, 0.1};
  const RateRules rules{0.1, 10.0};
  FeedPlan open = plan;
  time_optimal_durations(open, cap, rules, false);
  EXPECT_NEAR(100.0 / open.segments[0].duration_s, 30.0, 1e-9);
  EXPECT_NEAR(100.0 / open.segments[1].duration_s, 20.0, 1e-9);
  EXPECT_NEAR(100.0 / open.segments[2].duration_s, 10.0, 1e-9);
  time_optimal_durations(plan, cap, rules, true);
  EXPECT_NEAR(100.0 / plan.segments[0].duration_s, 20.0, 1e-9);
  EXPECT_TRUE(certify_motor_rules(plan, targets, rules, true).ok);
  EXPECT_TRUE(certify_motor_rules(open, targets, rules, false).ok);
  const Certificate broken = certify_motor_rules(open, targets, rules, true);
  ASSERT_FALSE(broken.ok);
  EXPECT_NE(broken.violations.front().find("segments 2-0"), std::string::npos) << broken.violations.front();
  // The relaxation ignores smoothness: 1 + 1 + 10 s.
  EXPECT_NEAR(relaxed_time_bound(plan, cap, targets), 12.0, 1e-9);
}

TEST(WheelLimits, EdgeRadiusIsTheConcaveRadiusOfCurvature) {
  // y = 100 + x^2 / 1000: radius of curvature 500 mm at x = 0, larger elsewhere.
  auto g = expression_generatrix("100 + x^2/1000", -50.0, 50.0);
  const EdgeRadiusLimit limit = largest_edge_radius(*g);
  EXPECT_NEAR(limit.radius_mm, 500.0, 0.5);
  EXPECT_NEAR(limit.x_mm, 0.0, 0.1);
  // A convex part limits nothing.
  EXPECT_TRUE(std::isinf(largest_edge_radius(*expression_generatrix(problem1, 0, 600)).radius_mm));
  // A flat face of width a on that valley cuts a^2/(8 rho) deep: 20 mm -> 0.1 mm.
  WheelSection face;
  face.thickness_mm = 20.0;
  const Interference hit = check_interference(*g, face, {0.0});
  EXPECT_NEAR(hit.depth_mm, 0.1, 2e-3);
  EXPECT_NEAR(std::abs(hit.x_mm), 10.0, 0.05);  // the face's ends dig in
  // The wheel's own limit: an arc of opening alpha fits the face width a: r <= a / (2 sin(alpha/2)).
  WheelSection arc{true, 40.0, 20.0, 180.0};
  EXPECT_NEAR(wheel_geometry_edge_radius_mm(arc), 20.0, 1e-12);
  arc.edge_angle_deg = 60.0;
  EXPECT_NEAR(wheel_geometry_edge_radius_mm(arc), 40.0, 1e-12);
}

// The quantised plan replayed pulse by pulse with the wheel section (MODELS.md P5).
Interference along_plan(const Generatrix& g, const WheelSection& wheel, Schedule* out = nullptr) {
  auto machine = seed_machine();
  Schedule s = plan_feed(g, *machine, seed_constraints(), 0.2);
  const Interference hit = check_interference_along_plan(s, g, *machine, wheel);
  if (out) *out = std::move(s);
  return hit;
}

TEST(WheelLimits, InterferenceAlongThePlanFindsTooLargeWheels) {
  // Valley of radius of curvature 500 mm at x = 0: a 20 mm face cuts 20^2 / (8 x 500) = 0.1 mm.
  auto valley = expression_generatrix("100 + x^2/1000", -25.0, 25.0);
  WheelSection face;
  face.thickness_mm = 20.0;
  Schedule s;
  const Interference hit = along_plan(*valley, face, &s);
  EXPECT_NEAR(hit.depth_mm, 0.1, 3e-3);
  EXPECT_NEAR(hit.contact_x_mm, 0.0, 10.0);  // nearly the same everywhere; deepest near x = 0
  EXPECT_GT(hit.states_checked, 2 * s.plan.segments.size());  // every pulse state, not the knots
  EXPECT_GT(hit.contacts_with_interference, hit.states_checked * 9 / 10);
  EXPECT_EQ(hit.segments_with_interference, s.plan.segments.size());
  // Edge arcs (opening 10 deg): a radius above the 500 mm limit cuts in, one below clears.
  WheelSection arc{true, 200.0, 600.0, 10.0};
  const Interference too_large = along_plan(*valley, arc);
  EXPECT_GT(too_large.depth_mm, 0.05);
  EXPECT_GT(too_large.contacts_with_interference, 0u);
  arc.edge_radius_mm = 400.0;
  const Interference clear = along_plan(*valley, arc);
  EXPECT_EQ(clear.depth_mm, 0.0);
  EXPECT_EQ(clear.contacts_with_interference, 0u);
  EXPECT_GT(clear.states_checked, 0u);
  // Problem 1 (convex everywhere) with the shipped 20 mm face: clear along the whole plan.
  face.thickness_mm = 20.0;
  EXPECT_EQ(along_plan(*expression_generatrix(problem1, 550.0, 600.0), face).contacts_with_interference, 0u);
}

TEST(WheelLimits, InterferenceAlongThePlanSaysWhere) {
  // A bump at x = 30 mm on a cylinder: a 20 mm face touching the cylinder within 10 mm of the
  // bump rides on it, and touching the bump's flank it tilts and digs its end into the cylinder.
  // The replay and the ideal placements agree on depth and place (the bump is symmetric: the
  // deepest state may lie on either side).
  auto bump = expression_generatrix("100 + 0.5*exp(-((x - 30)/5)^2)", 0.0, 60.0);
  WheelSection face;
  face.thickness_mm = 20.0;
  Schedule s;
  const Interference hit = along_plan(*bump, face, &s);
  std::vector<double> contacts;
  for (int i = 0; i <= 600; ++i) contacts.push_back(0.1 * i);
  const Interference ideal = check_interference(*bump, face, contacts);
  ASSERT_GT(hit.depth_mm, 0.1);
  EXPECT_NEAR(hit.depth_mm, ideal.depth_mm, 0.01);
  EXPECT_NEAR(std::abs(hit.contact_x_mm - 30.0), std::abs(ideal.contact_x_mm - 30.0), 0.5);
  EXPECT_NEAR(std::abs(hit.x_mm - 30.0), std::abs(ideal.x_mm - 30.0), 0.5);
  EXPECT_LT(std::abs(hit.contact_x_mm - 30.0), 12.0);          // on or beside the bump
  EXPECT_LE(std::abs(hit.x_mm - hit.contact_x_mm), 10.0 + 1e-6);  // a point of the face
  // The time is that of a state in the segment whose ends bracket the contact.
  std::size_t k = 0;
  while (k + 1 < s.plan.segments.size() && s.plan.segments[k + 1].start_s <= hit.time_s) ++k;
  EXPECT_LE(s.knots_mm[k] - 0.01, hit.contact_x_mm);
  EXPECT_GE(s.knots_mm[k + 1] + 0.01, hit.contact_x_mm);
  EXPECT_LT(hit.segments_with_interference, s.plan.segments.size());  // not everywhere
}

TEST(Wear, TriangleSweepDwellsUniformlySineAtTheEdges) {
  WearSweep sweep{"triangle", 10.0, 80.0, 5};
  std::vector<double> zeta, durations;
  for (int k = 0; k <= 4000; ++k) zeta.push_back(sweep_function(sweep, 0.0)(k * 0.2));
  durations.assign(4000, 1.0);
  const WearDistribution tri = wear_distribution(zeta, durations, 10.0, 20);
  EXPECT_GT(tri.uniformity, 0.97);
  sweep.law = "sine";
  for (int k = 0; k <= 4000; ++k) zeta[static_cast<std::size_t>(k)] = sweep_function(sweep, 0.0)(k * 0.2);
  const WearDistribution sine = wear_distribution(zeta, durations, 10.0, 20);
  EXPECT_LT(sine.uniformity, 0.8);
  EXPECT_GT(sine.dwell_s.front(), 3 * sine.dwell_s[10]);  // arcsine law: edges dwell longest
  EXPECT_NEAR(tri.used_width_mm, 20.0, 1e-9);
}

}  // namespace
}  // namespace chatterlab::planner
