#pragma once
// Design of experiments for process-condition matching (MODELS.md S4; book 5.4): Taguchi
// orthogonal arrays, range analysis, analysis of variance with F tests, and least-squares
// regression fits. docs/analysis/doe.md states the equations and checks the book's Table 5-3/5-4.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace chatterlab::doe {

// ------------------------------------------------------------------ orthogonal arrays
// runs[r][c] is the level (1..levels) of column c in run r. Columns are the linear forms over
// GF(s) of the basic columns (Taguchi's construction): for two levels, column j is the XOR of
// the basic columns whose bits are set in j (Taguchi's standard L4/L8/L16 order); L9 is
// (a, b, a+b, 2a+b) mod 3, the book's Table 5-3 order.
struct OrthogonalArray {
  std::string name;  // e.g. "L9(3^4)"
  int levels = 2;
  std::vector<std::vector<int>> runs;
  std::size_t rows() const { return runs.size(); }
  std::size_t columns() const { return runs.empty() ? 0 : runs.front().size(); }
  std::vector<int> column(std::size_t c) const;
};

// "L4", "L8", "L9", "L16", "L16_4" (L16(4^5)), "L27". Throws std::invalid_argument otherwise.
OrthogonalArray orthogonal_array(std::string_view name);
std::vector<std::string> orthogonal_array_names();

// Every combination of the two columns' levels occurs equally often (strength-2 balance).
bool balanced_pair(std::span<const int> a, std::span<const int> b);
// Every pair of columns balanced.
bool is_orthogonal(const std::vector<std::vector<int>>& columns);

// ------------------------------------------------------------------ range analysis
// Level labels are the distinct values of the factor column, ascending (1, 2, 3 in a Taguchi
// table). T_k: level sums, t_k = T_k / n_k: level means, R = max t - min t; the best level is the
// one with the smallest mean when minimising the response, the largest when maximising.
struct FactorRange {
  std::vector<double> levels, sums, means;
  std::vector<std::size_t> counts;
  double range = 0.0;
  double best_level = 0.0;
};
FactorRange range_analysis(std::span<const double> factor, std::span<const double> response,
                           bool minimise);

// ------------------------------------------------------------------ ANOVA
// Sum of squares of one column: S = sum_k T_k^2 / n_k - T^2 / n, df = levels - 1.
struct SumOfSquares {
  double s = 0.0;
  int df = 0;
};
SumOfSquares column_sum_of_squares(std::span<const double> factor,
                                   std::span<const double> response);

struct AnovaRow {
  std::string source;
  double s = 0.0;  // sum of squares
  int df = 0;
  double ms = 0.0;             // S / df
  std::optional<double> f, p;  // factors only, when the error has df > 0
};
struct Anova {
  std::vector<AnovaRow> factors;
  AnovaRow error;                // the error columns' sums (or the residual when there are none)
  AnovaRow total;                // S_T = sum y^2 - T^2/n, df = n - 1
  double unassigned = 0.0;       // S_T - factors - error: columns neither factor nor error
  double correction_term = 0.0;  // T^2 / n
};
// factors[f] / errors[e]: the level columns. With no error column the error is the residual
// S_T - sum S_f with df n - 1 - sum df_f. F = MS_f / MS_e, p = P(F(df_f, df_e) > F).
Anova analyse_variance(const std::vector<std::vector<double>>& factors,
                       const std::vector<std::string>& names,
                       const std::vector<std::vector<double>>& errors,
                       std::span<const double> response);

// ------------------------------------------------------------------ distributions
// Regularised incomplete beta I_x(a, b) (continued fraction, modified Lentz; symmetry
// I_x(a,b) = 1 - I_{1-x}(b,a) where the fraction converges slowly), relative accuracy ~1e-14.
double incomplete_beta(double a, double b, double x);
// F distribution (d1, d2 degrees of freedom): CDF P(F <= f) = I_{d1 f/(d1 f + d2)}(d1/2, d2/2)
// and the upper tail p = P(F > f) computed directly as I_{d2/(d2 + d1 f)}(d2/2, d1/2).
double f_cdf(double f, double d1, double d2);
double f_upper_tail(double f, double d1, double d2);
// Critical value F_alpha(d1, d2): P(F > F_alpha) = alpha (bisection on the tail).
double f_critical(double alpha, double d1, double d2);
// The book's wording of significance by p (Table 5-4 uses alpha = 0.25, 0.10, 0.05, 0.01).
std::string significance(double p);

// ------------------------------------------------------------------ regression
struct Fit {
  std::string model;    // e.g. "quadratic (least squares)"
  std::string label;    // short legend name, e.g. "quadratic LS"
  std::string formula;  // the fitted equation, printed
  std::vector<double> coefficients;
  double sse = 0.0;  // sum of squared residuals over the data
  std::vector<double> predicted;
  std::function<double(double)> at;  // the fitted curve y(x)
};
double sum_of_squared_errors(std::span<const double> y, std::span<const double> predicted);
Fit fit_linear(std::span<const double> x, std::span<const double> y);
Fit fit_quadratic(std::span<const double> x, std::span<const double> y);
// y = a b^(x - x0): log-linear least squares (ln y linear in x; y > 0 needed).
Fit fit_exponential_log_linear(std::span<const double> x, std::span<const double> y, double x0);
// y = a b^(x - x0): nonlinear least squares (Levenberg-Marquardt from the log-linear fit).
Fit fit_exponential_nonlinear(std::span<const double> x, std::span<const double> y, double x0);
// The book's two-point fits (S4, eqs 5-46, 5-47): the parabola with its vertex at point i
// through point j, y = (y_j - y_i)/(x_j - x_i)^2 (x - x_i)^2 + y_i, and the exponential through
// points i and j, y = y_i b^(x - x_i), b = (y_j / y_i)^(1/(x_j - x_i)).
Fit fit_two_point_parabola(std::span<const double> x, std::span<const double> y, std::size_t i,
                           std::size_t j);
Fit fit_two_point_exponential(std::span<const double> x, std::span<const double> y, std::size_t i,
                              std::size_t j);

}  // namespace chatterlab::doe
