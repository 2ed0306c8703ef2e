// Known answers for the Thompson criteria (MODELS.md G2): the closed forms against each other
// (2-43/2-48, 2-51/2-64, 2-65), against the frequency response of the single mode, and against the
// rightmost root of the same model's characteristic function (G1 eq 2-16).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

#include "chatterlab/errors.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/roots.hpp"
#include "models/thompson/thompson.hpp"

namespace chatterlab {
namespace {

using namespace thompson;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The example: one 251.6 Hz mode, zeta 0.05, kc 1e8, kg 1e9, kw 2e8 N/m, 1450/55 rpm.
ThompsonParameters example() {
  ThompsonParameters p;
  p.mass_kg = 20.0;
  p.stiffness_n_per_m = 5.0e7;
  p.damping_n_s_per_m = 0.1 * std::sqrt(5.0e7 * 20.0);
  p.wheel_wear_compliance_m_per_n = 1e-9;
  p.work_removal_compliance_m_per_n = 5e-9;
  p.contact_compliance_m_per_n = 1e-8;
  p.wheel_speed_rpm = 1450.0;
  p.work_speed_rpm = 55.0;
  return p;
}

std::complex<double> compliance(const ThompsonParameters& p, double w) {
  return 1.0 / std::complex<double>(p.stiffness_n_per_m - p.mass_kg * w * w, p.damping_n_s_per_m * w);
}

// min over w of Re H(jw), by a dense scan refined by golden section (the compliance circle).
double leftmost_real_compliance(const ThompsonParameters& p) {
  const double wn = std::sqrt(p.stiffness_n_per_m / p.mass_kg);
  double best_w = wn, best = 0.0;
  for (int i = 1; i < 20000; ++i) {
    const double w = wn * (1.0 + 2.0 * i / 20000.0);
    if (compliance(p, w).real() < best) best = compliance(p, w).real(), best_w = w;
  }
  double lo = best_w - 2e-4 * wn, hi = best_w + 2e-4 * wn;
  for (int it = 0; it < 200; ++it) {
    const double a = lo + 0.382 * (hi - lo), b = hi - 0.382 * (hi - lo);
    if (compliance(p, a).real() < compliance(p, b).real())
      hi = b;
    else
      lo = a;
  }
  return compliance(p, 0.5 * (lo + hi)).real();
}

RightmostRoot rightmost(const ThompsonParameters& p, double band_hz = 1000.0) {
  auto e = Thompson(p).characteristic();
  RootSearchOptions options;
  options.max_frequency_hz = band_hz;
  return find_rightmost_root(*e, options);
}

TEST(Thompson, UnconditionalDampingAgreesByFourRoutes) {
  for (double kc_compliance : {1e-12, 1e-9, 1e-8, 1e-7}) {
    ThompsonParameters p = example();
    p.contact_compliance_m_per_n = kc_compliance;
    const double cm = unconditional_damping_n_s_per_m(p);
    // (1) the book's printed 2-48 (with D -> D/H for contact);
    EXPECT_NEAR(unconditional_damping_eq_2_48_n_s_per_m(p), cm, 1e-7 * cm);
    // (2) the frequency-domain absolute-stability condition 2-65;
    EXPECT_NEAR(absolute_stability_damping_eq_2_65_n_s_per_m(p), cm, 1e-12 * cm);
    // (3) the maximum of the boundary damping 2-43 over a, found numerically, at a^4 = 2k/alpha
    // (2-46);
    const BoundaryQuartic q = boundary_quartic(p);
    const double a_star = -std::pow(2.0 * p.stiffness_n_per_m / q.alpha, 0.25);
    double scan_max = 0.0;
    for (int i = -3000; i <= 3000; ++i)
      scan_max = std::max(scan_max, boundary_damping_n_s_per_m(p, a_star * std::pow(10.0, i / 1000.0)));
    EXPECT_NEAR(boundary_damping_n_s_per_m(p, a_star), cm, 1e-12 * cm);
    EXPECT_LE(scan_max, cm * (1.0 + 1e-12));
    EXPECT_GE(scan_max, cm * (1.0 - 1e-6));
    // (4) the damping at which the compliance circle of m, c, k just touches the process line
    // -P (G1 eq 2-21), from the frequency response alone.
    ThompsonParameters touching = p;
    touching.damping_n_s_per_m = cm;
    EXPECT_NEAR(leftmost_real_compliance(touching), -process_line_m_per_n(p),
                1e-9 * process_line_m_per_n(p));
  }
}

TEST(Thompson, BoundariesCoincideExactlyAtTheUnconditionalDamping) {
  ThompsonParameters p = example();
  const double cm = unconditional_damping_n_s_per_m(p);
  // z1 = z2 (2-64's inner root vanishes) exactly when c = c_m, i.e. when 2-65 holds.
  p.damping_n_s_per_m = cm;
  const double b = 2.0 * p.mass_kg / (cutting_compliance_m_per_n(p) * cm * cm);
  EXPECT_LE(std::abs(eq_2_64_discriminant(p)), 1e-11 * b * b);
  for (double factor : {0.999, 0.9, 0.5, 0.1}) {
    p.damping_n_s_per_m = factor * cm;
    EXPECT_GT(eq_2_64_discriminant(p), 0.0) << factor;
    auto band = conditional_boundaries(p);
    auto z = dimensionless_boundaries(p);
    ASSERT_TRUE(band && z) << factor;
    // Two routes: 2-51 in a, 2-64 in z = a K/2.
    const double half_k = 0.5 * cutting_compliance_m_per_n(p);
    EXPECT_NEAR(z->z1, band->a1_n_per_m * half_k, 1e-9 * std::abs(z->z1));
    EXPECT_NEAR(z->z2, band->a2_n_per_m * half_k, 1e-9 * std::abs(z->z2));
    EXPECT_LT(band->a2_n_per_m, band->a1_n_per_m);
    EXPECT_LT(band->a1_n_per_m, 0.0);
    // On the boundaries the boundary damping is c0; inside it exceeds c0 (2-52: chatter).
    for (double a : {band->a1_n_per_m, band->a2_n_per_m})
      EXPECT_NEAR(boundary_damping_n_s_per_m(p, a), p.damping_n_s_per_m, 1e-9 * p.damping_n_s_per_m);
    const double inside = -std::sqrt(band->a1_n_per_m * band->a2_n_per_m);
    EXPECT_GT(boundary_damping_n_s_per_m(p, inside), p.damping_n_s_per_m);
    // The boundary frequency 2-63 lies where the c0 circle crosses the process line (2-61).
    for (double zz : {z->z1, z->z2}) {
      const double w = boundary_frequency_rad_s(p, zz);
      EXPECT_NEAR(compliance(p, w).real(), -process_line_m_per_n(p), 1e-9 * process_line_m_per_n(p));
      EXPECT_NEAR(compliance(p, w).imag(), half_k / zz, 1e-9 * std::abs(half_k / zz));  // 2-62
    }
  }
  p.damping_n_s_per_m = 1.001 * cm;
  EXPECT_FALSE(conditional_boundaries(p));
  EXPECT_FALSE(dimensionless_boundaries(p));
}

TEST(Thompson, RigidContactReducesToTheBookEquations2_43And2_55) {
  ThompsonParameters p = example();
  p.contact_compliance_m_per_n = 1e-30;  // H = 1
  const double K = cutting_compliance_m_per_n(p), k = p.stiffness_n_per_m, m = p.mass_kg;
  const BoundaryQuartic q = boundary_quartic(p);
  EXPECT_NEAR(q.alpha, K * K * K / 4.0 * (1.0 + k * K / 2.0), 1e-12 * q.alpha);
  EXPECT_NEAR(q.beta, K * (1.0 + k * K), 1e-12 * q.beta);
  p.damping_n_s_per_m = 0.4 * unconditional_damping_n_s_per_m(p);
  const double c = p.damping_n_s_per_m;
  const double b = 2.0 * m / (K * c * c) - k * K - 1.0;
  const double root = std::sqrt(b * b - k * K * (2.0 + k * K));
  auto z = dimensionless_boundaries(p);
  ASSERT_TRUE(z);
  EXPECT_NEAR(z->z1, -std::sqrt(b - root) / std::sqrt(2.0 + k * K), 1e-9 * std::abs(z->z1));
  EXPECT_NEAR(z->z2, -std::sqrt(b + root) / std::sqrt(2.0 + k * K), 1e-9 * std::abs(z->z2));
}

TEST(Thompson, SpeedCrossingIsARootOfTheCharacteristicOnTheAxis) {
  // At the damping the speed criterion calls marginal, the G1 characteristic of the same model
  // has a root at s = j w (2-39 and 2-41/2-58 are the real and imaginary parts of D(jw) = 0).
  ThompsonParameters p = example();
  const SpeedCriterion crit = speed_criterion(p);
  ASSERT_GT(crit.crossings, 10);
  const double w = crit.frequency_rad_s;
  ThompsonParameters marginal = p;
  marginal.damping_n_s_per_m = crit.critical_damping_n_s_per_m;
  const auto h = compliance(marginal, w);
  EXPECT_NEAR(h.real(), -process_line_m_per_n(p), 1e-9 * process_line_m_per_n(p));  // 2-58
  EXPECT_NEAR(h.imag(), inverse_stability_index_m_per_n(p, w), 1e-8 * std::abs(h.imag()));  // 2-39
  EXPECT_NEAR(1.0 / crit.stability_index_n_per_m, inverse_stability_index_m_per_n(p, w),
              1e-8 * std::abs(h.imag()));
  // a = F/L with the lobe heights of 2-35, 2-36: L/F = (1/2)[Kg sin(wTg)/(1 - cos wTg) + Kw ...].
  const double tg = 60.0 / p.wheel_speed_rpm, tw = 60.0 / p.work_speed_rpm;
  const double lobes = 0.5 * p.wheel_wear_compliance_m_per_n * std::sin(w * tg) / (1.0 - std::cos(w * tg)) +
                       0.5 * p.work_removal_compliance_m_per_n * std::sin(w * tw) / (1.0 - std::cos(w * tw));
  EXPECT_NEAR(lobes, inverse_stability_index_m_per_n(p, w), 1e-7 * std::abs(lobes));
  auto e = Thompson(marginal).characteristic();
  const CharacteristicValue at = e->evaluate(Complex(0.0, w));
  EXPECT_LE(std::abs(at.value / at.derivative), 1e-7 * w);  // a Newton step of ~0 from j w
  const RightmostRoot found = rightmost(marginal);
  ASSERT_TRUE(found.certified) << found.certificate;
  EXPECT_NEAR(found.root.real(), 0.0, 1e-6 * w);
  EXPECT_NEAR(found.root.imag(), w, 1e-7 * w);
}

TEST(Thompson, ClosedFormBandAgreesWithTheRightmostRoot) {
  // Thompson's conditional stability over wheel/work speeds: the closed-form verdict
  // (c0 < speed_critical_damping: chatter) against the sign of the rightmost root.
  // A soft contact (Kc = 1e-7 m/N, kP = 5) narrows the crossing range to wn..1.095 wn and fast
  // work speeds thin out the work lattice, so that only a few crossings exist and whether one
  // reaches the damping c0 = 0.95 c_m depends on the speeds (studies/thompson_band.toml).
  ThompsonParameters p = example();
  p.work_removal_compliance_m_per_n = 2e-10;
  p.contact_compliance_m_per_n = 1e-7;
  p.damping_n_s_per_m = 0.95 * unconditional_damping_n_s_per_m(p);
  int chatter = 0, stable = 0, compared = 0;
  for (double wheel_rpm = 1000.0; wheel_rpm <= 2000.0; wheel_rpm += 125.0) {
    for (double work_rpm : {700.0, 800.0, 900.0}) {
      p.wheel_speed_rpm = wheel_rpm;
      p.work_speed_rpm = work_rpm;
      const SpeedCriterion crit = speed_criterion(p);
      const RightmostRoot found = rightmost(p, 800.0);
      ASSERT_TRUE(found.certified) << found.certificate;
      if (std::abs(crit.chatter_margin) < 1e-3) continue;  // at the boundary: no verdict to compare
      ++compared;
      (crit.chatter_margin > 0 ? chatter : stable)++;
      EXPECT_EQ(crit.chatter_margin > 0, found.root.real() > 0)
          << wheel_rpm << "/" << work_rpm << " rpm: margin " << crit.chatter_margin << " root "
          << found.root;
    }
  }
  EXPECT_GT(compared, 20);
  EXPECT_GT(chatter, 0);  // the grid straddles the band
  EXPECT_GT(stable, 0);
}

TEST(Thompson, PluginReportsIndicatorsAndRejectsBadParameters) {
  const auto& entry = model_registry().at("thompson");
  auto model = entry.create(ParamValues(entry.info.example_params));
  const auto* indicators = dynamic_cast<const ClosedFormIndicators*>(model.get());
  ASSERT_NE(indicators, nullptr);
  const auto specs = indicators->indicator_specs();
  const auto values = indicators->indicator_values();
  ASSERT_EQ(specs.size(), values.size());
  int margins = 0;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    margins += specs[i].chatter_margin ? 1 : 0;
    EXPECT_FALSE(values[i].is_null()) << specs[i].name;  // the example is conditionally stable
  }
  EXPECT_EQ(margins, 1);
  EXPECT_EQ(model->wheel_period_s().value(), 60.0 / 1450.0);

