// The stability_map study kind: its [stability] table, output columns, one grid point against
// independent reference roots (tests/cli/reference/dde_rightmost_roots.csv), and which plots a
// grid gets.
#include "study_kinds/stability_map/stability_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// The DDE-BIFTOOL oscillator x'' + 0.1 x' + 1.3 x = 0.3 x(t - 10).
constexpr const char* dde_model = R"(
[model]
type = "linear_dde"
a0 = [[0.0, 1.0], [-1.3, -0.1]]
delayed = [{ delay_s = 10.0, matrix = [[0.0, 0.0], [0.3, 0.0]] }]
)";

// MODELS.md G1 with two G8 modes at 55 rpm work speed, wheel 1300..1600 rpm in 7 steps: the CLI
// test study (point 3 is the G8 experiment's 1450 rpm).
Study plunge_study() {
  return load_study(fs::path(CHATTERLAB_SOURCE_DIR) / "tests/cli/studies/plunge_1d.toml");
}

Study load(const TempDir& dir, const std::string& body) {
  return load_study(dir.write("study.toml", "[study]\nkind = \"stability_map\"\n" + body));
}

std::size_t column(const std::vector<std::string>& columns, const std::string& name) {
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == name) return c;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

const StabilityMap kind;

TEST(StabilityMap, IsRegisteredWithItsTables) {
  const auto& entry = study_kind_registry().at("stability_map");
  EXPECT_EQ(entry.info.name, "stability_map");
  EXPECT_EQ(kind.tables(), (std::vector<std::string>{"model", "stability", "suppression"}));
}

TEST(StabilityMap, StabilityTableGetsDefaults) {
  TempDir dir;
  Study study = load(dir, dde_model);
  const Json& stability = study.document.at("stability");
  EXPECT_TRUE(stability.at("max_frequency_hz").is_null());  // derived from the model per point
  EXPECT_EQ(stability.at("max_newton_iterations"), 60);
  EXPECT_EQ(stability.at("newton_relative_tolerance"), 1e-13);
  EXPECT_EQ(stability.at("max_function_evaluations"), 3000000);
  // Validation is idempotent: load_study re-validates per grid value.
  Json again = study.document;
  again.erase("grid");
  Json before = again;
  struct NoSources final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  } sources;
  kind.validate(again, sources);
  EXPECT_EQ(again, before);
}

TEST(StabilityMap, BadStabilityKeysAreInputErrors) {
  TempDir dir;
  std::string unknown = testing::input_error_of(
      [&] { load(dir, std::string(dde_model) + "[stability]\nmax_freq = 2.0\n"); });
  EXPECT_NE(unknown.find("study.toml:"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown key 'stability.max_freq'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("max_frequency_hz, max_function_evaluations, max_newton_iterations, "
                         "newton_relative_tolerance"),
            std::string::npos)
      << unknown;
  std::string negative = testing::input_error_of(
      [&] { load(dir, std::string(dde_model) + "[stability]\nmax_frequency_hz = -1.0\n"); });
  EXPECT_NE(negative.find("stability.max_frequency_hz = -1"), std::string::npos) << negative;
  EXPECT_NE(negative.find("> 0"), std::string::npos) << negative;
  std::string no_model =
      testing::input_error_of([&] { load(dir, "[stability]\nmax_frequency_hz = 1.0\n"); });
  EXPECT_NE(no_model.find("[model]"), std::string::npos) << no_model;
}

TEST(StabilityMap, WheelColumnOnlyForModelsWithAWheel) {
  TempDir dir;
  const std::vector<std::string> common = {
      "growth_rate_per_s", "chatter_frequency_hz",      "stable",
      "certified",         "certified_real_part_per_s", "certificate", "route"};
  EXPECT_EQ(kind.output_columns(load(dir, dde_model).document), common);
  std::vector<std::string> with_wheel = common;
  with_wheel.insert(with_wheel.begin() + 2, "growth_rate_per_wheel_rev");
  // A model with process conditions also reports the verdict over the speed-tolerance band.
  for (const char* c : {"band_worst_growth_rate_per_s", "band_worst_chatter_frequency_hz",
                        "stable_over_speed_band", "exact_speed_ratio"})
    with_wheel.push_back(c);
  // G1 also reports G3's closed form (null unless the work chain is off).
  for (const char* c : {"g3_growth_rate_per_s", "g3_growth_rate_per_wheel_rev", "g3_chatter_frequency_hz",
                        "g3_max_growth_rate_per_wheel_rev"})
    with_wheel.push_back(c);
  EXPECT_EQ(kind.output_columns(plunge_study().document), with_wheel);
}

// G1 with the G8 machine's first two modes and soft process stiffnesses at wheel 1450 rpm: at
// work 290 rpm the speed ratio is exactly 5, the wheel's delay lattice coincides with every fifth
// line of the work's, and the rightmost root jumps to about -2.9 /s, while at 289.9 and 290.01 rpm
// it is within 1e-7 /s of the axis. The verdict over the +-0.5 % band does not rest on the
// coincidence: it is as marginal as the neighbours' and says which ratio was exact.
TEST(StabilityMap, ExactSpeedRatioIsFlaggedAndTheBandVerdictIgnoresIt) {
  TempDir dir;
  const std::string model = R"(
[model]
type = "plunge_regenerative"
wheel_speed_rpm = 1450
work_speed_rpm = 290
contact_stiffness_n_per_m = 1.0e7
wheel_wear_stiffness_n_per_m = 6.3e10
work_removal_stiffness_n_per_m = 2.0e6
modes = [
  { frequency_hz = 67.56, damping_ratio = 0.03, stiffness_n_per_m = 5.53e7 },
  { frequency_hz = 102.44, damping_ratio = 0.03, stiffness_n_per_m = 1.27e8 },
]
[stability]
max_frequency_hz = 1250
[grid]
work_speed_rpm = [289.9, 290.0, 290.01]
)";
  Study study = load(dir, model);
  const std::vector<std::string> columns = kind.output_columns(study.document);
  auto value = [&](std::size_t point, const char* name) {
    return kind.run_point(study.point_document(point), {})[column(columns, name)];
  };
  const double exact = value(1, "growth_rate_per_s").get<double>();
  const double near = value(2, "growth_rate_per_s").get<double>();
  EXPECT_LT(exact, -1.0);             // the coincidence
  EXPECT_GT(near, -1e-7);             // its neighbours: marginal
  EXPECT_EQ(value(1, "exact_speed_ratio"), "5/1");
  EXPECT_EQ(value(2, "exact_speed_ratio"), "");
  const double band = value(1, "band_worst_growth_rate_per_s").get<double>();
  EXPECT_GT(band, -1e-5);             // the band sees the marginal neighbours
  EXPECT_GE(band, near - 1e-6);
  EXPECT_GE(value(0, "band_worst_growth_rate_per_s").get<double>(),
            value(0, "growth_rate_per_s").get<double>());  // the band includes the nominal point
}

