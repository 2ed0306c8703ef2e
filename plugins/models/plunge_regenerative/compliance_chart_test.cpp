// compliance_chart (book fig 2-4, G1 eq 2-21): the leftmost point of one mode's compliance circle
// in closed form, "apart means stable" against the rightmost root, Thompson's process line, and
// bad input.
#include "models/plunge_regenerative/compliance_chart.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "chatterlab/errors.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/study.hpp"
#include "models/thompson/thompson.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

PlungeRegenerativeParameters one_mode(double kc) {
  PlungeRegenerativeParameters p;
  p.wheel_speed_rpm = 1450.0;
  p.work_speed_rpm = 55.0;
  p.contact_stiffness_n_per_m = kc;
  p.wheel_wear_stiffness_n_per_m = 1e9;
  p.work_removal_stiffness_n_per_m = 2e8;
  p.modes = {{250.0, 0.05, 5e7}};
  return p;
}

TEST(ComplianceChart, LeftmostPointOfOneModeIsTheClosedForm) {
  const ComplianceChart c = compliance_chart(one_mode(1e8), 1000.0, 2000);
  const double zeta = 0.05, k = 5e7;
  EXPECT_NEAR(c.leftmost_real_m_per_n, -1.0 / (4.0 * zeta * (1.0 + zeta) * k), 1e-12 / k);
  EXPECT_NEAR(c.leftmost_frequency_hz, 250.0 * std::sqrt(1.0 + 2.0 * zeta), 1e-3);
  EXPECT_NEAR(c.process_line_m_per_n, -0.5 * (2e-8 + 1e-9 + 5e-9), 1e-20);
  EXPECT_EQ(c.frequency_hz.size(), 2000u);
}

TEST(ComplianceChart, ApartMeansStableAtTheseSpeeds) {
  // Eq 2-21: no intersection -> no root on the axis at any speed -> stable (the converse needs
  // the speeds: an intersection only makes chatter possible).
  for (double kc : {1e6, 3e6, 1e7, 1e8, 1e9}) {
    const PlungeRegenerativeParameters p = one_mode(kc);
    const ComplianceChart c = compliance_chart(p, 1000.0, 4000);
    RootSearchOptions options;
    options.max_frequency_hz = 1000.0;
    const RightmostRoot root = find_rightmost_root(PlungeCharacteristic(p), options);
    ASSERT_TRUE(root.certified) << root.certificate;
    if (!c.intersects) {
      EXPECT_LT(root.root.real(), 0.0) << "kc " << kc;
    }
    // kc counts double: halving kc moves the line by 1/kc, each chain's 1/k only by half that.
    EXPECT_NEAR(compliance_chart(one_mode(kc / 2), 1000.0, 200).process_line_m_per_n,
                c.process_line_m_per_n - 1.0 / kc, 1e-12 / kc);
  }
  EXPECT_TRUE(compliance_chart(one_mode(1e8), 1000.0, 400).intersects);  // the example chatters
  EXPECT_FALSE(compliance_chart(one_mode(1e6), 1000.0, 400).intersects);
}

TEST(ComplianceChart, ThompsonModelsUseTheirProcessLine) {
  ThompsonParameters t;
  t.mass_kg = 20.0;
  t.damping_n_s_per_m = 3162.3;
  t.stiffness_n_per_m = 5e7;
  t.wheel_wear_compliance_m_per_n = 1e-9;
  t.work_removal_compliance_m_per_n = 5e-9;
  t.contact_compliance_m_per_n = 1e-8;
  t.wheel_speed_rpm = 1450.0;
  t.work_speed_rpm = 55.0;
  const ComplianceChart c = compliance_chart(thompson::equivalent_g1(t), 1000.0, 400);
  EXPECT_NEAR(c.process_line_m_per_n, -thompson::process_line_m_per_n(t), 1e-22);
  // Apart exactly when c0 > c_m (2-65).
  EXPECT_EQ(c.intersects, t.damping_n_s_per_m < thompson::unconditional_damping_n_s_per_m(t));
}

TEST(ComplianceChart, ModelsWithoutAMachineComplianceAreBadInput) {
  testing::TempDir dir;
  const std::string study = R"([study]
kind = "compliance_chart"
[model]
type = "linear_dde"
a0 = [[0.0, 1.0], [-1.3, -0.1]]
delayed = [{ delay_s = 10.0, matrix = [[0.0, 0.0], [0.3, 0.0]] }]
)";
  try {
    load_study(dir.write("study.toml", study));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("study.toml:4: model.type = \"linear_dde\""), std::string::npos) << message;
    EXPECT_NE(message.find("plunge_regenerative, thompson"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace chatterlab
