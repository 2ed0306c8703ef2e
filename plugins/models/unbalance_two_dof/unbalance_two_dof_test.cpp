// Known answers for unbalance_two_dof (MODELS.md G6): the simulated steady forced response
// against the exact steady state of the linear two-DOF system (a 2x2 complex solve here), and
// Z = n_g / n_w lobes per revolution on the work surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/spectrum.hpp"
#include "models/unbalance_two_dof/unbalance_closed_form.hpp"
#include "models/unbalance_two_dof/unbalance_two_dof.hpp"

namespace chatterlab {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The model's example (m1 60 kg, c1 6000 N s/m, k1 5e7 N/m; m2 20 kg, c2 3000 N s/m, k2 3e7 N/m;
// kc 1e8, kg 1e9 N/m; U 1e-4 kg m; 1450/55 rpm).
UnbalanceTwoDofParameters example() {
  return UnbalanceTwoDof(ParamValues(UnbalanceTwoDof::info().example_params)).parameters();
}

// Exact steady state: [K - w^2 M + i w C] X = [U w^2, 0] (Cramer's rule), relative X1 + X2.
std::complex<double> exact_relative_amplitude(const UnbalanceTwoDofParameters& p) {
  using C = std::complex<double>;
  const double w = kTwoPi * p.wheel_speed_rpm / 60.0, k = unbalance::coupling_stiffness_n_per_m(p);
  const C a11(k + p.wheel_support_stiffness_n_per_m - p.wheel_mass_kg * w * w, w * p.wheel_damping_n_s_per_m);
  const C a22(k + p.work_support_stiffness_n_per_m - p.work_mass_kg * w * w, w * p.work_damping_n_s_per_m);
  const C a12 = k, a21 = k;
  const C f = p.unbalance_kg_m * w * w;
  const C det = a11 * a22 - a12 * a21;
  const C x1 = f * a22 / det, x2 = -a21 * f / det;
  return x1 + x2;
}

SimulationResult run(const UnbalanceTwoDofParameters& p, double duration_s) {
  UnbalanceTwoDofTimeDomain model(p);
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = 20000.0;
  s.disturbance = {0.0, 0.0};
  s.one_sided_contact = false;
  s.snapshot_times_s = {duration_s};
  return simulate(model, s);
}

// Complex amplitude X of x = Re(X e^{iwt}) = Re X cos wt - Im X sin wt: least-squares fit of
// a cos wt + b sin wt to the displacement after from_s (transients decayed).
std::complex<double> steady_amplitude(const SimulationResult& r, double w, double from_s) {
  double cc = 0, ss = 0, cs = 0, xc = 0, xs = 0;
  for (std::size_t i = 0; i < r.t_s.size(); ++i) {
    if (r.t_s[i] < from_s) continue;
    const double c = std::cos(w * r.t_s[i]), s = std::sin(w * r.t_s[i]), x = r.displacement_m[i];
    cc += c * c; ss += s * s; cs += c * s; xc += x * c; xs += x * s;
  }
  const double det = cc * ss - cs * cs;
  return {(xc * ss - xs * cs) / det, -(xs * cc - xc * cs) / det};
}

TEST(UnbalanceTwoDof, SteadyForcedResponseMatchesTheExactTwoByTwoSolution) {
  const auto p = example();
  const SimulationResult r = run(p, 2.2);
  ASSERT_EQ(r.status, "completed");
  // Least-squares fit of a cos wt + b sin wt over the last second (transients decayed: the
  // slowest mode decays at ~ c/(2m) = 50 /s).
  const double w = kTwoPi * p.wheel_speed_rpm / 60.0;
  const std::complex<double> fitted = steady_amplitude(r, w, 1.2);
  const double a = fitted.real(), b = -fitted.imag();
  const std::complex<double> exact = exact_relative_amplitude(p);
  // x = Re(X e^{iwt}) = Re X cos wt - Im X sin wt
  EXPECT_NEAR(std::hypot(a, b), std::abs(exact), 1e-4 * std::abs(exact));
  EXPECT_NEAR(a, exact.real(), 1e-3 * std::abs(exact));
  EXPECT_NEAR(b, -exact.imag(), 1e-3 * std::abs(exact));
}

// Cross-route: the simulated steady state against the closed form's unbalance_response (the
// book's 3-1..3-5 damped solve, written independently of this test's Cramer solve): x1 + x2.
TEST(UnbalanceTwoDof, SimulatedSteadyStateAgreesWithTheClosedForm) {
  const auto p = example();
  const SimulationResult r = run(p, 2.2);
  ASSERT_EQ(r.status, "completed");
  const double w = unbalance::forcing_frequency_rad_s(p);
  const std::complex<double> simulated = steady_amplitude(r, w, 1.2);
  const unbalance::SteadyState closed = unbalance::unbalance_response(p);
  const std::complex<double> relative = closed.wheel_m + closed.work_m;
  EXPECT_LT(std::abs(simulated - relative), 1e-3 * std::abs(relative));
  // The closed form's surface motion is the grinding spring's share of it, (x1 + x2)/(1 + kg/kc).
  EXPECT_LT(std::abs(closed.relative_m * (1.0 + p.grinding_stiffness_n_per_m / p.contact_stiffness_n_per_m) - relative),
            1e-12 * std::abs(relative));
}

TEST(UnbalanceTwoDof, WorkSurfaceCarriesWheelOverWorkSpeedLobes) {
  const auto p = example();
  const SimulationResult r = run(p, 2.5);
  ASSERT_EQ(r.snapshots.size(), 1u);
  const auto& profile = r.snapshots[0].surface_m[static_cast<std::size_t>(Rotor::work)];
  // Spectrum over angle: sample rate = samples per revolution, so frequencies read as
  // undulations per revolution.
  Spectrum s = amplitude_spectrum(profile, static_cast<double>(profile.size()));
  auto peak = find_peaks(s, 1);
  ASSERT_EQ(peak.size(), 1u);
  const double z = p.wheel_speed_rpm / p.work_speed_rpm;  // 26.36 lobes
  EXPECT_NEAR(peak[0].frequency_hz, z, 0.5);
  // The lobes' height is the forced amplitude.
  const auto [lo, hi] = std::minmax_element(profile.begin(), profile.end());
  EXPECT_NEAR(0.5 * (*hi - *lo), std::abs(exact_relative_amplitude(p)), 0.02 * std::abs(exact_relative_amplitude(p)));
}

}  // namespace
}  // namespace chatterlab
