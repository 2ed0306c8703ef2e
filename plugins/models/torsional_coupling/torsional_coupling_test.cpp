// Known answers for torsional_coupling (MODELS.md G5): the wheel-speed singularity handled
// without NaN and with a diagnostic; the rotation angles are states (speeds follow the torsional
// velocities); torsion modulates the force (soft drives fluctuate more than stiff ones).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/params.hpp"
#include "models/torsional_coupling/torsional_coupling.hpp"

namespace chatterlab {
namespace {

TorsionalCouplingParameters example() {
  const Json j = TorsionalCoupling::info().example_params;
  TorsionalCouplingParameters p;
  p.mass_kg = j["mass_kg"]; p.damping_n_s_per_m = j["damping_n_s_per_m"]; p.stiffness_n_per_m = j["stiffness_n_per_m"];
  p.work_inertia_kg_m2 = j["work_inertia_kg_m2"]; p.work_torsional_damping_n_m_s = j["work_torsional_damping_n_m_s"];
  p.work_torsional_stiffness_n_m = j["work_torsional_stiffness_n_m"];
  p.wheel_inertia_kg_m2 = j["wheel_inertia_kg_m2"]; p.wheel_torsional_damping_n_m_s = j["wheel_torsional_damping_n_m_s"];
  p.wheel_torsional_stiffness_n_m = j["wheel_torsional_stiffness_n_m"];
  p.work_radius_m = j["work_radius_m"]; p.wheel_radius_m = j["wheel_radius_m"];
  p.work_speed_rpm = j["work_speed_rpm"]; p.wheel_speed_rpm = j["wheel_speed_rpm"];
  p.grinding_width_m = j["grinding_width_m"]; p.removal_coefficient_n_per_m2 = j["removal_coefficient_n_per_m2"];
  p.grinding_ratio = j["grinding_ratio"]; p.force_angle_deg = j["force_angle_deg"];
  return p;
}

TEST(TorsionalCoupling, WheelSpeedNearZeroGivesNoNanAndADiagnostic) {
  const auto p = example();
  TorsionalCouplingTimeDomain model(p);
  std::vector<double> state(8, 0.0);
  state[0] = 1e-6;  // in contact
  ContactInput in;
  in.state = state;
  in.speed_rpm[static_cast<std::size_t>(Rotor::work)] = p.work_speed_rpm;
  ContactOutput out;
  // At 10 % of the speed the force is 10 x the nominal one (F ~ 1/v_g), finite.
  in.speed_rpm[static_cast<std::size_t>(Rotor::wheel)] = p.wheel_speed_rpm;
  model.contact(in, out);
  const double nominal = out.normal_force_n;
  EXPECT_GT(nominal, 0.0);
  in.speed_rpm[static_cast<std::size_t>(Rotor::wheel)] = 0.1 * p.wheel_speed_rpm;
  model.contact(in, out);
  EXPECT_NEAR(out.normal_force_n, 10.0 * nominal, 1e-9 * nominal);
  EXPECT_TRUE(model.diagnostics().empty());
  for (double rpm : {0.005 * p.wheel_speed_rpm, 0.0, -3.0}) {
    in.t_s = 0.25;
    in.speed_rpm[static_cast<std::size_t>(Rotor::wheel)] = rpm;
    model.contact(in, out);
    EXPECT_EQ(out.normal_force_n, 0.0) << rpm;
    EXPECT_TRUE(std::isfinite(out.depth_of_cut_m));
  }
  ASSERT_EQ(model.diagnostics().size(), 1u);
  EXPECT_NE(model.diagnostics()[0].find("wheel speed fell below 1 % of nominal"), std::string::npos);
  EXPECT_NE(model.diagnostics()[0].find("t = 0.25 s"), std::string::npos) << model.diagnostics()[0];
}

SimulationResult run(const TorsionalCouplingParameters& p) {
  TorsionalCouplingTimeDomain model(p);
  SimulationSettings s;
  s.duration_s = 0.5;
  s.sample_rate_hz = 5000.0;
  s.infeed_rate_m_per_s = 15e-6;
  s.disturbance = {0.0, 0.0};
  s.initial_waviness_m = 1e-6;
  return simulate(model, s);
}

double relative_fluctuation(const std::vector<double>& v) {
  double mean = 0, sq = 0;
  std::size_t n = 0;
  for (std::size_t i = v.size() / 2; i < v.size(); ++i, ++n) mean += v[i];
  mean /= static_cast<double>(n);
  for (std::size_t i = v.size() / 2; i < v.size(); ++i) sq += (v[i] - mean) * (v[i] - mean);
  return std::sqrt(sq / static_cast<double>(n)) / mean;
}

TEST(TorsionalCouplingAccuracy, SpeedsAreStatesAndTorsionModulatesTheForce) {
  auto soft = example();
  const SimulationResult a = run(soft);
  ASSERT_EQ(a.status, "completed");
  for (double f : a.force_n) ASSERT_TRUE(std::isfinite(f));
  // The speeds vary with the torsional velocities (not a constant law).
  double lo = 1e300, hi = 0;
  for (double rpm : a.speed_rpm[static_cast<std::size_t>(Rotor::work)]) { lo = std::min(lo, rpm); hi = std::max(hi, rpm); }
  EXPECT_GT(hi - lo, 1e-6);
  EXPECT_NEAR(0.5 * (hi + lo), soft.work_speed_rpm, 0.05 * soft.work_speed_rpm);
  auto stiff = soft;
  stiff.work_torsional_stiffness_n_m *= 20.0;
  stiff.wheel_torsional_stiffness_n_m *= 20.0;
  const SimulationResult b = run(stiff);
  ASSERT_EQ(b.status, "completed");
  EXPECT_GT(relative_fluctuation(a.force_n), relative_fluctuation(b.force_n));
}

}  // namespace
}  // namespace chatterlab
