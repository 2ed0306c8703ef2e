// Known answers for the S1-S3 quantifications (MODELS.md S1-S3, book 5-23..5-45).
#include "study_kinds/suppression_map/suppression_measures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "chatterlab/suppression.hpp"

namespace chatterlab::suppression_measures {
namespace {

constexpr double kPi = std::numbers::pi;

// The sinusoidal law of the registered variable_speed plugin (reached by name through the
// registry, as a study names it).
std::shared_ptr<const ModulationLaw> sine_law(double amplitude, double frequency) {
  const Json params = {{"target", "wheel_speed"}, {"shape", "sinusoidal"}, {"amplitude_ratio", amplitude},
                       {"frequency_hz", frequency}};
  struct Nowhere final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  };
  const auto& entry = suppression_registry().at("variable_speed");
  const Json validated = validate_params(params, entry.info.params, "suppression", Nowhere());
  return entry.create(ParamValues(validated))->law(10.0);
}

// ------------------------------------------------------------------ S2

TEST(SuppressionS2, RevolutionBoundariesAreWholeTurnsOfTheModulatedRotor) {
  auto law = sine_law(0.3, 1.7);
  const double mean_rpm = 1200.0, end = 2.0;
  const std::vector<double> b = revolution_boundaries(*law, mean_rpm, end);
  ASSERT_GT(b.size(), 30u);
  EXPECT_EQ(b.front(), 0.0);
  EXPECT_EQ(b.back(), end);
  for (std::size_t i = 1; i + 1 < b.size(); ++i)
    EXPECT_NEAR(mean_rpm / 60.0 * law->level_integral(b[i]), static_cast<double>(i), 1e-9) << i;
  // 40 turns at the mean speed in 2 s; the sine's integral over 3.4 periods adds a fraction.
  EXPECT_NEAR(static_cast<double>(b.size() - 2), std::floor(mean_rpm / 60.0 * law->level_integral(end)), 0.0);
}

TEST(SuppressionS2, ConstantGrowthGives538AndALinearGrowthAveragesOut) {
  // 5-38: constant rho gives ln(A_n/A_0) = sigma T.
  auto flat = sine_law(0.0, 1.0);
  const std::vector<double> b = revolution_boundaries(*flat, 1500.0, 2.0);
  EXPECT_NEAR(growth_averaging_log_amplification(*flat, b, [](double) { return 3.0; }), 6.0, 1e-12);
  // sigma linear in the level: sum_i sigma(level_i) T_i = sigma0 T + c (integral of level - T),
  // and the sine's integral over whole periods is T: the modulation has no net effect.
  auto law = sine_law(0.2, 2.0);  // 4 whole periods in 2 s
  const std::vector<double> bm = revolution_boundaries(*law, 1500.0, 2.0);
  EXPECT_NEAR(growth_averaging_log_amplification(*law, bm, [](double level) { return 3.0 + 40.0 * (level - 1.0); }),
              6.0, 1e-9);
  // A concave sigma (the rightmost root at a lobe peak) makes the average smaller: 5-39 < 5-38.
  const double peaked = growth_averaging_log_amplification(
      *law, bm, [](double level) { return 3.0 - 200.0 * (level - 1.0) * (level - 1.0); });
  // Mean of (0.2 sin)^2 = 0.02 -> 3 - 200*0.02 = -1 per s over 2 s; averaging the level over
  // each 40 ms revolution first shrinks the sine by sinc(pi f Tg) = 0.9895 (its square by 2 %):
  // about -1.83.
  EXPECT_NEAR(peaked, -1.83, 0.05);
}

TEST(SuppressionS2, PhaseDriftIsTheRegenerativePhaseChangePerRevolution) {
  // 200 Hz chatter, wheel 1500 rpm (Tg = 40 ms, 8 waves): a 1 % speed change moves w Tg by
  // 2 pi * 8 * 0.01.
  EXPECT_NEAR(quasi_static_phase_drift_rad(200.0, 1500.0, 0.01), 2 * kPi * 8 * 0.01, 1e-12);
}

// ------------------------------------------------------------------ S3

TEST(SuppressionS3, PhaseLagOfTheWavesPerRevolution) {
  // 60 f / n = J + eps (5-40), eps in [-0.5, 0.5), phi = -2 pi eps (corrected sign).
  EXPECT_NEAR(phase_lag_rad(10.25, 60.0), -kPi / 2, 1e-12);          // 10.25 waves: leads
  EXPECT_NEAR(phase_lag_rad(10.75, 60.0), kPi / 2, 1e-12);           // 11 - 0.25: lags
  EXPECT_NEAR(phase_lag_rad(12.0 * 55.0 / 60.0, 55.0), 0.0, 1e-9);   // whole waves: no lag
  EXPECT_NEAR(phase_lag_rad(7.5, 60.0), kPi, 1e-12);                 // eps = -0.5
}

TEST(SuppressionS3, PhaseLagFollowsTheSurfaceKinematics) {
  // The sign, from first principles: vibration y(t) = cos(w t); at a body-fixed angle the
  // current pass leaves y(t), the previous pass y(t - T). The lag phi of the current wave
  // behind the previous one solves y(t) = y0(t - phi/w) for the wave y0(t) = y(t - T), i.e.
  // cos(w t) = cos(w t - w T - phi) for all t: phi = -w T (mod 2 pi).
  const double f = 231.7, rpm = 60.0, period = 60.0 / rpm;
  double phi = -2 * kPi * f * period;
  phi = std::remainder(phi, 2 * kPi);
  EXPECT_NEAR(phase_lag_rad(f, rpm), phi, 1e-9);
  for (double t : {0.0, 0.3, 1.7}) {
    const double w = 2 * kPi * f;
    EXPECT_NEAR(std::cos(w * t), std::cos(w * (t - period) - phase_lag_rad(f, rpm)), 1e-6);
  }
}

TEST(SuppressionS3, EnergyPerCycleMatchesTheWorkIntegralOf545) {
  // Previous wave x0 = X cos(wt), current x = X cos(wt - phi), dF = C' (x - x0) (5-41, 5-44). The
  // force pushes the wheel out of the work, so the work done on the vibration over one cycle is
  // -closed-integral dF dx; quadrature against pi C' X^2 sin(phi) (5-45).
  const double c = 3.0e7, x_amp = 2.0e-6;
  for (double phi : {-2.5, -1.0, -0.1, 0.0, 0.4, kPi / 2, 2.9}) {
    const int n = 20000;
    double work = 0.0;
    for (int i = 0; i < n; ++i) {
      const double th = 2 * kPi * (i + 0.5) / n, dth = 2 * kPi / n;
      const double df = c * x_amp * (std::cos(th - phi) - std::cos(th));
      const double dx = -x_amp * std::sin(th - phi) * dth;
      work -= df * dx;
    }
    EXPECT_NEAR(energy_per_cycle_j(c, x_amp, phi), work, 1e-9 * c * x_amp * x_amp) << phi;
  }
  EXPECT_GT(energy_per_cycle_j(c, x_amp, 1.0), 0.0);   // lagging wave: exciting zone
  EXPECT_LT(energy_per_cycle_j(c, x_amp, -1.0), 0.0);  // leading wave: suppressing zone
}

TEST(SuppressionS3, ConstantSpeedStaysInOneZoneAndASweepSpendsHalfItsTimeInEach) {
  const double f = 200.0;
  const EnergyBalance fixed = energy_balance(f, [](double) { return 56.0; }, 0.0, 2.0, 1000);
  EXPECT_NEAR(fixed.mean_normalised_energy, std::sin(phase_lag_rad(f, 56.0)), 1e-12);
  EXPECT_EQ(fixed.exciting_fraction, std::sin(phase_lag_rad(f, 56.0)) > 0 ? 1.0 : 0.0);
  // A speed whose wave count 60 f/n falls linearly through 5 whole waves: eps is uniform, so the
  // mean of sin(phi) is 0 and the exciting zone holds half the time.
  auto sweep = [&](double t) { return 60.0 * f / (220.0 - 5.0 * t / 2.0); };
  const EnergyBalance b = energy_balance(f, sweep, 0.0, 2.0, 100000);
  EXPECT_NEAR(b.mean_normalised_energy, 0.0, 1e-4);
  EXPECT_NEAR(b.exciting_fraction, 0.5, 1e-3);
}

// ------------------------------------------------------------------ S1

FeedChatterModel single_mode() {
  FeedChatterModel m;
  const double wn = 2 * kPi * 180.0;
  m.modal_stiffness_n_per_m = 5.0e7;
  m.modal_mass_kg = m.modal_stiffness_n_per_m / (wn * wn);
  m.contact_stiffness_n_per_m = 1.0e8;
  m.wheel_wear_stiffness_n_per_m = 5.0e8;
  m.work_removal_stiffness_n_per_m = 4.0e7;
  m.thickness_exponent = 0.6;
  return m;
}

TEST(SuppressionS1, RealPartOfTheRegenerationTermIsOneHalf) {
  // The step the printed 5-24 gets wrong: 1/(1 - e^{-j theta}) = 1/2 - (j/2) cot(theta/2).
  for (double th : {0.3, 1.0, 2.5, 4.0, 5.9}) {
    const std::complex<double> v = 1.0 / (1.0 - std::exp(std::complex<double>(0.0, -th)));
    EXPECT_NEAR(v.real(), 0.5, 1e-12);
    EXPECT_NEAR(v.imag(), -0.5 / std::tan(th / 2.0), 1e-12);
  }
}

TEST(SuppressionS1, FrequencySolvesTheRealPartBalanceOf526) {
  // 5-26 with 5-24 corrected: Re H(jw) = (k - m w^2)/((k - m w^2)^2 + (c w)^2)
  // = -(1/kc + 1/(2 kg) + 1/(2 kw)). Solve it exactly (bisection on w above wn) and compare with
  // the closed form, which drops (c w)^2 (error ~ zeta^2 relative).
  FeedChatterModel m = single_mode();
  for (double da : {-0.3, 0.0, 0.4}) {
    for (double zeta : {0.002, 0.02}) {
      const double s = 1.0 - 0.5 * m.thickness_exponent * da;
      const double process = 1.0 / (m.contact_stiffness_n_per_m * s) + 0.5 / (m.wheel_wear_stiffness_n_per_m * s) +
                             0.5 / m.work_removal_stiffness_n_per_m;
      const double wn = std::sqrt(m.modal_stiffness_n_per_m / m.modal_mass_kg);
      const double c = 2 * zeta * std::sqrt(m.modal_stiffness_n_per_m * m.modal_mass_kg);
      auto balance = [&](double w) {
        const double re = m.modal_stiffness_n_per_m - m.modal_mass_kg * w * w;
        return re / (re * re + c * c * w * w) + process;
      };
      // Re H is smallest at w = wn sqrt(1 + 2 zeta); 5-28 is the root above it (w > wn).
      double lo = wn * std::sqrt(1.0 + 2.0 * zeta), hi = wn * 10.0;
      ASSERT_LT(balance(lo) * balance(hi), 0.0);
      for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (balance(lo) * balance(mid) <= 0.0 ? hi : lo) = mid;
      }
      const double exact_hz = 0.5 * (lo + hi) / (2 * kPi);
      const double closed_hz = feed_chatter_frequency_hz(m, da);
      EXPECT_NEAR(closed_hz / exact_hz - 1.0, 0.0, 30.0 * zeta * zeta + 1e-9) << "da/a " << da << " zeta " << zeta;
      // The printed 2m/kg, 2m/kw form does not solve the balance.
      EXPECT_GT(std::abs(feed_chatter_frequency_printed_hz(m, da) / exact_hz - 1.0), 0.02);
    }
  }
}

