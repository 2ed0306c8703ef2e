// measured_frf: the fitted-modes route is G1 with the fitted modes; the measured route's Nyquist
// count agrees with the certified rightmost root of G1 with the true modes (two independent
// routes); the width scaling; the FRF file through a study (relative path, bad input).
#include "models/measured_frf/measured_frf.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/nyquist.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/study.hpp"
#include "unit/frf_test_support.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::g8_modes;
using testing::TempDir;

Json g1_process(double kc, double work_rpm = 55.0) {
  return {{"wheel_speed_rpm", 1450},          {"work_speed_rpm", work_rpm},
          {"contact_stiffness_n_per_m", kc},  {"wheel_wear_stiffness_n_per_m", 6.3e10},
          {"work_removal_stiffness_n_per_m", 2e7}};
}

// The validated [model] table of measured_frf with an inline FRF.
Json measured_table(const MeasuredFrf& frf, const std::string& route, double kc, double work_rpm = 55.0) {
  Json table = g1_process(kc, work_rpm);
  table["type"] = "measured_frf";
  table["machine_compliance"] = route;
  Json f = Json::array(), re = Json::array(), im = Json::array();
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i) {
    f.push_back(frf.frequency_hz[i]);
    re.push_back(frf.receptance_m_per_n[i].real());
    im.push_back(frf.receptance_m_per_n[i].imag());
  }
  table["frf_frequency_hz"] = f;
  table["frf_real_m_per_n"] = re;
  table["frf_imag_m_per_n"] = im;
  struct NoSources final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  } sources;
  Json params = table;
  params.erase("type");
  Json validated = validate_params(params, MeasuredFrfModel::info().params, "model", sources);
  validated["type"] = "measured_frf";
  return validated;
}

// G1 with the true G8 modes (plunge_regenerative through the registry).
std::unique_ptr<Model> true_g1(double kc, double work_rpm = 55.0) {
  Json table = g1_process(kc, work_rpm);
  table["type"] = "plunge_regenerative";
  Json modes = Json::array();
  for (const FittedMode& m : g8_modes())
    modes.push_back({{"frequency_hz", m.frequency_hz}, {"damping_ratio", m.damping_ratio},
                     {"stiffness_n_per_m", m.stiffness_n_per_m}});
  table["modes"] = modes;
  table["wheel_regeneration"] = true;
  table["work_regeneration"] = true;
  return kit::build_model(table);
}

RootSearchOptions band(double hz) {
  RootSearchOptions o;
  o.max_frequency_hz = hz;
  return o;
}

TEST(MeasuredFrf, IsRegisteredWithBothRoutes) {
  const auto& entry = model_registry().at("measured_frf");
  EXPECT_EQ(entry.info.name, "measured_frf");
  const MeasuredFrf frf = testing::synthetic_frf(g8_modes(), 20.0, 400.0, 0.25);
  auto fitted = kit::build_model(measured_table(frf, "fitted_modes", 1e7));
  EXPECT_TRUE(fitted->characteristic());
  EXPECT_TRUE(fitted->return_difference());
  EXPECT_TRUE(fitted->time_domain());
  ASSERT_TRUE(fitted->measured_machine());
  EXPECT_TRUE(fitted->measured_machine()->modal_fit());
  auto measured = kit::build_model(measured_table(frf, "measured", 1e7));
  EXPECT_FALSE(measured->characteristic());
  EXPECT_TRUE(measured->return_difference());
  EXPECT_FALSE(measured->measured_machine()->modal_fit());
  EXPECT_EQ(measured->measured_machine()->measured_frf().frequency_hz.size(), 1521u);
}

// Without noise the fit returns the modes, so the fitted route is G1 with the true modes: the same
// rightmost root.
TEST(MeasuredFrf, FittedModesRouteIsG1WithTheFittedModes) {
  const MeasuredFrf frf = testing::synthetic_frf(g8_modes(), 20.0, 400.0, 0.25);
  for (double kc : {5e6, 2e8}) {
    auto fitted = kit::build_model(measured_table(frf, "fitted_modes", kc));
    const RightmostRoot a = find_rightmost_root(*fitted->characteristic(), band(400.0));
    const RightmostRoot b = find_rightmost_root(*true_g1(kc)->characteristic(), band(400.0));
    EXPECT_TRUE(a.certified && b.certified);
    EXPECT_NEAR(a.root.real(), b.root.real(), 1e-5 * std::abs(b.root));
    EXPECT_NEAR(a.root.imag(), b.root.imag(), 1e-6 * std::abs(b.root));
  }
}

