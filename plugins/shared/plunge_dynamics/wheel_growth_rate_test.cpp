// G3 closed-form wheel growth rate (corrected eq 2-68) against exact roots of the wheel-only G1
// characteristic (plunge_regenerative, work_regeneration = false), and the per-revolution
// amplification of eqs 5-37..5-39. The table printed by ErrorAgainstExactRootsAcrossDampingAndFrequency is the
// one in docs/models/closed_forms.md.
#include "shared/plunge_dynamics/wheel_growth_rate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "chatterlab/roots.hpp"
#include "shared/plunge_dynamics/plunge_characteristic.hpp"

namespace chatterlab {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kModalStiffness = 5e7, kWheelWear = 2e8;

// One mode; kc placed so that the process line sits at 1/ratio of the compliance circle's
// leftmost point (ratio > 1: wheel-regenerative chatter, growth rising with ratio).
PlungeRegenerativeParameters wheel_only(double frequency_hz, double zeta, double ratio) {
  PlungeRegenerativeParameters p;
  p.wheel_speed_rpm = 1450.0;
  p.work_speed_rpm = 55.0;
  p.work_regeneration = false;
  p.wheel_wear_stiffness_n_per_m = kWheelWear;
  const double circle = 1.0 / (4.0 * zeta * (1.0 + zeta) * kModalStiffness);
  p.contact_stiffness_n_per_m = 1.0 / (circle / ratio - 0.5 / kWheelWear);
  p.modes = {{frequency_hz, zeta, kModalStiffness}};
  return p;
}

std::complex<double> normalised_structure(const StructuralMode& m, std::complex<double> s) {
  const double wn = kTwoPi * m.frequency_hz;
  return 1.0 / (s * s / (wn * wn) + 2.0 * m.damping_ratio * s / wn + 1.0);
}

struct Comparison {
  double rho_exact, rho_closed, rho_at_root, sigma, frequency_hz;
};

Comparison compare(const PlungeRegenerativeParameters& p) {
  PlungeCharacteristic e(p);
  RootSearchOptions options;
  options.max_frequency_hz = 3.0 * p.modes[0].frequency_hz;
  const RightmostRoot found = find_rightmost_root(e, options);
  EXPECT_TRUE(found.certified) << found.certificate;
  const double tg = 60.0 / p.wheel_speed_rpm;
  const double pp = p.wheel_wear_stiffness_n_per_m / p.modes[0].stiffness_n_per_m;
  const double q = p.wheel_wear_stiffness_n_per_m / p.contact_stiffness_n_per_m;
  const std::complex<double> s = found.root, jw(0.0, found.root.imag());
  return {tg * s.real() / kTwoPi,
          wheel_growth::growth_rate_per_rev(pp, q, normalised_structure(p.modes[0], jw)),
          wheel_growth::growth_rate_per_rev(pp, q, normalised_structure(p.modes[0], s)),
          s.real(), s.imag() / kTwoPi};
}

TEST(WheelGrowthRate, ExactWhenTheStructureIsTakenAtTheRoot) {
  // Eq 2-67 holds at the root itself: with Gm(s) the corrected 2-68 is the root's Tg sigma/2pi,
  // and the lattice phase is w Tg mod 2 pi. The printed 2-68 (extra 1/p^2) is not.
  for (double ratio : {0.7, 1.2, 2.0}) {
    const PlungeRegenerativeParameters p = wheel_only(250.0, 0.05, ratio);
    const Comparison c = compare(p);
    EXPECT_NEAR(c.rho_at_root, c.rho_exact, 1e-9 * std::abs(c.rho_exact) + 1e-13) << ratio;
    PlungeCharacteristic e(p);
    RootSearchOptions options;
    options.max_frequency_hz = 750.0;
    const std::complex<double> s = find_rightmost_root(e, options).root;
    const double pp = kWheelWear / kModalStiffness, q = kWheelWear / p.contact_stiffness_n_per_m;
    // e^{-2 pi rho} e^{-j w Tg} = 1 + 1/W is a complex identity; its phase at s:
    const std::complex<double> w = pp * normalised_structure(p.modes[0], s) + q;
    const double phase = std::fmod(s.imag() * 60.0 / 1450.0, kTwoPi);
    const double closed_phase = -std::arg(1.0 + 1.0 / w) < 0 ? -std::arg(1.0 + 1.0 / w) + kTwoPi
                                                             : -std::arg(1.0 + 1.0 / w);
    EXPECT_NEAR(std::remainder(phase - closed_phase, kTwoPi), 0.0, 1e-8);
    const double printed = -std::log((1.0 / (pp * pp)) * (1.0 + (1.0 + 2.0 * w.real()) / std::norm(w))) /
                           (4.0 * std::numbers::pi);
    EXPECT_GT(std::abs(printed - c.rho_exact), 0.1);  // p = 4 here: the printed form is off by ln(16)/(4 pi)
  }
  // Growth rate sign: stable below the axis criterion (ratio < 1), chatter above.
  EXPECT_LT(compare(wheel_only(250.0, 0.05, 0.7)).rho_exact, 0.0);
  EXPECT_GT(compare(wheel_only(250.0, 0.05, 1.5)).rho_exact, 0.0);
}

TEST(WheelGrowthRate, ErrorAgainstExactRootsAcrossDampingAndFrequency) {
  // The closed form takes Gm at j w (w = the exact root's frequency). Its error is first order in
  // sigma: sigma |dW/ds| |d rho/dW| (W = p Gm + q), estimated here by differences. The table
  // (docs/models/closed_forms.md) is printed; the test holds the error to that estimate and
  // the verdict (sign) to the exact one wherever |rho| exceeds the estimate.
  std::printf("%7s %5s %5s %11s %9s %11s %10s %9s %11s\n", "f_n[Hz]", "zeta", "ratio",
              "sigma[1/s]", "f[Hz]", "closed[1/s]", "err[1/s]", "rel.err", "1st-ord[1/s]");
  const double tg = 60.0 / 1450.0, to_sigma = kTwoPi / tg;
  for (double f : {100.0, 250.0, 1000.0}) {
    for (double zeta : {0.01, 0.05, 0.2}) {
      for (double ratio : {1.2, 2.0, 4.0}) {
        const PlungeRegenerativeParameters p = wheel_only(f, zeta, ratio);
        const Comparison c = compare(p);
        const double pp = kWheelWear / kModalStiffness, q = kWheelWear / p.contact_stiffness_n_per_m;
        const double w = kTwoPi * c.frequency_hz;
        auto gm = [&](double omega) { return normalised_structure(p.modes[0], {0.0, omega}); };
        auto rho = [&](std::complex<double> ww) { return wheel_growth::growth_rate_per_rev(1.0, 0.0, ww); };
        const std::complex<double> at = pp * gm(w) + q;
        const double dw_ds = pp * std::abs(gm(w * (1 + 1e-6)) - gm(w * (1 - 1e-6))) / (2e-6 * w);
        const double drho_dw = std::abs(rho(at + 1e-6 * std::abs(at)) - rho(at - 1e-6 * std::abs(at))) /
                                   (2e-6 * std::abs(at)) +
                               std::abs(rho(at + std::complex<double>(0, 1e-6 * std::abs(at))) -
                                        rho(at - std::complex<double>(0, 1e-6 * std::abs(at)))) /
                                   (2e-6 * std::abs(at));
        const double first_order = std::abs(c.sigma) * dw_ds * drho_dw;  // in rho
        const double error = std::abs(c.rho_closed - c.rho_exact);
        std::printf("%7.0f %5.2f %5.1f %11.4g %9.2f %11.4g %10.3g %9.3g %11.3g\n", f, zeta, ratio,
                    c.sigma, c.frequency_hz, c.rho_closed * to_sigma, error * to_sigma,
                    error / std::abs(c.rho_exact), first_order * to_sigma);
        EXPECT_LE(error, 2.0 * first_order + 1e-12) << f << " Hz, zeta " << zeta << ", ratio " << ratio;
        if (std::abs(c.rho_exact) > 2.0 * first_order) {
          EXPECT_EQ(c.rho_closed > 0.0, c.rho_exact > 0.0) << f << " Hz, zeta " << zeta;
        }
        // The rule of thumb in the docs: within 5 % while |sigma| < 0.02 zeta w_n; and for chatter
        // roots the closed form errs on the safe side (it overestimates the growth).
        if (std::abs(c.sigma) < 0.02 * zeta * kTwoPi * f) {
          EXPECT_LT(error / std::abs(c.rho_exact), 0.05) << f << " Hz, zeta " << zeta << ", ratio " << ratio;
        }
        if (c.rho_exact > 0.0) {
          EXPECT_GE(c.rho_closed, c.rho_exact) << f << " Hz, zeta " << zeta << ", ratio " << ratio;
        }
      }
    }
  }
}

TEST(WheelGrowthRate, AmplificationPerRevolution) {
  // 5-38: constant speed, n revolutions at rho_max; 5-39: a schedule with rho_i < rho_max
  // amplifies less; 5-36 recursion.
  const std::vector<double> constant(50, 0.01);
  EXPECT_NEAR(wheel_growth::amplitude_after_revolutions(2.0, constant),
              2.0 * std::exp(2.0 * std::numbers::pi * 50 * 0.01), 1e-12);
  std::vector<double> varying;
  for (int i = 0; i < 50; ++i) varying.push_back(0.01 * std::cos(kTwoPi * i / 25.0));
  double recursive = 2.0;
  for (double r : varying) recursive *= std::exp(2.0 * std::numbers::pi * r);  // 5-36
  EXPECT_NEAR(wheel_growth::amplitude_after_revolutions(2.0, varying), recursive, 1e-12 * recursive);
  EXPECT_LT(wheel_growth::amplitude_after_revolutions(2.0, varying),
            wheel_growth::amplitude_after_revolutions(2.0, constant));
  EXPECT_NEAR(wheel_growth::log_amplification(std::vector<double>(1000000, 1.0)),
              2.0 * std::numbers::pi * 1e6, 1e-3);  // no overflow in the log form
  EXPECT_EQ(wheel_growth::amplitude_after_revolutions(1.0, {}), 1.0);
}

}  // namespace
}  // namespace chatterlab

