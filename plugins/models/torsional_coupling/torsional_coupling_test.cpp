// Known answers for torsional_coupling (MODELS.md G5): the wheel-speed singularity handled
// without NaN and with a diagnostic; the rotation angles are states (speeds follow the torsional
// velocities); torsion modulates the force (soft drives fluctuate more than stiff ones); without
// torque G5 is G1 with a rigid contact, in growth rate and frequency against G1's rightmost root
// (quantitative, the 1 % / 0.5 %), and with heavy torsional inertias it follows its
// torque-free form with the force projected by cos(alpha).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/process_conditions.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/spectrum.hpp"
#include "shared/plunge_dynamics/plunge_characteristic.hpp"
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
  // The force law reads the speeds from the state (n_g + phi_g' 60/2pi), as the engine does.
  auto set_wheel_rpm = [&](double rpm) {
    state[5] = (rpm - p.wheel_speed_rpm) / TorsionalCouplingEquations::rpm_per_rad_s;
  };
  ContactInput in;
  in.state = state;
  ContactOutput out;
  // At 10 % of the speed the force is 10 x the nominal one (F ~ 1/v_g), finite.
  set_wheel_rpm(p.wheel_speed_rpm);
  model.contact(in, out);
  const double nominal = out.normal_force_n;
  EXPECT_GT(nominal, 0.0);
  set_wheel_rpm(0.1 * p.wheel_speed_rpm);
  EXPECT_NEAR(model.speed_rpm_from_state(Rotor::wheel, state), 0.1 * p.wheel_speed_rpm, 1e-9 * p.wheel_speed_rpm);
  model.contact(in, out);
  EXPECT_NEAR(out.normal_force_n, 10.0 * nominal, 1e-9 * nominal);
  EXPECT_TRUE(model.diagnostics().empty());
  for (double rpm : {0.005 * p.wheel_speed_rpm, 0.0, -3.0}) {
    in.t_s = 0.25;
    set_wheel_rpm(rpm);
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

// A G5 machine and the G1 machine it reduces to when the torsional velocities stay zero (speeds
// nominal, so the force factor n_w'/n_w n_g/n_g' = 1): G5's interference x - Rw - Rg with
// F = lambda_w b delta_w, delta_w = I/(1 + r), r = lambda_w/lambda_g, is G1's
// F = I/(1/kc + 1/kg + 1/kw) with kw = lambda_w b, kg = kw/r and kc -> infinity (G5 has no
// contact stiffness; 1e14 N/m here changes the series compliance by 2e-6), and the transverse
// mode m x'' + c x' + k x = -F cos(alpha) is G1's mode (w^2 = k/m, zeta = c/(2 sqrt(km))) with
// modal stiffness k/cos(alpha) (x of G5 points into the work, G1's away from it; the equations
// are linear, so the same initial displacement gives the same x(t)). The G1 reference machine's
// 250 Hz mode, kw 2e8, kg 1e9, 1450/55 rpm, with zeta 0.1: rightmost root 12.56 /s at 505.2 Hz.
struct MatchedPair {
  TorsionalCouplingParameters g5;
  PlungeRegenerativeParameters g1;
};

MatchedPair matched_pair(double force_angle_deg, double torsional_inertia_kg_m2) {
  constexpr double pi = std::numbers::pi;
  const double frequency_hz = 250.0, zeta = 0.1, k = 5e7, kw = 2e8, kg = 1e9;
  MatchedPair m;
  TorsionalCouplingParameters& p = m.g5;
  p = example();
  p.stiffness_n_per_m = k;
  p.mass_kg = k / std::pow(2.0 * pi * frequency_hz, 2);
  p.damping_n_s_per_m = 2.0 * zeta * std::sqrt(k * p.mass_kg);
  p.work_inertia_kg_m2 = p.wheel_inertia_kg_m2 = torsional_inertia_kg_m2;
  p.removal_coefficient_n_per_m2 = kw / p.grinding_width_m;
  // lambda_g = lambda_w Gr Rg0 n_g / (Rw0 n_w) = kg / b
  p.grinding_ratio = kg * p.work_radius_m * p.work_speed_rpm / (kw * p.wheel_radius_m * p.wheel_speed_rpm);
  p.force_angle_deg = force_angle_deg;
  PlungeRegenerativeParameters& g = m.g1;
  g.wheel_speed_rpm = p.wheel_speed_rpm;
  g.work_speed_rpm = p.work_speed_rpm;
  g.contact_stiffness_n_per_m = 1e14;
  g.wheel_wear_stiffness_n_per_m = kg;
  g.work_removal_stiffness_n_per_m = kw;
  g.modes = {{frequency_hz, zeta, k / std::cos(force_angle_deg * pi / 180.0)}};
  return m;
}

SimulationSettings linear_run(double duration_s) {
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = 10000.0;
  s.one_sided_contact = false;  // the linear model of G1's eq 2-16
  s.divergence_limit_m = 1e6;
  s.relative_tolerance = 1e-4;
  return s;
}

// alpha = 0: no torque, the torsional modes are never excited, so the reduction is exact: the
// simulated growth rate and frequency must be G1's rightmost root (measured 12.578 /s against
// 12.563 /s, 505.17 Hz against 505.18 Hz).
TEST(TorsionalCouplingAccuracy, WithoutTorqueGrowthAndFrequencyAreTheG1Root) {
  const MatchedPair m = matched_pair(0.0, example().work_inertia_kg_m2);
  PlungeCharacteristic characteristic(m.g1);
  RootSearchOptions options;
  options.max_frequency_hz = 3000.0;
  const RightmostRoot root = find_rightmost_root(characteristic, options);
  ASSERT_TRUE(root.certified);
  const double growth = root.root.real(), frequency_hz = root.root.imag() / (2.0 * std::numbers::pi);
  ASSERT_GT(growth, 0.5);  // the criterion applies for |growth| >= 0.5 /s
  TorsionalCouplingTimeDomain model(m.g5);
  const SimulationResult r = simulate(model, linear_run(2.0));
  ASSERT_EQ(r.status, "completed");
  for (const auto& speeds : r.speed_rpm)
    EXPECT_EQ(*std::min_element(speeds.begin(), speeds.end()), *std::max_element(speeds.begin(), speeds.end()));
  const EnvelopeFit fit = fit_envelope(r.t_s, r.displacement_m, 1.0, 2.0);
  EXPECT_NEAR(fit.growth_rate_per_s, growth, 0.01 * growth);
  const std::size_t half = r.displacement_m.size() / 2;
  const Spectrum spectrum = amplitude_spectrum(
      std::span<const double>(r.displacement_m.data() + half, r.displacement_m.size() - half), 10000.0);
  EXPECT_NEAR(find_peaks(spectrum, 1).front().frequency_hz, frequency_hz, 0.005 * frequency_hz);
}

// alpha = 20 deg with torsional inertias of 1e9 kg m^2: the torque F R sin(alpha) barely moves
// the speeds (by 0.012 rpm of 1450 over the run), so G5 must follow its own torque-free form with
// the transverse mode scaled by 1/cos(alpha) (m, c, k; same w and zeta: the G1 mode of stiffness
// k/cos(alpha)), sample by sample (measured: 0.11 % of the largest |x| so far, the two runs'
// integration error at rtol 1e-4; both grow at 11.110 /s, as G1's own simulation of that mode;
// unprojected: 12.58 /s).
TEST(TorsionalCouplingAccuracy, HeavyTorsionFollowsTheProjectedForce) {
  const MatchedPair m = matched_pair(20.0, 1e9);
  auto projected = m.g5;
  projected.force_angle_deg = 0.0;
  const double cos_alpha = std::cos(m.g5.force_angle_deg * std::numbers::pi / 180.0);
  projected.mass_kg /= cos_alpha;
  projected.damping_n_s_per_m /= cos_alpha;
  projected.stiffness_n_per_m /= cos_alpha;
  const SimulationResult a = simulate(TorsionalCouplingTimeDomain(m.g5), linear_run(2.0));
  const SimulationResult b = simulate(TorsionalCouplingTimeDomain(projected), linear_run(2.0));
  ASSERT_EQ(a.status, "completed");
  ASSERT_EQ(b.status, "completed");
  ASSERT_EQ(a.displacement_m.size(), b.displacement_m.size());
  const auto& wheel = a.speed_rpm[static_cast<std::size_t>(Rotor::wheel)];
  EXPECT_LT(m.g5.wheel_speed_rpm - *std::min_element(wheel.begin(), wheel.end()), 0.1);
  double largest = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < a.displacement_m.size(); ++i) {
    largest = std::max(largest, std::abs(b.displacement_m[i]));
    worst = std::max(worst, std::abs(a.displacement_m[i] - b.displacement_m[i]) / largest);
  }
  EXPECT_LT(worst, 0.02);
  const double growth = fit_envelope(a.t_s, a.displacement_m, 1.0, 2.0).growth_rate_per_s;
  EXPECT_NEAR(growth, fit_envelope(b.t_s, b.displacement_m, 1.0, 2.0).growth_rate_per_s, 0.005 * growth);
  // Without the projection (the mode as given, force not projected) the runs separate: the
  // comparison can fail.
  auto unprojected = m.g5;
  unprojected.force_angle_deg = 0.0;
  const SimulationResult c = simulate(TorsionalCouplingTimeDomain(unprojected), linear_run(2.0));
  EXPECT_GT(std::abs(fit_envelope(c.t_s, c.displacement_m, 1.0, 2.0).growth_rate_per_s - growth), 0.02 * growth);
}