// The measured route (Nyquist count on the measured H, no fit) and the certified rightmost root of
// G1 with the true modes decide stability alike, on both sides of the boundary and at two work
// speeds; the count is even (conjugate pairs) and 0 exactly when the root is stable.
TEST(MeasuredFrf, MeasuredRouteNyquistCountAgreesWithTheRoots) {
  const MeasuredFrf frf = testing::synthetic_frf(g8_modes(), 20.0, 400.0, 0.25);
  int stable = 0, unstable = 0;
  for (double work_rpm : {40.0, 55.0})
    for (double kc : {2e6, 5e6, 7e6, 8e6, 9e6, 1.2e7, 3e7, 1e8}) {
      SCOPED_TRACE(fmt::format("kc {:g} work {:g} rpm", kc, work_rpm));
      auto measured = kit::build_model(measured_table(frf, "measured", kc, work_rpm));
      const NyquistCount count = count_unstable_roots(*measured->return_difference());
      ASSERT_TRUE(count.reliable) << count.note;
      EXPECT_EQ(count.unstable_roots % 2, 0);
      const RightmostRoot root = find_rightmost_root(*true_g1(kc, work_rpm)->characteristic(), band(1222.0));
      ASSERT_TRUE(root.certified);
      EXPECT_EQ(count.unstable_roots > 0, root.root.real() > 0.0) << "root " << root.root << ", count "
                                                                   << count.unstable_roots;
      (root.root.real() > 0.0 ? unstable : stable) += 1;
    }
  EXPECT_GE(stable, 3);
  EXPECT_GE(unstable, 3);
}

TEST(MeasuredFrf, GrindingWidthScalesEveryProcessStiffness) {
  const MeasuredFrf frf = testing::synthetic_frf(g8_modes(), 20.0, 400.0, 0.25);
  Json table = measured_table(frf, "fitted_modes", 2e8);
  table["grinding_width_mm"] = 17.5;
  table["reference_width_mm"] = 35.0;
  auto half = kit::build_model(table);
  const G1Process& p = dynamic_cast<const MeasuredFrfModel&>(*half).process();
  EXPECT_DOUBLE_EQ(p.contact_stiffness_n_per_m, 1e8);
  EXPECT_DOUBLE_EQ(p.wheel_wear_stiffness_n_per_m, 3.15e10);
  EXPECT_DOUBLE_EQ(p.work_removal_stiffness_n_per_m, 1e7);
  table["reference_width_mm"] = nullptr;
  const std::string e = testing::input_error_of([&] { kit::build_model(table); });
  EXPECT_NE(e.find("model.reference_width_mm is missing: grinding_width_mm and reference_width_mm go together"),
            std::string::npos) << e;
}

TEST(MeasuredFrf, FrfFileRelativeToTheStudyAndItsErrors) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "data");
  dir.write("data/tap.uff", uff58_bytes(testing::synthetic_frf(g8_modes(), 20.0, 400.0, 0.25, 0.02, 1),
                                        UffEncoding::binary_little_endian));
  const std::string model =
      "[study]\nkind = \"stability_map\"\n[model]\ntype = \"measured_frf\"\n"
      "wheel_speed_rpm = 1450\nwork_speed_rpm = 55\ncontact_stiffness_n_per_m = 1e7\n"
      "wheel_wear_stiffness_n_per_m = 6.3e10\nwork_removal_stiffness_n_per_m = 2e7\n";
  const Study study = load_study(dir.write("ok.toml", model + "frf_file = \"data/tap.uff\"\n"));
  EXPECT_EQ(study.document["model"]["frf_file"], (dir.path() / "data/tap.uff").string());
  std::string e = testing::input_error_of([&] { load_study(dir.write("missing.toml", model + "frf_file = \"data/no.uff\"\n")); });
  EXPECT_NE(e.find("missing.toml:10: model.frf_file = \"data/no.uff\": no such file (" +
                   (dir.path() / "data/no.uff").string() + ")"),
            std::string::npos) << e;
  // The measured route has no characteristic function: stability_map says so at load time.
  e = testing::input_error_of([&] {
    load_study(dir.write("route.toml", model + "frf_file = \"data/tap.uff\"\nmachine_compliance = \"measured\"\n"));
  });
  EXPECT_NE(e.find("route.toml:4: model.type = \"measured_frf\": this model has no characteristic function"),
            std::string::npos) << e;
  e = testing::input_error_of([&] { load_study(dir.write("none.toml", model)); });
  EXPECT_NE(e.find("model: missing FRF: give frf_file, or frf_frequency_hz, frf_real_m_per_n and frf_imag_m_per_n"),
            std::string::npos) << e;
  // A corrupt file: the FRF reader's message names the data file and its line.
  dir.write("data/bad.csv", "frequency [Hz], real [m/N], imag [m/N]\n10, 1e-8, 0\n20, oops, 0\n");
  e = testing::input_error_of([&] { load_study(dir.write("bad.toml", model + "frf_file = \"data/bad.csv\"\n")); });
  EXPECT_NE(e.find("data/bad.csv:3: column 'real' = 'oops': expected a finite number"), std::string::npos) << e;
}

}  // namespace
}  // namespace chatterlab
