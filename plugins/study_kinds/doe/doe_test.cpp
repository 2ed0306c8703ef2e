// Known-answer tests of the DOE core (MODELS.md S4): orthogonal arrays, the F distribution
// against closed forms and printed table values, the book's L9 experiment recomputed from its raw
// numbers, and the single-factor regression fits.
#include "study_kinds/doe/doe.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace chatterlab::doe {
namespace {

// Book Table 5-3 (MODELS.md S4): columns A B e C and the chatter RMS in mV.
const std::vector<double> book_a{1, 1, 1, 2, 2, 2, 3, 3, 3};
const std::vector<double> book_b{1, 2, 3, 1, 2, 3, 1, 2, 3};
const std::vector<double> book_e{1, 2, 3, 2, 3, 1, 3, 1, 2};
const std::vector<double> book_c{1, 2, 3, 3, 1, 2, 2, 3, 1};
const std::vector<double> book_mv{40.6, 44.2, 30.1, 56.5, 34.5, 53.7, 52.8, 43.8, 27.3};

TEST(Doe, OrthogonalArraysAreBalancedInEveryPairOfColumns) {
  struct Expected {
    const char* name;
    std::size_t rows, columns;
    int levels;
  };
  for (const Expected& e :
       {Expected{"L4", 4, 3, 2}, Expected{"L8", 8, 7, 2}, Expected{"L9", 9, 4, 3},
        Expected{"L16", 16, 15, 2}, Expected{"L16_4", 16, 5, 4}, Expected{"L27", 27, 13, 3}}) {
    SCOPED_TRACE(e.name);
    const OrthogonalArray oa = orthogonal_array(e.name);
    EXPECT_EQ(oa.rows(), e.rows);
    EXPECT_EQ(oa.columns(), e.columns);
    EXPECT_EQ(oa.levels, e.levels);
    std::vector<std::vector<int>> columns;
    for (std::size_t c = 0; c < oa.columns(); ++c) columns.push_back(oa.column(c));
    for (std::size_t i = 0; i < columns.size(); ++i) {
      // Each column uses every level equally often.
      for (int level = 1; level <= e.levels; ++level)
        EXPECT_EQ(std::count(columns[i].begin(), columns[i].end(), level),
                  static_cast<long>(e.rows) / e.levels);
      for (std::size_t j = i + 1; j < columns.size(); ++j)
        EXPECT_TRUE(balanced_pair(columns[i], columns[j])) << "columns " << i + 1 << ", " << j + 1;
    }
    EXPECT_TRUE(is_orthogonal(columns));
  }
  EXPECT_THROW(orthogonal_array("L12"), std::invalid_argument);
}

TEST(Doe, StandardColumnOrder) {
  // L9 is the book's Table 5-3 (columns A B e C).
  const OrthogonalArray l9 = orthogonal_array("L9");
  for (std::size_t r = 0; r < 9; ++r) {
    EXPECT_EQ(l9.runs[r][0], book_a[r]);
    EXPECT_EQ(l9.runs[r][1], book_b[r]);
    EXPECT_EQ(l9.runs[r][2], book_e[r]);
    EXPECT_EQ(l9.runs[r][3], book_c[r]);
  }
  // Taguchi's L8 rows 1-3: 1111111, 1112222, 1221122.
  const OrthogonalArray l8 = orthogonal_array("L8");
  EXPECT_EQ(l8.runs[0], (std::vector<int>{1, 1, 1, 1, 1, 1, 1}));
  EXPECT_EQ(l8.runs[1], (std::vector<int>{1, 1, 1, 2, 2, 2, 2}));
  EXPECT_EQ(l8.runs[2], (std::vector<int>{1, 2, 2, 1, 1, 2, 2}));
  // A design that is not orthogonal is recognised.
  std::vector<int> broken = l9.column(1);
  std::swap(broken[0], broken[4]);  // A = 1 now meets B = 2, 2, 3
  EXPECT_FALSE(balanced_pair(l9.column(0), broken));
}

TEST(Doe, IncompleteBetaClosedForms) {
  for (double x : {0.01, 0.2, 0.5, 0.77, 0.99}) {
    EXPECT_NEAR(incomplete_beta(1, 3.5, x), 1 - std::pow(1 - x, 3.5), 1e-14);
    EXPECT_NEAR(incomplete_beta(2.5, 1, x), std::pow(x, 2.5), 1e-14);
    // I_x(2, 3) = P(Binomial(4, x) >= 2).
    const double binom = 6 * x * x * (1 - x) * (1 - x) + 4 * x * x * x * (1 - x) + x * x * x * x;
    EXPECT_NEAR(incomplete_beta(2, 3, x), binom, 1e-14);
  }
  EXPECT_NEAR(incomplete_beta(7.3, 7.3, 0.5), 0.5, 1e-14);
  EXPECT_NEAR(incomplete_beta(200, 300, 0.4), 1 - incomplete_beta(300, 200, 0.6), 1e-13);
}

TEST(Doe, FDistributionAgainstClosedFormsAndTables) {
  // F(2, 2): P(F > f) = 1/(1 + f). The book's F = 9.97 for B gives p = 0.0912.
  for (double f : {0.5, 3.0, 6.48, 9.97, 11.65, 99.0})
    EXPECT_NEAR(f_upper_tail(f, 2, 2), 1 / (1 + f), 1e-14);
  EXPECT_NEAR(f_upper_tail(9.97, 2, 2), 0.091158, 1e-6);
  EXPECT_NEAR(f_cdf(9.97, 2, 2) + f_upper_tail(9.97, 2, 2), 1.0, 1e-14);
  // The book's critical values F_alpha(2, 2) = 3, 9, 19, 99 (note under Table 5-4): 1/alpha - 1.
  EXPECT_NEAR(f_critical(0.25, 2, 2), 3.0, 1e-9);
  EXPECT_NEAR(f_critical(0.10, 2, 2), 9.0, 1e-9);
  EXPECT_NEAR(f_critical(0.05, 2, 2), 19.0, 1e-9);
  EXPECT_NEAR(f_critical(0.01, 2, 2), 99.0, 1e-8);
  // Printed F tables (e.g. NIST/SEMATECH e-Handbook 1.3.6.7.3).
  EXPECT_NEAR(f_critical(0.05, 3, 10), 3.708, 5e-4);
  EXPECT_NEAR(f_critical(0.01, 2, 6), 10.925, 5e-4);
  EXPECT_NEAR(f_critical(0.05, 1, 1), 161.448, 5e-3);
  EXPECT_NEAR(f_critical(0.05, 5, 20), 2.711, 5e-4);
  // F(1, n) = t(n)^2: t_0.975(10) = 2.228139.
  EXPECT_NEAR(f_upper_tail(2.228139 * 2.228139, 1, 10), 0.05, 1e-6);
}

TEST(Doe, BookL9RecomputedFromItsRawNumbers) {
  // By hand (MODELS.md S4, Table 5-3): T = sum y = 383.5, T^2/9 = 147072.25/9 = 16341.3611.
  // A: T1 = 40.6 + 44.2 + 30.1 = 114.9, T2 = 56.5 + 34.5 + 53.7 = 144.7, T3 = 52.8 + 43.8 + 27.3
  //    = 123.9; means 38.30, 48.23, 41.30, R = 9.93; Q = (13202.01 + 20938.09 + 15351.21)/3
  //    = 16497.1033, S_A = 155.7422.
  // B: T = 149.9, 122.5, 111.1; R = 12.93; Q = 49819.47/3 = 16606.49, S_B = 265.1289.
  // e: T = 138.1, 128.0, 117.4; R = 6.90; Q = 49238.37/3 = 16412.79, S_e = 71.4289.
  // C: T = 102.4, 150.7, 130.4; R = 16.10; Q = 50200.41/3 = 16733.47, S_C = 392.1089.
  // S_T = 17225.77 - 16341.3611 = 884.4089 = S_A + S_B + S_e + S_C (a saturated L9).
  // F = (S/2)/(S_e/2): 2.18038, 3.71179, 5.48950; F(2, 2) tail p = 1/(1 + F).
  // The printed T, t and R and S_T = 885 are right; the printed S = 201/309/361 and 31 (from
  // Q = 16542/16650/16702 and 16372) are not: they add up to 902, not 885.
  const FactorRange a = range_analysis(book_a, book_mv, true);
  EXPECT_NEAR(a.sums[0], 114.9, 1e-9);
  EXPECT_NEAR(a.sums[1], 144.7, 1e-9);
  EXPECT_NEAR(a.sums[2], 123.9, 1e-9);
  EXPECT_NEAR(a.range, 9.9333333, 1e-6);
  EXPECT_NEAR(range_analysis(book_b, book_mv, true).range, 12.9333333, 1e-6);
  EXPECT_NEAR(range_analysis(book_c, book_mv, true).range, 16.1, 1e-9);
  EXPECT_NEAR(range_analysis(book_e, book_mv, true).range, 6.9, 1e-9);
  // Best levels for less chatter: A1 B3 C1 (the book's conclusion).
  EXPECT_EQ(a.best_level, 1);
  EXPECT_EQ(range_analysis(book_b, book_mv, true).best_level, 3);
  EXPECT_EQ(range_analysis(book_c, book_mv, true).best_level, 1);
  EXPECT_EQ(range_analysis(book_c, book_mv, false).best_level, 2);

  const Anova anova =
      analyse_variance({book_a, book_b, book_c}, {"A", "B", "C"}, {book_e}, book_mv);
  EXPECT_NEAR(anova.correction_term, 16341.361111, 1e-5);
  EXPECT_NEAR(anova.factors[0].s, 155.742222, 1e-5);
  EXPECT_NEAR(anova.factors[1].s, 265.128889, 1e-5);
  EXPECT_NEAR(anova.factors[2].s, 392.108889, 1e-5);
  EXPECT_NEAR(anova.error.s, 71.428889, 1e-5);
  EXPECT_NEAR(anova.total.s, 884.408889, 1e-5);
  EXPECT_EQ(anova.total.df, 8);
  EXPECT_EQ(anova.error.df, 2);
  EXPECT_NEAR(anova.unassigned, 0.0, 1e-9);
  const double f_expected[] = {2.1803814, 3.7117879, 5.4895000};
  for (std::size_t f = 0; f < 3; ++f) {
    EXPECT_EQ(anova.factors[f].df, 2);
    ASSERT_TRUE(anova.factors[f].f && anova.factors[f].p);
    EXPECT_NEAR(*anova.factors[f].f, f_expected[f], 1e-5);
    EXPECT_NEAR(*anova.factors[f].p, 1 / (1 + f_expected[f]), 1e-6);
  }
  // The printed sums of squares do not add up to the printed total.
  EXPECT_GT(201 + 309 + 361 + 31, 885 + 10);
  // Without an error column the residual is the e column (the L9 is saturated).
  const Anova residual = analyse_variance({book_a, book_b, book_c}, {"A", "B", "C"}, {}, book_mv);
  EXPECT_NEAR(residual.error.s, anova.error.s, 1e-9);
  EXPECT_EQ(residual.error.df, 2);
}

// Book Table 5-5: plunge speed Vf (um/s) -> chatter (mV).
const std::vector<double> vf{2, 5, 8, 10, 12, 15, 18};
const std::vector<double> mv{14.7, 20.4, 22.8, 26.5, 32.2, 40.6, 53.1};

TEST(Doe, BookSingleFactorFits) {
  // Parabola with vertex (2, 14.7) through (18, 53.1): k = 38.4/256 = 0.15, SSE = 37.605.
  const Fit parabola = fit_two_point_parabola(vf, mv, 0, 6);
  EXPECT_NEAR(parabola.coefficients[0], 0.15, 1e-12);
  EXPECT_NEAR(parabola.sse, 37.605, 1e-9);
  // Exponential through (8, 22.8) and (15, 40.6): b = (40.6/22.8)^(1/7) = 1.0859, SSE ~ 9.01.
  const Fit exponential = fit_two_point_exponential(vf, mv, 2, 5);
  EXPECT_NEAR(exponential.coefficients[1], 1.0859, 5e-5);
  EXPECT_NEAR(exponential.sse, 9.01, 0.02);
  // With the printed rounded constants 22.8 * 1.0859^(Vf - 8) the SSE is 9.011 (Table 5-5).
  std::vector<double> printed;
  for (double x : vf) printed.push_back(22.8 * std::pow(1.0859, x - 8));
  EXPECT_NEAR(sum_of_squared_errors(mv, printed), 9.010974, 2e-3);

  // Least squares does better than the two-point fits of the same model family.
  const Fit quadratic = fit_quadratic(vf, mv);
  EXPECT_LT(quadratic.sse, parabola.sse);
  const Fit log_linear = fit_exponential_log_linear(vf, mv, 8);
  const Fit nonlinear = fit_exponential_nonlinear(vf, mv, 8);
  EXPECT_LT(nonlinear.sse, exponential.sse);
  EXPECT_LE(nonlinear.sse, log_linear.sse);
  // The nonlinear fit is a minimum: any small change of a or b raises the SSE.
  const double a = nonlinear.coefficients[0], b = nonlinear.coefficients[1];
  for (double da : {-1e-3, 1e-3})
    for (double db : {-1e-5, 0.0, 1e-5}) {
      std::vector<double> p;
      for (double x : vf) p.push_back((a + da) * std::pow(b + db, x - 8));
      EXPECT_GT(sum_of_squared_errors(mv, p), nonlinear.sse);
    }
}

TEST(Doe, LinearFitIsExactOnALine) {
  const std::vector<double> x{0, 1, 2, 5}, y{1, 3, 5, 11};
  const Fit line = fit_linear(x, y);
  EXPECT_NEAR(line.coefficients[0], 1, 1e-12);
  EXPECT_NEAR(line.coefficients[1], 2, 1e-12);
  EXPECT_NEAR(line.sse, 0, 1e-20);
  const std::vector<double> yq{1, 2, 5, 26};  // 1 + x^2
  EXPECT_NEAR(fit_quadratic(x, yq).coefficients[2], 1, 1e-12);
}

}  // namespace
}  // namespace chatterlab::doe