// G5 written once: its stability is the certified rightmost root of the linearisation derived
// from the time-domain equations above (no hand-written characteristic function). At the rest
// point the force is zero, so the speed correction F (n_w'/n_w)(n_g/n_g') has no first-order
// term and the torsional modes, driven by the torque, do not feed back: the derived root must be
// the root of the G1 machine with the force projected by cos(alpha) (modal stiffness
// k/cos(alpha)), which plunge_regenerative computes from its hand-written eq 2-16 (contact
// stiffness 1e14 N/m in place of G5's rigid contact: 2e-6 relative in the series compliance).
TEST(TorsionalCoupling, DerivedRootIsTheProjectedG1Root) {
  for (double alpha_deg : {0.0, 20.0, 45.0}) {
    const MatchedPair m = matched_pair(alpha_deg, example().work_inertia_kg_m2);
    RootSearchOptions options;
    options.max_frequency_hz = 3000.0;
    const RightmostRoot reference = find_rightmost_root(PlungeCharacteristic(m.g1), options);
    const TorsionalCoupling g5(m.g5);
    const auto derived = g5.characteristic();
    ASSERT_TRUE(derived) << "G5 has a stability route";
    const RightmostRoot root = find_rightmost_root(*derived, options);
    ASSERT_TRUE(reference.certified);
    ASSERT_TRUE(root.certified) << root.certificate;
    EXPECT_NEAR(root.root.real(), reference.root.real(), 1e-4 * std::abs(reference.root)) << alpha_deg;
    EXPECT_NEAR(root.root.imag(), reference.root.imag(), 1e-5 * std::abs(reference.root)) << alpha_deg;
  }
}