  struct NoSources final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  };
  Json bad = entry.info.example_params;
  bad["damping_n_s_per_m"] = 0.0;
  try {
    validate_params(bad, entry.info.params, "model", NoSources{});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("model.damping_n_s_per_m = 0 [N s/m]"), std::string::npos) << message;
    EXPECT_NE(message.find("> 0"), std::string::npos) << message;
  }
}

TEST(Thompson, StiffnessChainAndComplianceAreTheEquivalentG1System) {
  // kc = 1/Kc, kg = 1/Kg, kw = 1/Kw, one mode f = sqrt(k/m)/2 pi, zeta = c/(2 sqrt(k m)); H(s) =
  // 1/(m s^2 + c s + k). Fig 2-4: the process line -(Kc + (Kg + Kw)/2) meets the circle's
  // leftmost point -1/(4 zeta (1 + zeta) k) exactly when c0 < c_m (2-48/2-65).
  for (const double c0 : {3162.3, 1.5e4, 2.0e4}) {
    ThompsonParameters p = example();
    p.damping_n_s_per_m = c0;
    const Thompson model(p);
    const StiffnessChain chain = model.stiffness_chain().value();
    EXPECT_EQ(chain.contact_stiffness_n_per_m, 1.0 / 1e-8);
    EXPECT_EQ(chain.wheel_wear_stiffness_n_per_m, 1.0 / 1e-9);
    EXPECT_EQ(chain.work_removal_stiffness_n_per_m, 1.0 / 5e-9);
    ASSERT_EQ(chain.modes.size(), 1u);
    const double zeta = c0 / (2.0 * std::sqrt(5e7 * 20.0));
    EXPECT_NEAR(chain.modes[0].frequency_hz, std::sqrt(5e7 / 20.0) / kTwoPi, 1e-12);
    EXPECT_NEAR(chain.modes[0].damping_ratio, zeta, 1e-15);
    const StructuralCompliance* h = model.structural_compliance();
    ASSERT_NE(h, nullptr);
    for (const double w : {0.0, 900.0, 1580.8, 3000.0}) {
      const std::complex<double> expected = compliance(p, w);
      EXPECT_NEAR(std::abs(h->compliance_m_per_n({0.0, w}) - expected), 0.0, 1e-12 * std::abs(expected)) << w;
    }
    const double line = -(1.0 / chain.contact_stiffness_n_per_m +
                          0.5 / chain.wheel_wear_stiffness_n_per_m + 0.5 / chain.work_removal_stiffness_n_per_m);
    EXPECT_NEAR(line, -process_line_m_per_n(p), 1e-24);
    const double leftmost = -1.0 / (4.0 * zeta * (1.0 + zeta) * 5e7);
    EXPECT_EQ(leftmost < line, c0 < unconditional_damping_n_s_per_m(p)) << c0;
  }
}

}  // namespace
}  // namespace chatterlab
