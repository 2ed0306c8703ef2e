// feed_risk (issue 5): the process model's known answers, the roots along a constant plan against
// stability_map at the same conditions, amplification = integral of the growth rate, the
// simulation along a constant plan against the root, validation of bad input.
#include "study_kinds/feed_risk/feed_risk.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <set>
#include <span>

#include "chatterlab/errors.hpp"
#include "chatterlab/study.hpp"
#include "study_kinds/feed_risk/feed_risk_kind.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/planner/feed_planning.hpp"
#include "chatterlab/spectrum.hpp"
#include "unit/g1_test_machines.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::feed_risk {
namespace {

namespace fs = std::filesystem;
using chatterlab::testing::TempDir;
using planner::SegmentConditions;

// feed_risk's test machine with the wheel chain off: the work chain chatters at 300 rpm (the
// growth rate is checked to be positive below, so the simulation test sees a growing response).
const std::string model_toml =
    testing::model_table_toml("plunge_regenerative", testing::g1_feed_risk_machine, "wheel_regeneration = false\n");

Json model_table() {
  TempDir dir;
  Study s = load_study(dir.write("m.toml", std::string("[study]\nkind = \"stability_map\"\n") + model_toml));
  return s.document["model"];
}

// The test model as plunge_with_penetration_damping with kd = `kd` (G4's dynamic force).
Json penetration_damping_table(double kd) {
  TempDir dir;
  const std::string toml = testing::model_table_toml(
      "plunge_with_penetration_damping", testing::g1_feed_risk_machine,
      "wheel_regeneration = false\npenetration_damping_n_s_per_m = " + std::to_string(kd) + "\n");
  Study s = load_study(dir.write("m.toml", std::string("[study]\nkind = \"stability_map\"\n") + toml));
  return s.document["model"];
}

Json stability_table() {
  TempDir dir;
  Study s = load_study(dir.write("m.toml", std::string("[study]\nkind = \"stability_map\"\n") + model_toml));
  return s.document["stability"];
}

// The reference conditions: width 10 mm, radius 100 mm, 300 rpm (= the model's), wheel 400 mm.
ProcessSettings reference_process() {
  ProcessSettings p;
  p.model = kit::build_model(model_table());
  p.reference_contact_width_mm = 10.0;
  p.reference_work_radius_mm = 100.0;
  p.wheel_speed_rpm = 1450.0;
  p.wheel_diameter_mm = 400.0;
  p.wheel_thickness_mm = 10.0;
  p.depth_of_cut_mm = 0.01;
  return p;
}

std::unique_ptr<planner::Generatrix> cylinder(double radius_mm, double length_mm) {
  return planner::build_generatrix(
      Json{{"generatrix", std::to_string(radius_mm)}, {"x_range_mm", {0.0, length_mm}}});
}

std::vector<SegmentConditions> constant_plan(std::size_t n, double duration_s, double radius_mm, double rpm) {
  std::vector<SegmentConditions> plan(n);
  for (std::size_t k = 0; k < n; ++k) {
    SegmentConditions& c = plan[k];
    c.start_s = duration_s * static_cast<double>(k);
    c.duration_s = duration_s;
    c.x_start_mm = 0.2 * static_cast<double>(k);
    c.x_end_mm = c.x_start_mm + 0.2;
    c.radius_mm = radius_mm;
    c.axial_speed_mm_per_s = 0.2 / duration_s;
    c.spindle_speed_rpm = rpm;
  }
  return plan;
}

// The roots and the simulation along `plan` on the 600 mm cylinder of radius 100 mm (start
// amplitude 1e-12 m, optional work spindle law).
struct RatedRun {
  PlanRisk risk;
  AlongPlanSimulation sim;
};
RatedRun rate_and_simulate(const std::vector<SegmentConditions>& plan,
                           std::shared_ptr<const SpeedLaw> work_speed = nullptr) {
  auto part = cylinder(100.0, 600.0);
  RatedRun run;
  run.risk = evaluate_roots(model_table(), reference_process(), plan, *part, {stability_table(), 1e-3}, {});
  AlongPlanSettings settings;
  settings.initial_waviness_m = 1e-12;
  settings.work_speed = std::move(work_speed);
  run.sim = simulate_along_plan(model_table(), reference_process(), plan, run.risk, settings);
  return run;
}

TEST(FeedRiskProcess, ContactWidthFromTheSectionAndTheDepth) {
  ProcessSettings p = reference_process();
  // Flat face on a straight generatrix: the whole face.
  EXPECT_DOUBLE_EQ(contact_width_mm(p, {100.0, 0.0, 0.0}), 10.0);
  // Flat face on a convex part of radius of curvature 1000 mm: chord 2 sqrt(h (2 rho - h)).
  EXPECT_NEAR(contact_width_mm(p, {100.0, 0.0, -1e-3}), 2 * std::sqrt(0.01 * (2000.0 - 0.01)), 1e-9);
  // Edge arc r = 20 mm on a straight part; on a concave part of radius 60 mm, 1/rho = 1/20 - 1/60.
  p.profiled_wheel = true;
  p.edge_radius_mm = 20.0;
  EXPECT_NEAR(contact_width_mm(p, {100.0, 0.0, 0.0}), 2 * std::sqrt(0.01 * (40.0 - 0.01)), 1e-12);
  EXPECT_NEAR(contact_width_mm(p, {100.0, 0.0, 1.0 / 60.0}), 2 * std::sqrt(0.01 * (60.0 - 0.01)), 1e-9);
  // Deep cut: capped by the arc's chord 2 r sin(alpha/2) (alpha = 180 deg: 40 mm).
  p.depth_of_cut_mm = 30.0;
  EXPECT_NEAR(contact_width_mm(p, {100.0, 0.0, 0.0}), 40.0, 1e-12);
}

TEST(FeedRiskProcess, ReferenceConditionsGiveTheModelAndWidthScalesStiffnesses) {
  ProcessSettings p = reference_process();
  auto part = cylinder(100.0, 600.0);
  const auto plan = constant_plan(1, 1.0, 100.0, 300.0);
  SegmentProcess s = map_segment(p, plan[0], *part);
  const Json at_reference = segment_model_table(model_table(), p, s);
  EXPECT_EQ(at_reference.at("type"), "plunge_regenerative");
  EXPECT_NEAR(at_reference.at("contact_stiffness_n_per_m").get<double>(), 2.0e7, 1e-6);
  EXPECT_NEAR(at_reference.at("work_removal_stiffness_n_per_m").get<double>(), 1.6e6, 1e-6);
  EXPECT_NEAR(at_reference.at("wheel_wear_stiffness_n_per_m").get<double>(), 2.0e9, 1e-3);
  EXPECT_NEAR(s.work_surface_speed_m_per_s, std::numbers::pi * 0.2 * 5.0, 1e-12);
  EXPECT_NEAR(s.equivalent_diameter_mm, 200.0 * 400.0 / 600.0, 1e-12);
  EXPECT_NEAR(s.contact_length_mm, std::sqrt(0.01 * 200.0 * 400.0 / 600.0), 1e-12);
  EXPECT_NEAR(s.axial_feed_per_rev_mm, 0.2 * 60.0 / 300.0, 1e-12);
  EXPECT_NEAR(s.overlap_ratio, 1.0 - 0.04 / 10.0, 1e-12);
  // Twice the width doubles all three; twice the work speed raises kw by the G4 factor Kv/(1+Kv).
  p.contact_width_mm = 20.0;
  auto faster = plan;
  faster[0].spindle_speed_rpm = 600.0;
  const SegmentProcess w = map_segment(p, faster[0], *part);
  const Json at_w = segment_model_table(model_table(), p, w);
  EXPECT_NEAR(at_w.at("contact_stiffness_n_per_m").get<double>(), 4.0e7, 1e-6);
  EXPECT_EQ(at_w.at("work_speed_rpm").get<double>(), 600.0);
  const double kv = s.speed_ratio;
  EXPECT_NEAR(at_w.at("work_removal_stiffness_n_per_m").get<double>(),
              3.2e6 * (2 * kv / (1 + 2 * kv)) / (kv / (1 + kv)), 1e-3);
  EXPECT_NEAR(at_w.at("wheel_wear_stiffness_n_per_m").get<double>(), 4.0e9 * (1 + kv) / (1 + 2 * kv), 1.0);
}

TEST(FeedRisk, ConstantPlanGivesTheStabilityMapRoot) {
  // stability_map at the model's own conditions.
  TempDir dir;
  Study map = load_study(dir.write("m.toml", std::string("[study]\nkind = \"stability_map\"\n") + model_toml));
  const std::vector<Json> row = study_kind_registry().at("stability_map").create(ParamValues())->run_point(map.point_document(0), {});
  const double map_growth = row[0].get<double>(), map_frequency = row[1].get<double>();
  ASSERT_GT(map_growth, 0.0) << "the test model must chatter";

  auto part = cylinder(100.0, 600.0);
  const auto plan = constant_plan(50, 1.0, 100.0, 300.0);
  const PlanRisk risk = evaluate_roots(model_table(), reference_process(), plan, *part,
                                       {stability_table(), 1e-3}, {});
  EXPECT_EQ(risk.groups, 1u);
  for (const SegmentRisk& r : risk.segments) {
    EXPECT_DOUBLE_EQ(r.growth_rate_per_s, map_growth);
    EXPECT_DOUBLE_EQ(r.chatter_frequency_hz, map_frequency);
    EXPECT_TRUE(r.certified);
  }
  // Amplification: the integral of a constant growth rate over 50 s; above 10: chatter.
  EXPECT_NEAR(risk.final_log_amplification, 50.0 * map_growth, 1e-9 * 50.0 * map_growth);
  EXPECT_EQ(risk.worst, Risk::chatter);
}

TEST(FeedRisk, AnyModelWithProcessConditionsWorks) {
  // plunge_with_penetration_damping declares the process-conditions capability too: feed_risk
  // rates a plan with it unchanged. A plan over 280..320 rpm on the reference cylinder.
  auto part = cylinder(100.0, 600.0);
  auto plan = constant_plan(9, 1.0, 100.0, 300.0);
  for (std::size_t k = 0; k < plan.size(); ++k) plan[k].spindle_speed_rpm = 280.0 + 5.0 * static_cast<double>(k);
  const RootSettings roots{stability_table(), 1e-9};
  const PlanRisk g1 = evaluate_roots(model_table(), reference_process(), plan, *part, roots, {});
  ASSERT_GT(g1.max_growth_rate_per_s, 0.0) << "the G1 test model must chatter";
  auto rate = [&](double kd) {
    ProcessSettings p = reference_process();
    p.model = kit::build_model(penetration_damping_table(kd));
    return std::pair{evaluate_roots(penetration_damping_table(kd), p, plan, *part, roots, {}), p};
  };
  // kd = 0 is G1 (MODELS.md G4 -> G1): the same roots at every segment.
  const PlanRisk zero = rate(0.0).first;
  for (std::size_t k = 0; k < plan.size(); ++k)
    EXPECT_NEAR(zero.segments[k].growth_rate_per_s, g1.segments[k].growth_rate_per_s,
                1e-9 * std::abs(g1.segments[k].growth_rate_per_s)) << "segment " << k;
  EXPECT_EQ(zero.groups, g1.groups);
  // kd > 0 damps the work chain: every segment grows more slowly than with G1. At 300 rpm (segment
  // 4) the conditions are the reference, so the root is the model's own rightmost root.
  const double kd = 2.0e3;
  const auto [damped, p] = rate(kd);
  for (std::size_t k = 0; k < plan.size(); ++k)
    EXPECT_LT(damped.segments[k].growth_rate_per_s, g1.segments[k].growth_rate_per_s - 1e-3) << "segment " << k;
  const double own = kit::rightmost_root(*kit::build_model(penetration_damping_table(kd)),
                                         kit::stability_settings_table().read(stability_table())).root.real();
  EXPECT_NEAR(damped.segments[4].growth_rate_per_s, own, 1e-9 * std::abs(own));
  // kd follows G4 (kd ~ kw sqrt(de u0) / v_w): on the cylinder only the work speed changes, so at
  // n rpm kd = kd_ref (kw(n)/kw_ref) (300/n).
  const Json at_280 = segment_model_table(penetration_damping_table(kd), p, damped.process[0]);
  const double kw_ratio = at_280.at("work_removal_stiffness_n_per_m").get<double>() / 1.6e6;
  EXPECT_NEAR(at_280.at("penetration_damping_n_s_per_m").get<double>(), kd * kw_ratio * 300.0 / 280.0, 1e-9 * kd);
}

TEST(FeedRisk, AmplificationIsTheIntegralOfTheGrowthRate) {
  // Segments of unequal length with sigma(t) = 2 - t/5 (piecewise constant at the segment
  // middles): ln A(t) = sum sigma_k d_k; the floored form restarts from 0 after a decay.
  std::vector<SegmentConditions> plan;
  PlanRisk risk;
  double t = 0.0, exact = 0.0, floored = 0.0, floored_max = 0.0;
  for (int k = 0; k < 40; ++k) {
    SegmentConditions c;
    c.start_s = t;
    c.duration_s = 0.25 + 0.05 * (k % 5);
    const double sigma = 2.0 - (t + 0.5 * c.duration_s) / 5.0;
    SegmentRisk r;
    r.growth_rate_per_s = sigma;
    risk.segments.push_back(r);
    plan.push_back(c);
    exact += sigma * c.duration_s;
    floored = std::max(0.0, floored + sigma * c.duration_s);
    floored_max = std::max(floored_max, floored);
    t += c.duration_s;
  }
  accumulate(plan, {1.0, 10.0}, risk);
  EXPECT_NEAR(risk.final_log_amplification, exact, 1e-12);
  EXPECT_NEAR(risk.max_floored_log_amplification, floored_max, 1e-12);
  // Analytic: sigma = 2 - t/5 integrates to 2T - T^2/10; the midpoint rule is exact for a line.
  EXPECT_NEAR(risk.final_log_amplification, 2 * t - t * t / 10.0, 1e-9);
  // The peak of the integral is at t = 10 s (sigma = 0): 2*10 - 100/10 = 10 = ln A > ln 10: chatter.
  EXPECT_EQ(risk.worst, Risk::chatter);
  EXPECT_EQ(risk.segments.front().risk, Risk::marginal);  // growing, not yet 10x
}

TEST(FeedRisk, StreamedSamplesAreTheStoredSamples) {
  // The engine's streaming option (SimulationSettings::on_sample, store_samples) hands out exactly
  // the samples it would store; with storage off the series stay empty.
  auto model = kit::build_model(model_table())->time_domain();
  SimulationSettings s;
  s.duration_s = 0.5;
  s.sample_rate_hz = 2000.0;
  s.one_sided_contact = false;
  const SimulationResult stored = simulate(*model, s);
  std::vector<OutputSample> streamed;
  s.on_sample = [&](const OutputSample& sample) { streamed.push_back(sample); };
  s.store_samples = false;
  const SimulationResult lean = simulate(*model, s);
  EXPECT_TRUE(lean.t_s.empty());
  EXPECT_TRUE(lean.displacement_m.empty());
  ASSERT_EQ(streamed.size(), stored.t_s.size());
  for (std::size_t i = 0; i < streamed.size(); ++i) {
    EXPECT_EQ(streamed[i].t_s, stored.t_s[i]);
    EXPECT_EQ(streamed[i].displacement_m, stored.displacement_m[i]);
    EXPECT_EQ(streamed[i].depth_of_cut_m, stored.depth_of_cut_m[i]);
    EXPECT_EQ(streamed[i].surface_at_contact_m[1], stored.surface_at_contact_m[1][i]);
  }
  EXPECT_EQ(lean.steps, stored.steps);
}

// Re-planning settings of the optimiser tests: 250-300 rpm in 6 speeds, constant and +-5 %
// modulated.
OptimiseSettings six_speeds(int phase_samples, double max_time_factor, double condition_tolerance) {
  OptimiseSettings o;
  o.spindle_min_rpm = 250.0;
  o.spindle_max_rpm = 300.0;
  o.speed_steps = 6;
  o.amplitude_ratios = {0.0, 0.05};
  o.phase_samples = phase_samples;
  o.max_time_factor = max_time_factor;
  o.condition_tolerance = condition_tolerance;
  return o;
}

TEST(FeedRisk, OptimiserReplansRatesAndKeepsTheTimeLimit) {
  auto part = cylinder(100.0, 600.0);
  const ProcessSettings p = reference_process();
  const RootSettings roots{stability_table(), 1e-9};
  // The planner's behaviour in miniature: the axial-speed bound grows with the spindle speed, so
  // the same 20 segments take 300/n times as long at n rpm.
  std::vector<double> replanned_at;
  std::mutex replanned_mutex;  // the optimiser plans its speeds concurrently
  const Replan replan = [&](double rpm) {
    {
      const std::lock_guard<std::mutex> lock(replanned_mutex);
      replanned_at.push_back(rpm);
    }
    return constant_plan(20, 300.0 / rpm, 100.0, rpm);
  };
  const OptimiseSettings o = six_speeds(4, 1.1, 1e-9);
  const OptimiseResult r = optimise(model_table(), p, replan, 20.0, *part, roots, {}, o);
  ASSERT_EQ(r.candidates.size(), 12u);
  const Candidate& best = r.candidates[r.best];
  EXPECT_TRUE(best.admissible);
  for (const Candidate& c : r.candidates) {
    // Time factor = 300 / planning speed; beyond 1.1 (planning below 272.7 rpm) not admissible.
    EXPECT_NEAR(c.time_factor, 300.0 / c.planning_speed_rpm, 1e-9);
    EXPECT_EQ(c.admissible, c.time_factor <= 1.1 + 1e-9);
    EXPECT_NEAR(c.planning_speed_rpm, c.spindle_speed_rpm * (1 - c.amplitude_ratio), 1e-9);
    if (c.admissible) {
      EXPECT_LE(best.max_floored_log_amplification, c.max_floored_log_amplification + 1e-9);
    }
    // The modulated speed range stays inside the machine's.
    EXPECT_GE(c.spindle_speed_rpm * (1 - c.amplitude_ratio), 250.0 - 1e-9);
    EXPECT_LE(c.spindle_speed_rpm * (1 + c.amplitude_ratio), 300.0 + 1e-9);
    if (c.amplitude_ratio == 0.0) {
      // Unmodulated: the segment's own root (as evaluate_roots gives it, to Newton's tolerance
      // 1e-13 |s| with |s| < 10^4 rad/s here: the batch warm-starts it from another rating's group).
      const double newton_tolerance = 1e-9;
      const PlanRisk direct = evaluate_roots(model_table(), p, constant_plan(20, 1.0, 100.0, c.spindle_speed_rpm),
                                             *part, roots, {});
      EXPECT_NEAR(c.nominal_max_growth_rate_per_s, direct.max_growth_rate_per_s, newton_tolerance);
      // Rated by the worst case over the spindle-speed band n (1 +- 0.5 %), issue 19.
      const PlanRisk band = evaluate_roots(model_table(), p, constant_plan(20, 1.0, 100.0, c.spindle_speed_rpm),
                                           *part, roots, {}, o.speed_tolerance);
      EXPECT_NEAR(c.max_growth_rate_per_s, band.max_growth_rate_per_s, newton_tolerance);
      EXPECT_GE(c.max_growth_rate_per_s, c.nominal_max_growth_rate_per_s);
    } else {
      // Modulated: the mean of the roots at the frozen speeds n (1 + a sin((j + 1/2) pi/2)), j = 0..3.
      double mean = 0.0;
      for (int j = 0; j < 4; ++j) {
        const double rpm = c.spindle_speed_rpm * (1 + 0.05 * std::sin(2 * std::numbers::pi * (j + 0.5) / 4));
        mean += evaluate_roots(model_table(), p, constant_plan(1, 1.0, 100.0, rpm), *part, roots, {})
                    .max_growth_rate_per_s / 4;
      }
      EXPECT_NEAR(c.nominal_max_growth_rate_per_s, mean, 1e-12);
    }
  }
  // Replanned once per distinct planning speed, the best plan at the best candidate's mean speed.
  std::set<double> planning_speeds;
  for (const Candidate& c : r.candidates) planning_speeds.insert(c.planning_speed_rpm);
  EXPECT_EQ(replanned_at.size(), planning_speeds.size());
  EXPECT_EQ(r.best_plan.front().spindle_speed_rpm, best.spindle_speed_rpm);
}

// The re-plan's ratings are solved as one batch in which the modulated candidates' phases share
// condition groups (rate_plans): groups, representatives and warm starts depend only on the data,
// so every candidate's figures are the same bits for one thread and for two.
TEST(FeedRisk, OptimiserIsTheSameForAnyThreadCount) {
  auto part = cylinder(100.0, 600.0);
  const ProcessSettings p = reference_process();
  const RootSettings roots{stability_table(), 1e-3};
  const Replan replan = [](double rpm) { return constant_plan(20, 300.0 / rpm, 100.0, rpm); };
  // The default tolerance 1e-2: neighbouring candidates' phases share cells.
  const OptimiseSettings o = six_speeds(8, 1.2, 1e-2);
  const auto runs = testing::with_one_two_two_threads(
      [&] { return optimise(model_table(), p, replan, 20.0, *part, roots, {}, o).candidates; });
  ASSERT_EQ(runs[0].size(), 12u);
  for (std::size_t run = 1; run < runs.size(); ++run)
    for (std::size_t k = 0; k < runs[0].size(); ++k) {
      SCOPED_TRACE(::testing::Message() << "run " << run << ", candidate " << k);
      EXPECT_EQ(runs[run][k].max_growth_rate_per_s, runs[0][k].max_growth_rate_per_s);
      EXPECT_EQ(runs[run][k].nominal_max_growth_rate_per_s, runs[0][k].nominal_max_growth_rate_per_s);
      EXPECT_EQ(runs[run][k].max_floored_log_amplification, runs[0][k].max_floored_log_amplification);
    }
}

TEST(FeedRiskAccuracy, SimulationFollowsTheSegmentsConditionsAndSpindleSchedule) {
  // 30 s at radius 100 mm and 300 rpm, then 30 s at radius 80 mm and 280 rpm: two condition
  // groups (kw scales with Kv, G4) and a spindle-speed step. The wrapper switches the contact law
  // and the schedule the work delay at 30 s; each stretch's simulated growth approaches its root.
  auto plan = constant_plan(60, 1.0, 100.0, 300.0);
  for (std::size_t k = 30; k < 60; ++k) {
    plan[k].radius_mm = 80.0;
    plan[k].spindle_speed_rpm = 280.0;
  }
  const auto [risk, sim] = rate_and_simulate(plan);
  EXPECT_EQ(risk.groups, 2u);
  const double first = risk.segments.front().growth_rate_per_s, second = risk.segments.back().growth_rate_per_s;
  ASSERT_FALSE(sim.failed || sim.diverged) << sim.status;
  // Revolutions counted by the schedule: 30 s x 5 /s + 30 s x 4.667 /s = 290.
  EXPECT_NEAR(static_cast<double>(sim.revolutions.size()), 290.0, 1.5);
  const double fitted_first = fitted_growth_rate_per_s(sim.revolutions, 12.0, 30.0);
  const double fitted_second = fitted_growth_rate_per_s(sim.revolutions, 42.0, 60.0);
  // Measured: 0.3451 vs 0.3560 /s and -0.5619 vs -0.5424 /s (the neighbouring lattice roots,
  // see the constant-plan test).
  EXPECT_GT(first, 0.0);
  EXPECT_LT(second, 0.0);
  EXPECT_NEAR(fitted_first, first, 0.06 * std::abs(first));
  EXPECT_NEAR(fitted_second, second, 0.06 * std::abs(second));
}

TEST(FeedRisk, ModulatedSpindleCountsRevolutionsByTheSpeedLaw) {
  // The optimiser's modulated spindle (make_modulated_speed) drives the simulation: 10 s at
  // 300 rpm +- 5 % at 0.5 Hz is 5 whole modulation periods, i.e. exactly 50 work revolutions.
  const auto plan = constant_plan(10, 1.0, 100.0, 300.0);
  const AlongPlanSimulation sim =
      rate_and_simulate(plan, make_modulated_speed(300.0, SpeedModulation::sinusoidal, 0.05, 0.5)).sim;
  ASSERT_FALSE(sim.failed || sim.diverged) << sim.status;
  EXPECT_NEAR(static_cast<double>(sim.revolutions.size()), 50.0, 1.0);
  // The plan's own schedule: constant plans get a constant law, a speed step a schedule.
  auto stepped = plan;
  for (std::size_t k = 5; k < 10; ++k) stepped[k].spindle_speed_rpm = 250.0;
  auto law = plan_spindle_speed(stepped);
  EXPECT_DOUBLE_EQ(law->rpm(2.0), 300.0);
  EXPECT_DOUBLE_EQ(law->rpm(7.0), 250.0);
  EXPECT_NEAR(law->angle_rad(10.0) / (2 * std::numbers::pi), 25.0 + 250.0 / 12.0, 1e-3);
}

TEST(FeedRiskAccuracy, SimulationAlongAConstantPlanGrowsAtTheRootsRate) {
  const auto [risk, sim] = rate_and_simulate(constant_plan(60, 1.0, 100.0, 300.0));
  const AlongPlanSettings settings;
  ASSERT_FALSE(sim.failed || sim.diverged) << sim.status;
  ASSERT_GT(sim.revolutions.size(), 290u);  // 60 s at 5 rev/s
  const double fitted = fitted_growth_rate_per_s(sim.revolutions, 30.0, 60.0);
  const double root = risk.segments.front().growth_rate_per_s;

  // Independent route: the engine on the plain G1 model (no wrapper, no streaming), its own
  // envelope fit over the same window.
  SimulationSettings plain;
  plain.duration_s = 60.0;
  plain.sample_rate_hz = settings.sample_rate_hz;
  plain.disturbance = {1e-12, 0.0};
  plain.initial_waviness_m = 1e-12;
  plain.one_sided_contact = false;
  plain.relative_tolerance = settings.relative_tolerance;
  auto model = kit::build_model(model_table())->time_domain();
  const SimulationResult r = simulate(*model, plain);
  const double engine = fit_envelope(r.t_s, r.displacement_m, 30.0, 60.0, 10.0).growth_rate_per_s;
  EXPECT_NEAR(fitted, engine, 0.01 * engine) << "along-plan " << fitted << " engine " << engine;
  // The work lattice puts roots 1/Tw = 5 Hz apart whose growth rates differ little from the
  // rightmost one (sigma is flat near its peak), so the envelope approaches e^{sigma t} slowly:
  // both simulated rates sit a few per cent below the root after 30..60 s, never above it.
  EXPECT_LT(fitted, root * 1.005);
  EXPECT_GT(fitted, 0.95 * root) << "fitted " << fitted << " root " << root;
}

// Issue 25's engine equivalence on a variable work speed: the along-plan model (a condition-group
// change and a 300 -> 280 rpm spindle step at 10 s, the work delay following the schedule) by the
// fixed-step engine the kind uses and by the adaptive ARKODE reference (rtol 1e-8): growth rate
// within 0.5 % and chatter frequency within 0.1 % on each stretch, the work surface at the end
// within 1 % rms.
TEST(FeedRiskAccuracy, AlongPlanFixedStepAgreesWithTheReferenceRoute) {
  auto plan = constant_plan(20, 1.0, 100.0, 300.0);
  for (std::size_t k = 10; k < 20; ++k) {
    plan[k].radius_mm = 80.0;
    plan[k].spindle_speed_rpm = 280.0;
  }
  auto part = cylinder(100.0, 600.0);
  const PlanRisk risk = evaluate_roots(model_table(), reference_process(), plan, *part, {stability_table(), 1e-3}, {});
  ASSERT_EQ(risk.groups, 2u);
  const auto model = along_plan_model(model_table(), reference_process(), plan, risk);
  SimulationSettings s;
  s.duration_s = 20.0;
  s.sample_rate_hz = 4000.0;
  s.disturbance = {1e-6, 0.0};
  s.one_sided_contact = false;
  s.divergence_limit_m = 1e6;
  s.speed[static_cast<std::size_t>(Rotor::work)] = plan_spindle_speed(plan);
  s.snapshot_times_s = {20.0};
  SimulationSettings reference = s;
  reference.integrator = TimeIntegrator::explicit_runge_kutta;
  reference.relative_tolerance = 1e-8;
  s.integrator = TimeIntegrator::fixed_step;
  const SimulationResult a = simulate(*model, reference), b = simulate(*model, s);
  ASSERT_EQ(a.status, "completed");
  ASSERT_EQ(b.status, "completed");
  for (auto [from, to] : {std::pair{4.0, 10.0}, std::pair{14.0, 20.0}}) {
    const EnvelopeFit fa = fit_envelope(a.t_s, a.displacement_m, from, to, 10.0);
    const EnvelopeFit fb = fit_envelope(b.t_s, b.displacement_m, from, to, 10.0);
    EXPECT_NEAR(fb.growth_rate_per_s, fa.growth_rate_per_s, 0.005 * std::abs(fa.growth_rate_per_s)) << from;
    const auto peak = [&](const SimulationResult& r) {
      const auto i0 = static_cast<std::size_t>(from * s.sample_rate_hz), i1 = static_cast<std::size_t>(to * s.sample_rate_hz);
      const std::span<const double> x(r.displacement_m.data() + i0, i1 - i0);
      return find_peaks(amplitude_spectrum(x, s.sample_rate_hz), 1, 0.0, 1e-3).at(0).frequency_hz;
    };
    EXPECT_NEAR(peak(b), peak(a), 0.001 * peak(a)) << from;
    std::printf("[%g, %g] s: growth %.6g vs %.6g /s, frequency %.6g vs %.6g Hz\n", from, to, fb.growth_rate_per_s,
                fa.growth_rate_per_s, peak(b), peak(a));
  }
  ASSERT_EQ(a.snapshots.size(), 1u);
  ASSERT_EQ(b.snapshots.size(), 1u);
  const std::vector<double>& wa = a.snapshots[0].surface_m[static_cast<std::size_t>(Rotor::work)];
  const std::vector<double>& wb = b.snapshots[0].surface_m[static_cast<std::size_t>(Rotor::work)];
  ASSERT_EQ(wa.size(), wb.size());
  double mean = 0.0, diff = 0.0, size = 0.0;
  for (double v : wa) mean += v / static_cast<double>(wa.size());
  for (std::size_t i = 0; i < wa.size(); ++i) {
    diff += (wb[i] - wa[i]) * (wb[i] - wa[i]);
    size += (wa[i] - mean) * (wa[i] - mean);
  }
  ASSERT_GT(size, 0.0);
  EXPECT_LT(std::sqrt(diff / size), 0.01);
  std::printf("work surface: %.3g %% rms\n", 100.0 * std::sqrt(diff / size));
}

}  // namespace
}  // namespace chatterlab::feed_risk