// The process-conditions capability (feed_risk, suppression_map): at its own conditions the model
// is unchanged; a doubled width doubles b only; the removal coefficient follows G4's Kv/(1+Kv)
// computed here from the surface speeds by hand; the conditions' speeds and geometry are taken;
// and moving there and back returns the model (to rounding).
TEST(TorsionalCoupling, ProcessConditionsFollowG4AndRoundTrip) {
  const TorsionalCoupling g5(example());
  const ProcessConditionsModel* process = g5.process_conditions();
  ASSERT_NE(process, nullptr);
  const ProcessConditions own = process->nominal_conditions();
  EXPECT_DOUBLE_EQ(own.contact_width_mm, 35.0);
  EXPECT_DOUBLE_EQ(own.work_radius_mm, 50.0);
  EXPECT_DOUBLE_EQ(own.wheel_diameter_mm, 400.0);
  const Json example_table = TorsionalCoupling::info().example_params;
  const Json same = process->parameters_at(own, own, ProcessScaling{});
  for (const auto& [key, value] : example_table.items())
    EXPECT_DOUBLE_EQ(same.at(key).get<double>(), value.get<double>()) << key;

  ProcessConditions wider = own;
  wider.contact_width_mm *= 2.0;
  const Json w = process->parameters_at(own, wider, ProcessScaling{});
  EXPECT_DOUBLE_EQ(w.at("grinding_width_m").get<double>(), 0.07);
  EXPECT_DOUBLE_EQ(w.at("removal_coefficient_n_per_m2").get<double>(), 1.5e9);

  ProcessConditions at = own;
  at.work_speed_rpm = 110.0;
  at.wheel_speed_rpm = 1200.0;
  at.work_radius_mm = 40.0;
  const Json moved = process->parameters_at(own, at, ProcessScaling{});
  const auto kv = [](double work_radius_mm, double work_rpm, double wheel_diameter_mm, double wheel_rpm) {
    return (2.0 * work_radius_mm * work_rpm) / (wheel_diameter_mm * wheel_rpm);  // pi d n / 60 cancels
  };
  const double kv_own = kv(50.0, 55.0, 400.0, 1450.0), kv_at = kv(40.0, 110.0, 400.0, 1200.0);
  EXPECT_NEAR(moved.at("removal_coefficient_n_per_m2").get<double>(),
              1.5e9 * (kv_at / (1.0 + kv_at)) / (kv_own / (1.0 + kv_own)), 1e-12 * 1.5e9);
  EXPECT_DOUBLE_EQ(moved.at("work_speed_rpm").get<double>(), 110.0);
  EXPECT_DOUBLE_EQ(moved.at("wheel_speed_rpm").get<double>(), 1200.0);
  EXPECT_DOUBLE_EQ(moved.at("work_radius_m").get<double>(), 0.04);
  EXPECT_DOUBLE_EQ(moved.at("wheel_radius_m").get<double>(), 0.2);
  // Without the speed law only the width would scale lambda_w.
  ProcessScaling width_only;
  width_only.speed_dependent_stiffness = false;
  EXPECT_DOUBLE_EQ(process->parameters_at(own, at, width_only).at("removal_coefficient_n_per_m2").get<double>(), 1.5e9);

  const TorsionalCoupling there{ParamValues(moved)};
  const Json back = there.process_conditions()->parameters_at(at, own, ProcessScaling{});
  for (const auto& [key, value] : example_table.items())
    EXPECT_NEAR(back.at(key).get<double>(), value.get<double>(), 1e-12 * std::abs(value.get<double>())) << key;
}

