// plunge_with_penetration_damping (G1 + G4's dynamic grinding force): kd = 0 is G1 exactly; the
// reported roots solve the raw characteristic equation; kd damps work-regenerative chatter.
#include "models/plunge_with_penetration_damping/plunge_with_penetration_damping.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>

#include "chatterlab/registry.hpp"
#include "chatterlab/roots.hpp"
#include "shared/plunge_dynamics/grinding_process.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab {
namespace {

// the G1 example (1450/55 rpm, kc 1e8, kg 5e9, kw 5e7 N/m, modes 184.08 Hz and 305.6 Hz):
// work-regenerative chatter at 376.5 Hz (docs/models/plunge_regenerative.md).
PlungeRegenerativeParameters example() {
  return plunge_dynamics::plunge_parameters_table().read(plunge_dynamics::example_g1_parameters());
}

RightmostRoot rightmost(const CharacteristicFunction& e) {
  RootSearchOptions options;
  options.max_frequency_hz = 1222.4;
  return find_rightmost_root(e, options);
}

// D(s) = 1 + kc [H + 1/(kg (1 - e^{-Tg s})) + 1/(kw (1 - e^{-Tw s}) + kd s)], written out directly.
std::complex<double> raw(const PlungeRegenerativeParameters& p, double kd, std::complex<double> s) {
  std::complex<double> h = 0.0;
  for (const StructuralMode& m : p.modes) {
    const double w = 2.0 * std::numbers::pi * m.frequency_hz;
    h += 1.0 / (m.stiffness_n_per_m * (s * s / (w * w) + 2.0 * m.damping_ratio * s / w + 1.0));
  }
  const std::complex<double> a = 1.0 - std::exp(-s * 60.0 / p.wheel_speed_rpm);
  const std::complex<double> b = 1.0 - std::exp(-s * 60.0 / p.work_speed_rpm);
  return 1.0 + p.contact_stiffness_n_per_m *
                   (h + 1.0 / (p.wheel_wear_stiffness_n_per_m * a) + 1.0 / (p.work_removal_stiffness_n_per_m * b + kd * s));
}

TEST(PlungeWithPenetrationDamping, WithoutDampingItIsG1) {
  const RightmostRoot g1 = rightmost(PlungeCharacteristic(example()));
  const RightmostRoot same = rightmost(PenetrationDampingCharacteristic(example(), 0.0));
  ASSERT_TRUE(same.certified) << same.certificate;
  EXPECT_EQ(same.root, g1.root);
  EXPECT_NEAR(g1.root.real(), 1.2863, 1e-4);  // as documented for plunge_regenerative
}

TEST(PlungeWithPenetrationDamping, RootsSolveTheRawEquationAndKdRemovesTheWorkChain) {
  // kd takes energy out of the work chain only: growth falls from the G1 value towards the
  // wheel-regenerative chatter that remains when the work term is gone (kd -> infinity, the
  // work_regeneration = false model), which it reaches from below or above depending on how the
  // work term's real part (process compliance) fades.
  PlungeRegenerativeParameters wheel_only = example();
  wheel_only.work_regeneration = false;
  const RightmostRoot limit = rightmost(PlungeCharacteristic(wheel_only));
  ASSERT_TRUE(limit.certified) << limit.certificate;
  double previous = rightmost(PlungeCharacteristic(example())).root.real();
  std::printf("kd [N s/m]   sigma [1/s]   f [Hz]\n");
  for (double kd : {1e2, 1e3, 1e4, 1.09e5, 1e6, 1e9}) {
    const PenetrationDampingCharacteristic e(example(), kd);
    const RightmostRoot found = rightmost(e);
    ASSERT_TRUE(found.certified) << "kd " << kd << ": " << found.certificate;
    std::printf("%10.3g %12.5g %9.2f\n", kd, found.root.real(), found.root.imag() / (2.0 * std::numbers::pi));
    // A root of D itself: the Newton step on the raw equation is negligible.
    const std::complex<double> s = found.root, d = 1e-6 * std::abs(s);
    const std::complex<double> slope = (raw(example(), kd, s + d) - raw(example(), kd, s - d)) / (2.0 * d);
    EXPECT_LT(std::abs(raw(example(), kd, s) / slope), 1e-8 * std::abs(s)) << "kd " << kd;
    if (kd <= 1e4) {
      EXPECT_LT(found.root.real(), previous) << "kd " << kd;
    }
    previous = found.root.real();
  }
  EXPECT_NEAR(previous, limit.root.real(), 1e-3 * std::abs(limit.root.real()) + 1e-4);
  // The kd of a real process (kw = 5e7 N/m, de = 80 mm, u0 = 5 um, vw = 0.29 m/s) is 1.09e5 N s/m.
  const double kd = grinding_process::dynamic_grinding_coefficient_n_s_per_m(5e7, 0.08, 5e-6, 0.29);
  EXPECT_NEAR(kd, 1.09e5, 0.01e5);
}

TEST(PlungeWithPenetrationDamping, RegisteredAndBuildsFromItsExample) {
  const auto& entry = model_registry().at("plunge_with_penetration_damping");
  EXPECT_EQ(entry.info.models_md_ids, "G1, G4");
  struct Here final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {"example", 0}; }
  };
  auto model = entry.create(ParamValues(validate_params(entry.info.example_params, entry.info.params, "model", Here())));
  ASSERT_NE(model->characteristic(), nullptr);
  EXPECT_DOUBLE_EQ(model->wheel_period_s().value(), 60.0 / 1450.0);
}