TEST(StabilityMap, DdeBiftoolPointMatchesTheReferenceRoot) {
  TempDir dir;
  Study study = load(dir, std::string(dde_model) + "[stability]\nmax_frequency_hz = 1.0\n");
  std::vector<std::string> columns = kind.output_columns(study.document);
  std::vector<Json> out = kind.run_point(study.point_document(0), {});
  ASSERT_EQ(out.size(), columns.size());
  // Reference: mpmath, 40 digits (tests/cli/reference/make_dde_reference.py).
  const double sigma = 0.038562247054131913, frequency = 0.178611627971801;
  const double modulus = std::hypot(sigma, 2 * std::numbers::pi * frequency);
  EXPECT_NEAR(out[column(columns, "growth_rate_per_s")].get<double>(), sigma, 1e-9 * modulus);
  EXPECT_NEAR(out[column(columns, "chatter_frequency_hz")].get<double>(), frequency,
              1e-9 * frequency);
  EXPECT_EQ(out[column(columns, "stable")], false);
  EXPECT_EQ(out[column(columns, "certified")], true);
  EXPECT_GE(out[column(columns, "certified_real_part_per_s")].get<double>(), sigma);
  EXPECT_EQ(out[column(columns, "certificate")].get<std::string>().substr(0, 3), "ok:");
  EXPECT_FALSE(kind.requires_serial(study.document));
}

// MODELS.md G5 written once (issue 17's "must show"): the example of `chatterlab describe
// torsional_coupling` as a stability_map point gets a certified root from the derived route.
TEST(StabilityMap, TorsionalCouplingExampleIsCertifiedThroughTheDerivedRoute) {
  TempDir dir;
  Study study = load(dir, testing::example_model_toml("torsional_coupling"));
  std::vector<std::string> columns = kind.output_columns(study.document);
  std::vector<Json> out = kind.run_point(study.point_document(0), {});
  ASSERT_EQ(out.size(), columns.size());
  EXPECT_EQ(out[column(columns, "certified")], true);
  EXPECT_EQ(out[column(columns, "certificate")].get<std::string>().substr(0, 3), "ok:")
      << out[column(columns, "certificate")];
  EXPECT_GT(out[column(columns, "chatter_frequency_hz")].get<double>(), 0.0);
}

TEST(StabilityMap, GrowthPerWheelRevolutionIsTgReSOver2Pi) {
  Study study = plunge_study();
  ASSERT_EQ(study.grid.at(0).values.at(3), 1450.0);
  std::vector<std::string> columns = kind.output_columns(study.document);
  std::vector<Json> out = kind.run_point(study.point_document(3), {});
  const double sigma = out[column(columns, "growth_rate_per_s")].get<double>();
  const double wheel_period = 60.0 / 1450.0;
  EXPECT_NEAR(out[column(columns, "growth_rate_per_wheel_rev")].get<double>(),
              wheel_period * sigma / (2 * std::numbers::pi), 1e-15 * std::abs(sigma));
  EXPECT_EQ(out[column(columns, "stable")], sigma < 0);
}

