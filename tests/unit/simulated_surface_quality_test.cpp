// Part quality of simulated work surfaces (issue 7 part 6): the `simulate` kind measures the
// final work surface through the profile-quality capability of the surface metrology
// (surface_profile plugin). Cross-cutting: a study kind, a model's closed form, an analysis. Known answer: MODELS.md
// G6 wheel unbalance at n_g / n_w = 1500 / 50 imprints exactly Z = 30 lobes of the steady relative
// amplitude |X1 + X2| (the closed form, a 2 x 2 complex solve independent of the simulation);
// the 50 UPR Gaussian passes them with ISO 16610-21 transmission exp(-pi (alpha Z / 50)^2), so
// RONt = Wt = 2 |X1 + X2| T, and the unfiltered low band Wz|f holds the same lobes at 30 UPR.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "models/unbalance_two_dof/unbalance_closed_form.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::TempDir;

// The G6 plugin's own example (chatterlab describe unbalance_two_dof) at 1500/50 rpm: Z = 30.
Json g6_model() {
  Json model = model_registry().at("unbalance_two_dof").info.example_params;
  model["wheel_speed_rpm"] = 1500.0;
  model["work_speed_rpm"] = 50.0;
  return model;
}

std::string g6_study() {
  std::string text = "[study]\nkind = \"simulate\"\n[model]\ntype = \"unbalance_two_dof\"\n";
  const Json model = g6_model();  // named: items() of a temporary would dangle
  for (const auto& [key, value] : model.items()) text += key + " = " + value.dump() + "\n";
  return text + R"([simulation]
duration_s = 1.6
sample_rate_hz = 5000
initial_displacement_m = 0.0
one_sided_contact = false
)";
}

double steady_relative_amplitude_m() {
  // The closed form's parameter names for the same machine.
  using P = UnbalanceTwoDofParameters;
  const std::pair<const char*, double P::*> names[] = {
      {"mass_1_kg", &P::wheel_mass_kg},
      {"damping_1_n_s_per_m", &P::wheel_damping_n_s_per_m},
      {"stiffness_1_n_per_m", &P::wheel_support_stiffness_n_per_m},
      {"mass_2_kg", &P::work_mass_kg},
      {"damping_2_n_s_per_m", &P::work_damping_n_s_per_m},
      {"stiffness_2_n_per_m", &P::work_support_stiffness_n_per_m},
      {"contact_stiffness_n_per_m", &P::contact_stiffness_n_per_m},
      {"wheel_wear_stiffness_n_per_m", &P::grinding_stiffness_n_per_m},
      {"unbalance_kg_m", &P::unbalance_kg_m},
      {"wheel_speed_rpm", &P::wheel_speed_rpm},
      {"work_speed_rpm", &P::work_speed_rpm}};
  const Json model = g6_model();
  P p;
  for (const auto& [key, member] : names) p.*member = model.at(key).get<double>();
  const auto s = unbalance::unbalance_response(p);
  return std::abs(s.wheel_m + s.work_m);  // the engine's work surface copies x1 + x2
}

// ISO 16610-21 Gaussian waviness transmission at `upr` for a cut-off of `cutoff_upr`.
double gaussian_transmission(double upr, double cutoff_upr) {
  const double alpha = std::sqrt(std::log(2.0) / std::numbers::pi);
  return std::exp(-std::numbers::pi * std::pow(alpha * upr / cutoff_upr, 2));
}

Json run(const TempDir& dir, const std::string& extra, std::vector<Json>* row = nullptr) {
  Study study = load_study(dir.write("study.toml", g6_study() + extra));
  auto owned = study_kind_registry().at("simulate").create(ParamValues{});
  PointContext context;
  context.artifact_dir = dir.path() / "out";
  context.plots = false;
  std::filesystem::create_directories(context.artifact_dir);
  std::vector<Json> out = owned->run_point(study.point_document(0), context);
  if (row) *row = out;
  std::ifstream in(context.artifact_dir / "summary.json");
  return Json::parse(in);
}

