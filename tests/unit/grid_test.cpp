// [grid]: key resolution, expansion of lists and ranges, grid order, per-value validation and
// normalisation, point documents.
#include <gtest/gtest.h>

#include "chatterlab/study.hpp"
#include "study_test_support.hpp"

namespace chatterlab::testing {
namespace {

std::vector<Json> values_of(const Study& study, std::size_t axis) { return study.grid.at(axis).values; }

TEST(Grid, KeysResolveToPathsAndKeepTheirNamesAndLines) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[grid]\n"                                           // 10
                                          "speed_rpm = [1000, 2000]\n"                         // 11
                                          "\"model.modes.1.damping_ratio\" = [0.01, 0.02]\n"   // 12
                                          "model.gains.1.0 = [0.5]\n"                          // 13
                                          "fake_settings.scale = [1.0, 3.0]\n"));              // 14
  ASSERT_EQ(study.grid.size(), 4u);
  EXPECT_EQ(study.grid[0].key, "speed_rpm");
  EXPECT_EQ(study.grid[0].path, "model.speed_rpm");
  EXPECT_EQ(study.grid[0].where.line, 11);
  EXPECT_EQ(study.grid[1].key, "model.modes.1.damping_ratio");
  EXPECT_EQ(study.grid[1].path, "model.modes.1.damping_ratio");
  EXPECT_EQ(study.grid[1].where.line, 12);
  // Written without quotes, TOML makes nested tables of the dotted key: it is still one grid key.
  EXPECT_EQ(study.grid[2].key, "model.gains.1.0");
  EXPECT_EQ(study.grid[2].where.line, 13);
  EXPECT_EQ(study.grid[3].path, "fake_settings.scale");
  EXPECT_EQ(study.point_count(), 2u * 2u * 1u * 2u);
  // The [grid] table is kept flat, as written, for meta.json.
  EXPECT_EQ(study.document["grid"]["model.gains.1.0"], Json::array({0.5}));
}

TEST(Grid, OrderIsAsWrittenEvenAcrossDottedSubtables) {
  TempDir dir;
  // toml++ sorts keys; dotted keys nest. The axis order must still be the written order.
  Study study = load_text(dir, fake_study("[grid]\n"
                                          "model.speed_rpm = [1000, 2000]\n"
                                          "mass_kg = [1.0, 2.0]\n"
                                          "model.harmonics = [1, 2]\n"
                                          "[grid.fake_settings]\n"
                                          "scale = [2.0]\n"));
  std::vector<std::string> keys;
  for (const auto& axis : study.grid) keys.push_back(axis.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"model.speed_rpm", "mass_kg", "model.harmonics",
                                            "fake_settings.scale"}));
}

TEST(Grid, CartesianProductWithTheLastKeyFastest) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[grid]\nspeed_rpm = [1000, 2000]\nmass_kg = [1.0, 2.0, 3.0]\n"));
  ASSERT_EQ(study.point_count(), 6u);
  std::vector<std::vector<std::size_t>> expected = {{0, 0}, {0, 1}, {0, 2}, {1, 0}, {1, 1}, {1, 2}};
  for (std::size_t p = 0; p < 6; ++p) EXPECT_EQ(study.point_indices(p), expected[p]) << "point " << p;
  Json point = study.point_document(4);
  EXPECT_EQ(point["model"]["speed_rpm"], 2000.0);
  EXPECT_EQ(point["model"]["mass_kg"], 2.0);
  EXPECT_FALSE(point.contains("grid")) << "a point is one set of values";
  EXPECT_EQ(point["model"]["modes"], study.document["model"]["modes"]) << "other values untouched";
  EXPECT_THROW(study.point_indices(6), std::out_of_range);
}