TEST(StabilityMap, TinyWorkBudgetFailsThePoint) {
  TempDir dir;
  Study study =
      load(dir, std::string(dde_model) +
                    "[stability]\nmax_frequency_hz = 1.0\nmax_function_evaluations = 3\n");
  try {
    kind.run_point(study.point_document(0), {});
    ADD_FAILURE() << "no failure with a budget of 3 evaluations";
  } catch (const PointFailure& e) {
    EXPECT_NE(std::string(e.what()).find("budget"), std::string::npos) << e.what();
  }
}

// Plots: which files a grid of a given shape gets (the drawing itself is plot.cpp's).
std::vector<std::string> plots_for(const std::string& grid,
                                   const std::string& model = std::string(dde_model) +
                                                              "[stability]\nmax_frequency_hz = 1.0\n") {
  TempDir dir;
  Study study = load(dir, model + "[grid]\n" + grid);
  std::vector<std::string> columns = kind.output_columns(study.document);
  ResultTable table;
  for (const auto& axis : study.grid) table.grid_columns.push_back(axis.key);
  table.output_columns = columns;
  for (std::size_t p = 0; p < study.point_count(); ++p) {
    std::vector<Json> row;
    std::vector<std::size_t> index = study.point_indices(p);
    for (std::size_t a = 0; a < study.grid.size(); ++a)
      row.push_back(study.grid[a].values[index[a]]);
    for (auto& v : kind.run_point(study.point_document(p), {})) row.push_back(v);
    table.rows.push_back(row);
    table.status.push_back("ok");
  }
  fs::path out = dir.path() / "out";
  fs::create_directories(out);
  kind.write_artifacts(study, table, out);
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(out))
    if (e.path().extension() == ".png") files.push_back(e.path().stem().string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(StabilityMap, PlotsFollowTheNumberOfVaryingGridKeys) {
  EXPECT_EQ(plots_for("\"model.delayed.0.delay_s\" = [2.0, 5.0, 10.0]\n"),
            (std::vector<std::string>{"chatter_frequency", "growth_rate"}));
  // A key with one value is a fixed parameter, not a dimension.
  EXPECT_EQ(plots_for("\"model.a0.1.1\" = [-0.1]\n\"model.delayed.0.delay_s\" = [2.0, 5.0]\n"),
            (std::vector<std::string>{"chatter_frequency", "growth_rate"}));
  EXPECT_EQ(plots_for("\"model.delayed.0.matrix.1.0\" = [0.1, 0.3]\n\"model.delayed.0.delay_s\" = "
                      "[2.0, 5.0]\n"),
            (std::vector<std::string>{"chatter_frequency_map", "growth_rate_map"}));
  EXPECT_TRUE(plots_for("\"model.delayed.0.delay_s\" = [10.0]\n").empty());
  EXPECT_TRUE(
      plots_for("\"model.a0.1.1\" = [-0.1, -0.2]\n\"model.delayed.0.matrix.1.0\" = [0.1, 0.3]\n"
                "\"model.delayed.0.delay_s\" = [2.0, 5.0]\n")
          .empty());
}

// A model with closed-form indicators (chatterlab/closed_form.hpp): MODELS.md G2, Thompson.
constexpr const char* thompson_model = R"(
[model]
type = "thompson"
mass_kg = 20.0
damping_n_s_per_m = 3162.3
stiffness_n_per_m = 5.0e7
wheel_wear_compliance_m_per_n = 1.0e-9
work_removal_compliance_m_per_n = 5.0e-9
contact_compliance_m_per_n = 1.0e-8
wheel_speed_rpm = 1450
work_speed_rpm = 55
[stability]
max_frequency_hz = 600
)";

TEST(StabilityMap, ClosedFormIndicatorsBecomeColumnsAfterTheRootResults) {
  TempDir dir;
  Study study = load(dir, thompson_model);
  std::vector<std::string> columns = kind.output_columns(study.document);
  const std::size_t route = column(columns, "route");
  const std::size_t margin = column(columns, "closed_form_chatter_margin");
  EXPECT_GT(margin, route);
  EXPECT_EQ(columns.size(), route + 1 + 11);  // Thompson reports 11 indicators
  std::vector<Json> out = kind.run_point(study.point_document(0), {});
  ASSERT_EQ(out.size(), columns.size());
  // Example parameters: conditionally stable (a band exists), chattering at 1450/55 rpm, and the
  // closed form says so too.
  EXPECT_FALSE(out[column(columns, "boundary_a1_n_per_m")].is_null());
  EXPECT_EQ(out[column(columns, "stable")], false);
  EXPECT_GT(out[margin].get<double>(), 0.0);
  EXPECT_NEAR(out[column(columns, "unconditional_damping_n_s_per_m")].get<double>(),
              out[column(columns, "absolute_stability_damping_n_s_per_m")].get<double>(), 1e-6);
  // Models without indicators keep their columns (WheelColumnOnlyForModelsWithAWheel).
}

TEST(StabilityMap, ChatterMarginIndicatorsGetTheirOwnPlot) {
  EXPECT_EQ(plots_for("wheel_speed_rpm = [1400, 1450]\n", thompson_model),
            (std::vector<std::string>{"chatter_frequency", "closed_form_chatter_margin", "growth_rate"}));
}

}  // namespace
}  // namespace chatterlab