TEST(SuppressionS1, AThickerCutLowersTheChatterFrequency) {
  // kc, kg = k0 (1 - eps/2 da/a): a thicker cut (da/a > 0) softens the contact, and w moves
  // toward wn; at eps = 0 the feed has no effect.
  FeedChatterModel m = single_mode();
  EXPECT_LT(feed_chatter_frequency_hz(m, 0.3), feed_chatter_frequency_hz(m, 0.0));
  EXPECT_GT(feed_chatter_frequency_hz(m, -0.3), feed_chatter_frequency_hz(m, 0.0));
  EXPECT_GT(feed_chatter_frequency_hz(m, 0.3), 180.0);
  m.thickness_exponent = 0.0;
  EXPECT_EQ(feed_chatter_frequency_hz(m, 0.3), feed_chatter_frequency_hz(m, 0.0));
  // 5-28 at da/a = 0: w^2 = wn^2 + 1/(m (1/kc + 1/(2kg) + 1/(2kw))).
  m = single_mode();
  const double wn2 = m.modal_stiffness_n_per_m / m.modal_mass_kg;
  const double process = 1.0 / 1.0e8 + 0.5 / 5.0e8 + 0.5 / 4.0e7;
  EXPECT_NEAR(feed_chatter_frequency_hz(m, 0.0), std::sqrt(wn2 + 1.0 / (m.modal_mass_kg * process)) / (2 * kPi), 1e-9);
  // A switched-off chain (stiffness +inf) drops its term.
  m.wheel_wear_stiffness_n_per_m = std::numeric_limits<double>::infinity();
  const double no_wheel = 1.0 / 1.0e8 + 0.5 / 4.0e7;
  EXPECT_NEAR(feed_chatter_frequency_hz(m, 0.0), std::sqrt(wn2 + 1.0 / (m.modal_mass_kg * no_wheel)) / (2 * kPi), 1e-9);
}

}  // namespace
}  // namespace chatterlab::suppression_measures