namespace chatterlab {
namespace {

// The closed form at one wheel speed (wheel_chatter_at_speed, the stability_map column): its
// lattice search finds the rightmost root's frequency, and its rho is the closed form at that
// frequency, so it agrees with the root as compare() does, at every speed of a sweep across lobes;
// rho_max bounds the root's rho everywhere.
TEST(WheelGrowthRate, AtOneSpeedTheLatticeSearchFindsTheRootsFrequency) {
  for (double rpm : {1200.0, 1333.0, 1450.0, 1575.0, 1700.0}) {
    SCOPED_TRACE(rpm);
    PlungeRegenerativeParameters p = wheel_only(180.0, 0.03, 1.3);
    p.wheel_speed_rpm = rpm;
    const Comparison root = compare(p);
    const PlungeCharacteristic e(p);
    const auto g3 = wheel_growth::wheel_chatter_at_speed(
        p.wheel_wear_stiffness_n_per_m, p.contact_stiffness_n_per_m,
        [&](double w) { return e.structural_compliance(std::complex<double>(0.0, w)); }, 60.0 / rpm, 720.0);
    EXPECT_NEAR(g3.chatter_frequency_hz, root.frequency_hz, 0.01 * root.frequency_hz);
    EXPECT_NEAR(g3.growth_rate_per_rev, root.rho_closed, 1e-3 * std::abs(root.rho_closed) + 1e-9);
    EXPECT_NEAR(g3.growth_rate_per_s, kTwoPi * g3.growth_rate_per_rev * rpm / 60.0, 1e-12);
    EXPECT_GE(g3.max_growth_rate_per_rev, root.rho_exact);
  }
}

}  // namespace
}  // namespace chatterlab