TEST(SimulatedSurfaceQuality, UnbalanceLobesGiveTheForcedAmplitudeAsRoundness) {
  TempDir dir;
  std::vector<Json> row;
  const Json summary = run(dir, "", &row);
  const Json& q = summary.at("work_surface_quality");
  ASSERT_TRUE(q.contains("RONt_um")) << q.dump();
  const double a_um = 1e6 * steady_relative_amplitude_m();
  const double expected = 2.0 * a_um * gaussian_transmission(30.0, 50.0);  // default 50 UPR
  EXPECT_NEAR(q.at("RONt_um").get<double>(), expected, 0.01 * expected);
  EXPECT_NEAR(q.at("Wt_um").get<double>(), expected, 0.01 * expected);
  // A pure 30-lobe profile: every reference circle is the LS circle.
  EXPECT_NEAR(q.at("roundness").at("minimum_zone").at("RONt_um").get<double>(), expected, 0.01 * expected);
  // Wz|f from the recorded speeds: Z = 30, the forced band's dominant order 30 at 25 Hz, its
  // wave height the unfiltered 2 A; nothing in the chatter band.
  const Json& wzf = q.at("Wz_f");
  EXPECT_NEAR(wzf.at("forced_lobes_per_rev").get<double>(), 30.0, 1e-6);
  EXPECT_EQ(wzf.at("low").at("dominant_upr").get<double>(), 30.0);
  EXPECT_NEAR(wzf.at("low").at("dominant_frequency_hz").get<double>(), 25.0, 1e-6);
  EXPECT_NEAR(wzf.at("low").at("Wz_um").get<double>(), 2.0 * a_um, 0.01 * 2.0 * a_um);
  EXPECT_LT(wzf.at("high").at("Wz_um").get<double>(), 0.01 * a_um);
  // results.csv columns: Wt, Wz, RONt (LS) of the same evaluation.
  ASSERT_GE(row.size(), 11u);  // after growth, fit_valid/regime/reason, frequency, max, contact, outcome
  EXPECT_EQ(row[8], q.at("Wt_um"));
  EXPECT_EQ(row[9], q.at("Wz_um"));
  EXPECT_EQ(row[10], q.at("RONt_um"));
}

TEST(SimulatedSurfaceQuality, SurfaceTableSetsTheCutoff) {
  TempDir dir;
  const Json q = run(dir, "[surface]\ncutoff_upr = 150\n").at("work_surface_quality");
  const double expected = 2e6 * steady_relative_amplitude_m() * gaussian_transmission(30.0, 150.0);
  EXPECT_NEAR(q.at("RONt_um").get<double>(), expected, 0.01 * expected);
  EXPECT_EQ(q.at("filter").at("cutoff_upr").get<double>(), 150.0);
}

TEST(SimulatedSurfaceQuality, BadSurfaceKeysNameTheKeyAndLimit) {
  TempDir dir;
  auto message = [&](const std::string& extra) {
    return testing::input_error_of([&] {
      Study study = load_study(dir.write("bad.toml", g6_study() + extra));
      (void)study;
    });
  };
  const std::string mm = message("[surface]\ncutoff_mm = 0.8\n");
  EXPECT_NE(mm.find("surface.cutoff_mm = 0.8: a simulated work surface is a closed profile (one revolution); "
                    "a closed profile takes its cut-off in undulations per revolution: give cutoff_upr"),
            std::string::npos) << mm;
  const std::string one_speed = message("[surface]\nwork_speed_rpm = 50\n");
  EXPECT_NE(one_speed.find("Wz|f needs both wheel_speed_rpm and work_speed_rpm"), std::string::npos)
      << one_speed;
  const std::string band = message("[surface]\nlow_band_upr = [40, 20]\n");
  EXPECT_NE(band.find("low_band_upr = [40.0,20.0]: expected [from, to] with from <= to"),
            std::string::npos) << band;
  const std::string negative = message("[surface]\ncutoff_upr = -5\n");
  EXPECT_NE(negative.find("surface.cutoff_upr"), std::string::npos) << negative;
}

}  // namespace
}  // namespace chatterlab
