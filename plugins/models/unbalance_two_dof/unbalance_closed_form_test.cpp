// G6 closed forms: the corrected undamped amplitude 3-3 against the damped 2 x 2 solve, limits
// (decoupling, resonance, anti-resonance), reciprocity, and Z = n_g/n_w.
#include "models/unbalance_two_dof/unbalance_closed_form.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace chatterlab {
namespace {

using namespace unbalance;

UnbalanceTwoDofParameters example() {
  UnbalanceTwoDofParameters p;
  p.wheel_mass_kg = 40.0;
  p.wheel_damping_n_s_per_m = 2000.0;
  p.wheel_support_stiffness_n_per_m = 5e7;
  p.work_mass_kg = 6.0;
  p.work_damping_n_s_per_m = 800.0;
  p.work_support_stiffness_n_per_m = 2e7;
  p.contact_stiffness_n_per_m = 1e8;
  p.grinding_stiffness_n_per_m = 5e7;
  p.unbalance_kg_m = 1e-4;
  p.wheel_speed_rpm = 1450.0;
  p.work_speed_rpm = 55.0;
  return p;
}

UnbalanceTwoDofParameters undamped(UnbalanceTwoDofParameters p) {
  p.wheel_damping_n_s_per_m = 0.0;
  p.work_damping_n_s_per_m = 0.0;
  return p;
}

TEST(UnbalanceClosedForm, UndampedAmplitudeAgreesWithTheSolveAndNaturalFrequenciesAreItsPoles) {
  const UnbalanceTwoDofParameters p = undamped(example());
  const NaturalFrequencies n = natural_frequencies(p);
  ASSERT_LT(n.lower_rad_s, n.upper_rad_s);
  const double k = coupling_stiffness_n_per_m(p);
  EXPECT_NEAR(k, 1e8 * 5e7 / 1.5e8, 1e-6);
  for (double w : {n.lower_rad_s, n.upper_rad_s}) {
    // det of the undamped 2 x 2 matrix vanishes at w_a1, w_a2 (3-4).
    const double a11 = k + p.wheel_support_stiffness_n_per_m - p.wheel_mass_kg * w * w;
    const double a22 = k + p.work_support_stiffness_n_per_m - p.work_mass_kg * w * w;
    EXPECT_NEAR(a11 * a22 - k * k, 0.0, 1e-9 * k * k);
  }
  for (double w : {100.0, 0.5 * n.lower_rad_s, 0.5 * (n.lower_rad_s + n.upper_rad_s), 3.0 * n.upper_rad_s}) {
    const SteadyState s = steady_state(p, w);
    EXPECT_NEAR(s.relative_m.real(), undamped_relative_amplitude_m(p, w), 1e-12 * std::abs(s.relative_m));
    EXPECT_EQ(s.relative_m.imag(), 0.0);
  }
  // Anti-resonance of the relative motion at w^2 = k2/m2 (numerator of 3-3).
  const double anti = std::sqrt(p.work_support_stiffness_n_per_m / p.work_mass_kg);
  EXPECT_NEAR(undamped_relative_amplitude_m(p, anti), 0.0, 1e-15);
  EXPECT_LT(std::abs(steady_state(example(), anti).relative_m),
            0.05 * std::abs(steady_state(example(), n.lower_rad_s).relative_m));
}

TEST(UnbalanceClosedForm, WeakCouplingDecouplesWheelAndWork) {
  UnbalanceTwoDofParameters p = example();
  p.contact_stiffness_n_per_m = 1e-3;  // k -> 0
  const NaturalFrequencies n = natural_frequencies(p);
  const double wheel_alone = std::sqrt(p.wheel_support_stiffness_n_per_m / p.wheel_mass_kg);
  const double work_alone = std::sqrt(p.work_support_stiffness_n_per_m / p.work_mass_kg);
  EXPECT_NEAR(n.lower_rad_s, std::min(wheel_alone, work_alone), 1e-6);
  EXPECT_NEAR(n.upper_rad_s, std::max(wheel_alone, work_alone), 1e-6);
  const double w = forcing_frequency_rad_s(p);
  const SteadyState s = steady_state(p, w);
  const std::complex<double> single = p.unbalance_kg_m * w * w /
      std::complex<double>(p.wheel_support_stiffness_n_per_m - p.wheel_mass_kg * w * w, p.wheel_damping_n_s_per_m * w);
  EXPECT_NEAR(std::abs(s.wheel_m - single), 0.0, 1e-9 * std::abs(single));
  EXPECT_LT(std::abs(s.work_m), 1e-9 * std::abs(single));
}

TEST(UnbalanceClosedForm, ResonancePeakIsBoundedByDampingAndNearTheNaturalFrequency) {
  const NaturalFrequencies n = natural_frequencies(example());
  // Undamped: grows without bound towards w_a1.
  EXPECT_GT(std::abs(undamped_relative_amplitude_m(example(), n.lower_rad_s * (1.0 - 1e-6))),
            1e4 * std::abs(undamped_relative_amplitude_m(example(), 0.5 * n.lower_rad_s)));
  // Damped: a finite peak close to w_a1 that halves when the damping doubles.
  auto peak = [&](double scale) {
    UnbalanceTwoDofParameters p = example();
    p.wheel_damping_n_s_per_m *= scale;
    p.work_damping_n_s_per_m *= scale;
    double best = 0.0, where = 0.0;
    for (int i = 0; i < 20001; ++i) {
      const double w = n.lower_rad_s * (0.9 + 0.2 * i / 20000.0);
      const double a = std::abs(steady_state(p, w).relative_m);
      if (a > best) best = a, where = w;
    }
    return std::pair{best, where};
  };
  const auto [light, light_at] = peak(0.1);
  const auto [heavy, heavy_at] = peak(0.2);
  EXPECT_NEAR(light_at, n.lower_rad_s, 1e-3 * n.lower_rad_s);
  EXPECT_NEAR(light / heavy, 2.0, 0.05);
  EXPECT_TRUE(std::isfinite(light));
  (void)heavy_at;
}

TEST(UnbalanceClosedForm, ReciprocityAndLobes) {
  // Maxwell reciprocity: the work-axis response to a force on the wheel is unchanged when the two
  // bodies swap their mass, damping and support stiffness.
  UnbalanceTwoDofParameters p = example(), swapped = example();
  std::swap(swapped.wheel_mass_kg, swapped.work_mass_kg);
  std::swap(swapped.wheel_damping_n_s_per_m, swapped.work_damping_n_s_per_m);
  std::swap(swapped.wheel_support_stiffness_n_per_m, swapped.work_support_stiffness_n_per_m);
  for (double w : {500.0, 1500.0, 3000.0}) {
    const std::complex<double> a = steady_state(p, w).work_m, b = steady_state(swapped, w).work_m;
    EXPECT_NEAR(std::abs(a - b), 0.0, 1e-12 * std::abs(a));
  }
  EXPECT_NEAR(natural_frequencies(p).lower_rad_s, natural_frequencies(swapped).lower_rad_s, 1e-9);
  EXPECT_NEAR(lobes_per_revolution(p), 1450.0 / 55.0, 1e-12);  // 26.36 lobes (3-6)
  EXPECT_NEAR(forcing_frequency_rad_s(p), 2.0 * std::numbers::pi * 1450.0 / 60.0, 1e-12);
  // Unbalance response: F = U w^2 at the wheel's own frequency.
  const SteadyState r = unbalance_response(p);
  const SteadyState direct = steady_state(p, forcing_frequency_rad_s(p));
  EXPECT_EQ(r.relative_m, direct.relative_m);
}

}  // namespace
}  // namespace chatterlab
