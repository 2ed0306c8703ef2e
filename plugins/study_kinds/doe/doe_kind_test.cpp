// The `doe` study kind end to end: the shipped book study (MODELS.md S4) recomputed into
// summary.json, the maximise goal, and bad input with the message text.
#include "study_kinds/doe/doe_kind.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "chatterlab/study.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

Json run_and_read(const Study& study, const fs::path& out, std::vector<Json>* row = nullptr) {
  const DoeKind kind;
  PointContext context;
  context.artifact_dir = out;
  context.plots = false;
  auto values = kind.run_point(study.point_document(0), context);
  if (row) *row = values;
  std::ifstream in(out / "summary.json");
  return Json::parse(in);
}

TEST(DoeKind, ShippedBookStudy) {
  TempDir dir;
  std::vector<Json> row;
  const Json s = run_and_read(
      load_study(fs::path(CHATTERLAB_SOURCE_DIR) / "studies/doe_book_l9.toml"), dir.path(), &row);
  // Values derived by hand in doe_test.cpp (BookL9RecomputedFromItsRawNumbers).
  const Json& anova = s.at("anova");
  EXPECT_NEAR(anova.at("A").at("S").get<double>(), 155.742222, 1e-5);
  EXPECT_NEAR(anova.at("B").at("S").get<double>(), 265.128889, 1e-5);
  EXPECT_NEAR(anova.at("C").at("S").get<double>(), 392.108889, 1e-5);
  EXPECT_NEAR(anova.at("error").at("S").get<double>(), 71.428889, 1e-5);
  EXPECT_NEAR(anova.at("total").at("S").get<double>(), 884.408889, 1e-5);
  EXPECT_EQ(anova.at("A").at("df"), 2);
  EXPECT_EQ(anova.at("error").at("df"), 2);
  EXPECT_EQ(anova.at("total").at("df"), 8);
  EXPECT_NEAR(anova.at("C").at("F").get<double>(), 5.4895000, 1e-6);
  EXPECT_NEAR(anova.at("C").at("p").get<double>(), 1 / (1 + 5.4895000), 1e-7);
  EXPECT_NEAR(anova.at("B").at("F_critical").at("0.1").get<double>(), 9.0, 1e-8);
  EXPECT_NEAR(s.at("ranges").at("A").at("R").get<double>(), 9.9333333, 1e-6);
  EXPECT_NEAR(s.at("ranges").at("C").at("R").get<double>(), 16.1, 1e-9);
  EXPECT_EQ(s.at("ranges").at("B").at("best_level"), 3);
  EXPECT_EQ(s.at("best_combination"), "A1 B3 C1");
  EXPECT_EQ(s.at("factors_by_range"), (std::vector<std::string>{"C", "B", "A"}));
  EXPECT_EQ(s.at("array"), "L9(3^4)");
  EXPECT_TRUE(s.at("design_orthogonal").get<bool>());
  // Regression: the book's two-point fits and the least-squares fits (lower SSE).
  double book_parabola = 0, book_exponential = 0, ls_quadratic = 0, ls_exponential = 0;
  for (const Json& fit : s.at("regression").at("fits")) {
    const std::string model = fit.at("model");
    const double sse = fit.at("sse");
    if (model.find("parabola through two points") != std::string::npos) book_parabola = sse;
    if (model.find("exponential through two points") != std::string::npos) book_exponential = sse;
    if (model == "quadratic (least squares)") ls_quadratic = sse;
    if (model == "exponential (nonlinear least squares)") ls_exponential = sse;
  }
  EXPECT_NEAR(book_parabola, 37.605, 1e-9);
  EXPECT_NEAR(book_exponential, 9.01, 0.02);
  EXPECT_GT(ls_quadratic, 0.0);
  EXPECT_LT(ls_quadratic, book_parabola);
  EXPECT_GT(ls_exponential, 0.0);
  EXPECT_LT(ls_exponential, book_exponential);
  // results.csv row: S_A, F_A, p_A, ..., S_error, S_total, best_combination.
  ASSERT_EQ(row.size(), 12u);
  EXPECT_NEAR(row[0].get<double>(), 155.742222, 1e-5);
  EXPECT_EQ(row[11], "A1 B3 C1");
}

constexpr const char* l9_csv =
    "run,A,B,e,C,y\n1,1,1,1,1,40.6\n2,1,2,2,2,44.2\n3,1,3,3,3,30.1\n4,2,1,2,3,56.5\n"
    "5,2,2,3,1,34.5\n6,2,3,1,2,53.7\n7,3,1,3,2,52.8\n8,3,2,1,3,43.8\n9,3,3,2,1,27.3\n";

std::string doe_study(const std::string& input, const std::string& rest = "") {
  return "[study]\nkind = \"doe\"\n[input]\nfile = \"l9.csv\"\n" + input + rest;
}

TEST(DoeKind, MaximiseAndResidualError) {
  TempDir dir;
  dir.write("l9.csv", l9_csv);
  const Json s =
      run_and_read(load_text(dir, doe_study("response = \"y\"\nfactors = [\"A\", \"B\", \"C\"]\n",
                                            "[doe]\ngoal = \"maximize\"\n")),
                   dir.path() / "out");
  EXPECT_EQ(s.at("best_combination"), "A2 B1 C2");
  EXPECT_EQ(s.at("anova").at("error").at("columns"), "residual");
  EXPECT_NEAR(s.at("anova").at("error").at("S").get<double>(), 71.428889, 1e-5);
}

TEST(DoeKind, ColumnsByIndex) {
  // Columns may be named by 1-based index, as everywhere data tables are read.
  TempDir dir;
  dir.write("l9.csv", l9_csv);
  const Json s = run_and_read(
      load_text(dir, doe_study("response = \"6\"\nfactors = [\"2\", \"3\", \"5\"]\nerror_columns = [\"4\"]\n")),
      dir.path() / "out");
  EXPECT_NEAR(s.at("anova").at("5").at("S").get<double>(), 392.108889, 1e-5);  // C
  EXPECT_EQ(s.at("best_combination"), "21 33 51");
}

TEST(DoeKind, BadInputIsRefusedWithItsReason) {
  TempDir dir;
  dir.write("l9.csv", l9_csv);
  auto expect_in = [](const std::string& message, const std::string& part) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  };
  std::string m =
      testing::load_error(dir, doe_study("response = \"y\"\nfactors = [\"A\", \"D\"]\n"));
  expect_in(m, "study.toml:6: input.factors: no column \"D\" in");
  expect_in(m, "(columns: run, A, B, e, C, y)");
  m = testing::load_error(dir, doe_study("response = \"chatter\"\nfactors = [\"A\"]\n"));
  expect_in(m, "input.response: no column \"chatter\"");
  m = testing::load_error(dir, doe_study("factors = [\"A\"]\n"));
  expect_in(m, "missing required key 'input.response'");
  m = testing::load_error(dir, doe_study("response = \"y\"\nfactors = [\"A\", \"A\"]\n"));
  expect_in(m, "\"A\" is listed twice");
  m = testing::load_error(dir, doe_study("response = \"y\"\nfactors = [\"run\"]\n"));
  expect_in(m, "column \"run\" has a different value in every run");
  m = testing::load_error(
      dir, doe_study("response = \"y\"\nfactors = [\"A\"]\nerror_columns = [\"A\"]\n"));
  expect_in(m, "\"A\" is also the response or an error column");
  m = testing::load_error(
      dir, doe_study("response = \"y\"\nfactors = [\"A\"]\n", "[doe]\ngoal = \"smallest\"\n"));
  expect_in(m, "doe.goal");
}

}  // namespace
}  // namespace chatterlab