TEST(Grid, LinearRangesIncludeBothEndsAndGiveCleanDecimals) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[grid]\n"
                                          "speed_rpm = { from = 1000, to = 2000, steps = 5 }\n"
                                          "\"model.modes.0.damping_ratio\" = { from = 0.01, to = 0.05, steps = 5 }\n"
                                          "mass_kg = { from = 3, to = 1, steps = 3 }\n"
                                          "stiffness_n_per_m = { from = 5e6, to = 9e6, steps = 1 }\n"
                                          "\"model.gains.0.1\" = { from = -0.3, to = 0.3, steps = 7 }\n"));
  EXPECT_EQ(values_of(study, 0), (std::vector<Json>{1000.0, 1250.0, 1500.0, 1750.0, 2000.0}));
  // Exactly the doubles of the decimals 0.02, 0.03, 0.04, not 0.01 + k * 0.01 rounding noise.
  EXPECT_EQ(values_of(study, 1), (std::vector<Json>{0.01, 0.02, 0.03, 0.04, 0.05}));
  EXPECT_EQ(values_of(study, 2), (std::vector<Json>{3.0, 2.0, 1.0})) << "descending ranges";
  EXPECT_EQ(values_of(study, 3), (std::vector<Json>{5e6})) << "steps = 1 is just `from`";
  EXPECT_EQ(values_of(study, 4), (std::vector<Json>{-0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3})) << "through zero";
}

TEST(Grid, LogRangesAreGeometric) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[grid]\n"
                                          "stiffness_n_per_m = { from = 1e6, to = 1e9, steps = 4, log = true }\n"
                                          "mass_kg = { from = 1, to = 4, steps = 3, log = true }\n"));
  EXPECT_EQ(values_of(study, 0), (std::vector<Json>{1e6, 1e7, 1e8, 1e9}));
  EXPECT_EQ(values_of(study, 1), (std::vector<Json>{1.0, 2.0, 4.0}));
}

TEST(Grid, ValuesAreNormalisedByValidation) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[grid]\n"
                                          "speed_rpm = [1000, 1500.5]\n"
                                          "harmonics = { from = 1, to = 3, steps = 3 }\n"
                                          "mode_shape = [\"torsion\", \"bending\"]\n"));
  // A real parameter written as an integer becomes a double, a whole generated value for an
  // integer parameter becomes an integer: point documents look like validated documents.
  EXPECT_TRUE(values_of(study, 0)[0].is_number_float());
  for (const auto& v : values_of(study, 1)) EXPECT_TRUE(v.is_number_integer()) << v;
  EXPECT_EQ(values_of(study, 1), (std::vector<Json>{1, 2, 3}));
  EXPECT_EQ(values_of(study, 2), (std::vector<Json>{"torsion", "bending"}));
}

TEST(Grid, ReachesDefaultedKeysAndWholeTables) {
  TempDir dir;
  // stiffness_n_per_m is not written in [model]: it exists after defaults are filled in. A grid
  // value may also be a whole list of tables.
  Study study = load_text(dir, fake_study(
                                   "[grid]\n"
                                   "stiffness_n_per_m = [2e7]\n"
                                   "\"model.modes\" = [[{ frequency_hz = 50.0, damping_ratio = 0.3 }],\n"
                                   "                   [{ frequency_hz = 60.0, damping_ratio = 0.4 }]]\n"));
  EXPECT_EQ(study.point_count(), 2u);
  Json point = study.point_document(1);
  EXPECT_EQ(point["model"]["stiffness_n_per_m"], 2e7);
  EXPECT_EQ(point["model"]["modes"], Json::parse(R"([{"frequency_hz": 60.0, "damping_ratio": 0.4}])"));
}

TEST(Grid, EmptyGridTableIsOnePoint) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[grid]\n"));
  EXPECT_TRUE(study.grid.empty());
  EXPECT_EQ(study.point_count(), 1u);
}

TEST(Grid, AllowLargeAcceptsGridsOverTheLimitWithoutExpandingThePoints) {
  TempDir dir;
  // Just over this machine's limit (it depends on the memory: chatterlab/study.hpp GridCost).
  const std::size_t n = grid_cost(0, 2, 2).default_max_points / 10000 + 1;
  std::string text = fake_study("[grid]\n"
                                "speed_rpm = { from = 1, to = 2, steps = 10000 }\n"
                                "mass_kg = { from = 1, to = 2, steps = " + std::to_string(n) + " }\n");
  std::string message = input_error_of([&] { load_text(dir, text); });
  EXPECT_NE(message.find(std::to_string(10000 * n) + " points"), std::string::npos) << message;
  Study study = load_text(dir, text, {.allow_large = true});
  EXPECT_EQ(study.point_count(), 10000 * n);
  EXPECT_EQ(study.point_indices(10000 * n - 1), (std::vector<std::size_t>{9999, n - 1}));
  EXPECT_EQ(study.point_document(n + 1)["model"]["mass_kg"], study.grid[1].values[1]);
}

}  // namespace
}  // namespace chatterlab::testing