// The example machine of `chatterlab describe torsional_coupling`: a certified root.
TEST(TorsionalCoupling, ExampleMachineHasACertifiedRoot) {
  const TorsionalCoupling g5{ParamValues(TorsionalCoupling::info().example_params)};
  const auto e = g5.characteristic();
  ASSERT_TRUE(e);
  RootSearchOptions options;
  options.max_frequency_hz = 3000.0;
  const RightmostRoot root = find_rightmost_root(*e, options);
  EXPECT_TRUE(root.certified) << root.certificate;
  EXPECT_GT(root.root.imag(), 0.0);
}

// Roots against the engine: bilateral runs of the G5 time-domain form with the example's soft
// torsional drives grow at the derived root's rate (within 2 %) at three force angles; the
// torsional speeds move during these runs (the model is not reduced to G1 by stiff drives). The
// runs start from 1e-18 m: the work turns at 5.8 rad/s, so 1 um of vibration already modulates
// its speed by about 9 % through the torque, and the speed correction, second order in the
// amplitude, would no longer be small (from 1e-6 m the run at 20 deg grows at 0.19 /s against
// the root's 11.23 /s; from 1e-12 and 1e-15 m, as with torsional inertias of 1e9 kg m^2, at
// 11.11 /s). Measured: 0 deg 12.56 root / 12.58 simulated (as the G1 test above), 20 deg
// 11.23 / 11.11, 45 deg 9.42 / 9.44 (at most 1.1 %: the fit over 1..2 s of a root cluster spaced by
// the 0.9 Hz work lattice; over 0.4..0.8 s the fit is 7 % low at 20 deg with or without torsion).
TEST(TorsionalCouplingAccuracy, SimulatedGrowthMatchesTheDerivedRoot) {
  for (double alpha_deg : {0.0, 20.0, 45.0}) {
    const MatchedPair m = matched_pair(alpha_deg, example().work_inertia_kg_m2);
    const TorsionalCoupling g5(m.g5);
    RootSearchOptions options;
    options.max_frequency_hz = 3000.0;
    const RightmostRoot root = find_rightmost_root(*g5.characteristic(), options);
    ASSERT_TRUE(root.certified) << root.certificate;
    const double growth = root.root.real();
    ASSERT_GT(growth, 0.5);
    SimulationSettings settings = linear_run(2.0);
    settings.disturbance = {1e-18, 0.0};
    const SimulationResult r = simulate(*g5.time_domain(), settings);
    ASSERT_EQ(r.status, "completed");
    if (alpha_deg > 0.0) {
      const auto& wheel = r.speed_rpm[static_cast<std::size_t>(Rotor::wheel)];
      EXPECT_GT(*std::max_element(wheel.begin(), wheel.end()) - *std::min_element(wheel.begin(), wheel.end()), 0.0);
    }
    const EnvelopeFit fit = fit_envelope(r.t_s, r.displacement_m, 1.0, 2.0);
    EXPECT_NEAR(fit.growth_rate_per_s, growth, 0.02 * growth) << alpha_deg << " deg, root " << root.root;
  }
}

}  // namespace
}  // namespace chatterlab