TEST(PlungeWithPenetrationDamping, G4IndicatorsFromTheProcessGeometry) {
  // The example's process: work 100 mm at 55 rpm, wheel 400 mm, u0 = 5 um, kw = 5e7 N/m.
  // v_w = pi 0.1 55/60 = 0.288 m/s; de = 0.1 0.4/0.5 = 0.08 m; l_c = sqrt(de u0) = 0.632 mm;
  // kd = kw l_c/v_w = 1.098e5 N s/m (the example's kd); v_c = 2 pi f sqrt(u0 Re) at the most
  // compliant mode (184.08 Hz: zeta k = 2.5e6 < 3.2e6 N/m), Re = 0.05 0.2/0.25 = 0.04 m.
  const auto& entry = model_registry().at("plunge_with_penetration_damping");
  Json table = entry.info.example_params;
  table["wheel_regeneration"] = true;
  table["work_regeneration"] = true;
  const PlungeWithPenetrationDamping model{ParamValues(table)};
  const ClosedFormIndicators* indicators = model.closed_forms();
  ASSERT_NE(indicators, nullptr);
  const std::vector<Json> v = indicators->indicator_values();
  ASSERT_EQ(v.size(), indicators->indicator_specs().size());
  const double vw = std::numbers::pi * 0.1 * 55.0 / 60.0;
  EXPECT_NEAR(v[0].get<double>(), vw, 1e-15);
  EXPECT_NEAR(v[1].get<double>(), 1e3 * std::sqrt(0.08 * 5e-6), 1e-14);
  EXPECT_NEAR(v[2].get<double>(), 5e7 * std::sqrt(0.08 * 5e-6) / vw, 1e-9);
  EXPECT_NEAR(v[2].get<double>(), 1.09e5, 0.01e5);
  EXPECT_NEAR(v[3].get<double>(), 2.0 * std::numbers::pi * 184.08 * std::sqrt(5e-6 * 0.04), 1e-12);
  // Without the geometry the indicators do not apply.
  table.erase("wheel_diameter_mm");
  table["wheel_diameter_mm"] = nullptr;
  const std::vector<Json> partial = PlungeWithPenetrationDamping{ParamValues(table)}.indicator_values();
  EXPECT_NEAR(partial[0].get<double>(), vw, 1e-15);
  for (std::size_t i = 1; i < partial.size(); ++i) EXPECT_TRUE(partial[i].is_null()) << i;
}

TEST(PlungeWithPenetrationDamping, StiffnessChainCarriesKdInTheWorkChain) {
  PenetrationDampingParameters p;
  p.plunge = example();
  p.penetration_damping_n_s_per_m = 1.09e5;
  StiffnessChain chain = PlungeWithPenetrationDamping(p).stiffness_chain().value();
  EXPECT_EQ(chain.work_removal_stiffness_n_per_m, 5e7);
  EXPECT_EQ(chain.penetration_damping_n_s_per_m, 1.09e5);
  // The structural compliance is G1's.
  const Complex s(0.0, 1500.0);
  EXPECT_EQ(PlungeWithPenetrationDamping(p).compliance_m_per_n(s), PlungeCharacteristic(example()).structural_compliance(s));
  // With the work chain off kd has no effect, and the chain says so.
  p.plunge.work_regeneration = false;
  chain = PlungeWithPenetrationDamping(p).stiffness_chain().value();
  EXPECT_EQ(chain.penetration_damping_n_s_per_m, 0.0);
}

}  // namespace
}  // namespace chatterlab
