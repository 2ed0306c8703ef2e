// compliance_chart (book fig 2-4, G1 eq 2-21): the leftmost point of one mode's compliance circle
// in closed form, "apart means stable" against the rightmost root, Thompson's process line, and
// bad input. The models are built by name from the registry and reached through their
// capabilities (stiffness chain, structural compliance), as the study kind reaches them.
#include "study_kinds/compliance_chart/compliance_chart.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "chatterlab/errors.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/study.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

std::unique_ptr<Model> one_mode(double kc) {
  return kit::build_model(Json{{"type", "plunge_regenerative"},
                               {"wheel_speed_rpm", 1450.0},
                               {"work_speed_rpm", 55.0},
                               {"contact_stiffness_n_per_m", kc},
                               {"wheel_wear_stiffness_n_per_m", 1e9},
                               {"work_removal_stiffness_n_per_m", 2e8},
                               {"modes", {{{"frequency_hz", 250.0}, {"damping_ratio", 0.05}, {"stiffness_n_per_m", 5e7}}}},
                               {"wheel_regeneration", true},
                               {"work_regeneration", true}});
}

ComplianceChart chart_of(const Model& model, double band_hz, int points) {
  return compliance_chart(*model.stiffness_chain(), *model.structural_compliance(), band_hz, points);
}

TEST(ComplianceChart, LeftmostPointOfOneModeIsTheClosedForm) {
  const ComplianceChart c = chart_of(*one_mode(1e8), 1000.0, 2000);
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
    const auto model = one_mode(kc);
    const ComplianceChart c = chart_of(*model, 1000.0, 4000);
    RootSearchOptions options;
    options.max_frequency_hz = 1000.0;
    const RightmostRoot root = find_rightmost_root(*model->characteristic(), options);
    ASSERT_TRUE(root.certified) << root.certificate;
    if (!c.intersects) {
      EXPECT_LT(root.root.real(), 0.0) << "kc " << kc;
    }
    // kc counts double: halving kc moves the line by 1/kc, each chain's 1/k only by half that.
    EXPECT_NEAR(chart_of(*one_mode(kc / 2), 1000.0, 200).process_line_m_per_n, c.process_line_m_per_n - 1.0 / kc,
                1e-12 / kc);
  }
  EXPECT_TRUE(chart_of(*one_mode(1e8), 1000.0, 400).intersects);  // the example chatters
  EXPECT_FALSE(chart_of(*one_mode(1e6), 1000.0, 400).intersects);
}

TEST(ComplianceChart, ThompsonModelsUseTheirProcessLine) {
  // Thompson's example (docs/models/thompson.md): P = Kc + (Kg + Kw)/2 (2-59) and c_m = 18.8 kN s/m
  // (2-48): the measured c0 = 3162 N s/m is below it (curve and line meet); 2e4 N s/m is above
  // (apart: unconditionally stable, 2-65).
  const auto& entry = model_registry().at("thompson");
  Json table = entry.info.example_params;
  table["type"] = "thompson";
  const ComplianceChart c = chart_of(*kit::build_model(table), 1000.0, 4000);
  EXPECT_NEAR(c.process_line_m_per_n, -(1e-8 + 0.5 * (1e-9 + 5e-9)), 1e-22);
  EXPECT_TRUE(c.intersects);
  table["damping_n_s_per_m"] = 2.0e4;
  EXPECT_FALSE(chart_of(*kit::build_model(table), 1000.0, 4000).intersects);
}

// A compliance_chart study of the model `type` with `lines` after its type (which is line 4).
std::string chart_study(const std::string& type, const std::string& lines) {
  return "[study]\nkind = \"compliance_chart\"\n[model]\ntype = \"" + type + "\"\n" + lines;
}

TEST(ComplianceChart, ModelsWithoutAMachineComplianceAreBadInput) {
  testing::TempDir dir;
  const std::string message = testing::load_error(
      dir, chart_study("linear_dde", "a0 = [[0.0, 1.0], [-1.3, -0.1]]\n"
                                     "delayed = [{ delay_s = 10.0, matrix = [[0.0, 0.0], [0.3, 0.0]] }]\n"));
  EXPECT_NE(message.find("study.toml:4: model.type = \"linear_dde\""), std::string::npos) << message;
  EXPECT_NE(message.find("plunge_regenerative, thompson"), std::string::npos) << message;
}

TEST(ComplianceChart, PenetrationDampingIsRefusedNamingKd) {
  // With kd > 0 the work term's real part on the axis is not 1/(2 kw): the line of eq 2-21 would
  // claim a stability it cannot prove.
  testing::TempDir dir;
  const std::string study = chart_study("plunge_with_penetration_damping", R"(wheel_speed_rpm = 1450
work_speed_rpm = 55
contact_stiffness_n_per_m = 1e8
wheel_wear_stiffness_n_per_m = 5e9
work_removal_stiffness_n_per_m = 5e7
modes = [{ frequency_hz = 184.08, damping_ratio = 0.05, stiffness_n_per_m = 5e7 }]
penetration_damping_n_s_per_m = 1.09e5
)");
  const std::string message = testing::load_error(dir, study);
  EXPECT_NE(message.find("study.toml:11: model.penetration_damping_n_s_per_m = 109000"), std::string::npos)
      << message;
  EXPECT_NE(message.find("kd = 0 or work_regeneration = false"), std::string::npos) << message;
  // kd = 0 is G1: drawn.
  const std::string g1 = std::string(study).replace(study.find("1.09e5"), 6, "0.0");
  EXPECT_NO_THROW(load_study(dir.write("g1.toml", g1)));
}

}  // namespace
}  // namespace chatterlab
