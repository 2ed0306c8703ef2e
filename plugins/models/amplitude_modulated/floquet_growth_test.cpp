// G7 Floquet growth rate (semi-discretised monodromy operator) against (1) the rightmost root of
// the constant-coefficient characteristic equation at Q = 0 (the wheel-only G1 model of
// plunge_regenerative for mu = 1; Newton on the raw equation for mu < 1), (2) a growth rate fitted
// to a direct fixed-step simulation of the same DDE (RK4 written here), and (3) the sideband
// structure of eq 3-18..3-20.
#include "models/amplitude_modulated/floquet_growth.hpp"
#include "models/amplitude_modulated/g7_test_case.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "chatterlab/roots.hpp"
#include "shared/plunge_dynamics/plunge_characteristic.hpp"

namespace chatterlab {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

using testing::g7_base_case;

// 1 + Kg (H + 1/Kc)(1 - mu e^{-sT}) = 0 (eq 3-14 with Q = 0), H = 1/(m s^2 + c s + k).
std::complex<double> raw(const AmplitudeModulatedParameters& p, std::complex<double> s) {
  const std::complex<double> h = 1.0 / (p.mass_kg * s * s + p.damping_n_s_per_m * s + p.stiffness_n_per_m);
  return 1.0 + p.grinding_stiffness_n_per_m * (h + 1.0 / p.contact_stiffness_n_per_m) *
                   (1.0 - p.overlap_factor * std::exp(-s * 60.0 / p.wheel_speed_rpm));
}

// Rightmost root by Newton (numerical derivative) from every wheel-lattice point and the
// structural pole up to 2 kHz: a brute-force reference independent of the solver.
std::complex<double> rightmost_by_newton(const AmplitudeModulatedParameters& p) {
  std::vector<std::complex<double>> guesses;
  const double t = 60.0 / p.wheel_speed_rpm;
  for (int n = 0; n * kTwoPi / t < kTwoPi * 2000.0; ++n) guesses.emplace_back(0.0, n * kTwoPi / t);
  guesses.emplace_back(0.0, std::sqrt(p.stiffness_n_per_m / p.mass_kg));
  std::complex<double> best(-1e300, 0.0);
  for (std::complex<double> s : guesses) {
    for (int it = 0; it < 100; ++it) {
      const std::complex<double> d = 1e-6 * (1.0 + std::abs(s));
      const std::complex<double> step = raw(p, s) / ((raw(p, s + d) - raw(p, s - d)) / (2.0 * d));
      s -= step;
      if (std::abs(step) < 1e-13 * std::abs(s)) break;
    }
    if (std::abs(raw(p, s)) < 1e-9 && s.real() > best.real()) best = s;
  }
  return best;
}

// Direct time stepping: RK4 on (x1, v1), the relative displacement x stored on the step grid and
// read one period back (dt divides T exactly, so the delayed value is a stored sample; RK4's
// half-step stages use the mean of the two neighbours, accurate to O(dt^2) at dt = T/4000).
// Returns the growth rate fitted to ln(max |x1| per period) over the last half of the run.
double simulated_growth(const AmplitudeModulatedParameters& p, int periods) {
  const double T = 60.0 / p.wheel_speed_rpm, w0 = kTwoPi / T;
  const int per = 4000;
  const double dt = T / per, q = p.grinding_stiffness_n_per_m / p.contact_stiffness_n_per_m;
  std::vector<double> x_hist(static_cast<std::size_t>(per * (periods + 1) + 1), 0.0);
  // Initial history: a small 250 Hz wave on the wheel surface.
  for (int i = 0; i <= per; ++i) x_hist[static_cast<std::size_t>(i)] = 1e-6 * std::sin(1571.0 * (i - per) * dt);
  double x1 = 0.0, v1 = 0.0;
  auto g = [&](double t) { return 1.0 + p.modulation_depth * std::sin(w0 * t); };
  auto accel = [&](double t, double x, double v, double delayed) {
    const double kappa = p.grinding_stiffness_n_per_m * g(t) / (1.0 + q * g(t));
    const double force = -kappa * (x - p.overlap_factor * delayed);
    return (force - p.damping_n_s_per_m * v - p.stiffness_n_per_m * x) / p.mass_kg;
  };
  std::vector<double> peak(static_cast<std::size_t>(periods), 0.0);
  for (int i = 0; i < per * periods; ++i) {
    const double t = i * dt;
    const double d0 = x_hist[static_cast<std::size_t>(i)], d1 = x_hist[static_cast<std::size_t>(i + 1)];
    const double dm = 0.5 * (d0 + d1);
    const double k1x = v1, k1v = accel(t, x1, v1, d0);
    const double k2x = v1 + 0.5 * dt * k1v, k2v = accel(t + 0.5 * dt, x1 + 0.5 * dt * k1x, k2x, dm);
    const double k3x = v1 + 0.5 * dt * k2v, k3v = accel(t + 0.5 * dt, x1 + 0.5 * dt * k2x, k3x, dm);
    const double k4x = v1 + dt * k3v, k4v = accel(t + dt, x1 + dt * k3x, k4x, d1);
    x1 += dt / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v1 += dt / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    const double qg = q * g(t + dt);
    x_hist[static_cast<std::size_t>(i + 1 + per)] = (x1 + qg * p.overlap_factor * d1) / (1.0 + qg);
    auto& pk = peak[static_cast<std::size_t>(i / per)];
    pk = std::max(pk, std::abs(x1));
  }
  // Least-squares slope of ln(peak) against time over the second half.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int count = 0;
  for (int k = periods / 2; k < periods; ++k) {
    const double tk = k * T, yk = std::log(peak[static_cast<std::size_t>(k)]);
    sx += tk, sy += yk, sxx += tk * tk, sxy += tk * yk;
    ++count;
  }
  return (count * sxy - sx * sy) / (count * sxx - sx * sx);
}

TEST(FloquetGrowth, UnmodulatedEqualsTheRightmostRootOfTheWheelOnlyG1Model) {
  for (double grinding : {4e6, 1e7}) {
    AmplitudeModulatedParameters p = g7_base_case();
    p.grinding_stiffness_n_per_m = grinding;
    const G7FloquetResult f = floquet_growth(p);
    ASSERT_TRUE(f.converged) << f.growth_rate_change_per_s;
    PlungeRegenerativeParameters g1;
    g1.wheel_speed_rpm = p.wheel_speed_rpm;
    g1.work_speed_rpm = 55.0;
    g1.work_regeneration = false;
    g1.contact_stiffness_n_per_m = p.contact_stiffness_n_per_m;
    g1.wheel_wear_stiffness_n_per_m = p.grinding_stiffness_n_per_m;
    g1.modes = {{std::sqrt(p.stiffness_n_per_m / p.mass_kg) / kTwoPi,
                 p.damping_n_s_per_m / (2.0 * std::sqrt(p.stiffness_n_per_m * p.mass_kg)), p.stiffness_n_per_m}};
    RootSearchOptions options;
    options.max_frequency_hz = 2000.0;
    const RightmostRoot root = find_rightmost_root(PlungeCharacteristic(g1), options);
    ASSERT_TRUE(root.certified) << root.certificate;
    EXPECT_NEAR(f.growth_rate_per_s, root.root.real(), 0.01 + 2e-3 * std::abs(root.root.real()))
        << "kg b " << grinding;
    EXPECT_NEAR(f.carrier_frequency_hz, root.root.imag() / kTwoPi, 1e-6 * root.root.imag())
        << "kg b " << grinding;
    // No modulation: one harmonic only.
    for (const FloquetSideband& s : f.sidebands) {
      if (s.order != 0) {
        EXPECT_LT(s.relative_amplitude, 1e-6) << s.order;
      }
    }
  }
}

TEST(FloquetGrowth, PartialOverlapEqualsNewtonOnTheRawEquation) {
  AmplitudeModulatedParameters p = g7_base_case();
  p.overlap_factor = 0.8;
  p.grinding_stiffness_n_per_m = 2e7;
  const G7FloquetResult f = floquet_growth(p);
  ASSERT_TRUE(f.converged);
  const std::complex<double> s = rightmost_by_newton(p);
  EXPECT_NEAR(f.growth_rate_per_s, s.real(), 0.01 + 2e-3 * std::abs(s.real()));
  EXPECT_NEAR(f.carrier_frequency_hz, s.imag() / kTwoPi, 1e-6 * s.imag());
}

TEST(FloquetGrowthAccuracy, ModulationAgreesWithDirectTimeStepping) {
  for (double depth : {0.0, 0.3, 0.6}) {
    AmplitudeModulatedParameters p = g7_base_case();
    p.modulation_depth = depth;
    const G7FloquetResult f = floquet_growth(p);
    ASSERT_TRUE(f.converged) << depth;
    const double fitted = simulated_growth(p, 60);
    EXPECT_NEAR(fitted, f.growth_rate_per_s, 0.05 + 0.02 * std::abs(f.growth_rate_per_s))
        << "Q " << depth;
  }
}

TEST(FloquetGrowth, SidebandsAreSpacedByTheWheelFrequencyAndGrowWithQ) {
  AmplitudeModulatedParameters p = g7_base_case();
  p.modulation_depth = 0.05;
  const G7FloquetResult small = floquet_growth(p);
  p.modulation_depth = 0.1;
  const G7FloquetResult twice = floquet_growth(p);
  const double wheel_hz = 1450.0 / 60.0;  // 24.17 Hz
  ASSERT_EQ(twice.sidebands.size(), 7u);
  for (std::size_t i = 1; i < twice.sidebands.size(); ++i)
    EXPECT_NEAR(twice.sidebands[i].frequency_hz - twice.sidebands[i - 1].frequency_hz, wheel_hz, 1e-9);
  EXPECT_DOUBLE_EQ(twice.sidebands[3].relative_amplitude, 1.0);
  // First sidebands are first order in Q (eq 3-9: m/2 per side), second ones second order.
  for (std::size_t i : {2u, 4u}) {
    EXPECT_GT(twice.sidebands[i].relative_amplitude, 1e-3);
    EXPECT_NEAR(twice.sidebands[i].relative_amplitude / small.sidebands[i].relative_amplitude, 2.0, 0.1);
  }
  for (std::size_t i : {1u, 5u})
    EXPECT_NEAR(twice.sidebands[i].relative_amplitude / small.sidebands[i].relative_amplitude, 4.0, 0.4);
}

TEST(FloquetGrowth, WithoutRegenerationItIsTheStiffenedOscillator) {
  // mu = 0: no memory; at Q = 0 the force is -kappa x1 with kappa = kg b/(1 + kg/kc), so the
  // solution decays at exactly -c/(2m) and rings at sqrt((k + kappa)/m - (c/2m)^2).
  AmplitudeModulatedParameters p = g7_base_case();
  p.overlap_factor = 0.0;
  const G7FloquetResult f = floquet_growth(p);
  ASSERT_TRUE(f.converged);
  const double decay = -p.damping_n_s_per_m / (2.0 * p.mass_kg);
  EXPECT_NEAR(f.growth_rate_per_s, decay, 1e-6 * std::abs(decay));
  const double kappa = p.grinding_stiffness_n_per_m / (1.0 + p.grinding_stiffness_n_per_m / p.contact_stiffness_n_per_m);
  const double ring = std::sqrt((p.stiffness_n_per_m + kappa) / p.mass_kg - decay * decay);
  EXPECT_NEAR(f.carrier_frequency_hz, ring / kTwoPi, 1e-6 * ring);
}

TEST(FloquetGrowth, RejectsParametersOutsideTheModel) {
  AmplitudeModulatedParameters p = g7_base_case();
  p.modulation_depth = 1.0;
  EXPECT_THROW(floquet_growth(p), std::invalid_argument);
  p = g7_base_case();
  p.overlap_factor = 1.5;
  EXPECT_THROW(floquet_growth(p), std::invalid_argument);
}

}  // namespace
}  // namespace chatterlab
