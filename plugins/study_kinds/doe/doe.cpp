#include "study_kinds/doe/doe.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>

namespace chatterlab::doe {

namespace {

// Linear forms over GF(s) (s prime: arithmetic mod s) of `factors` basic columns: run r has the
// basic values (a, b, c, ...) = base-s digits of r, the first basic column varying slowest.
OrthogonalArray prime_field_array(std::string name, int s, int basics,
                                  const std::vector<std::vector<int>>& forms) {
  OrthogonalArray oa;
  oa.name = std::move(name);
  oa.levels = s;
  int runs = 1;
  for (int k = 0; k < basics; ++k) runs *= s;
  for (int r = 0; r < runs; ++r) {
    std::vector<int> digits(static_cast<std::size_t>(basics));
    for (int k = basics - 1, v = r; k >= 0; --k, v /= s)
      digits[static_cast<std::size_t>(k)] = v % s;
    std::vector<int> row;
    for (const auto& form : forms) {
      int value = 0;
      for (int k = 0; k < basics; ++k)
        value += form[static_cast<std::size_t>(k)] * digits[static_cast<std::size_t>(k)];
      row.push_back(value % s + 1);
    }
    oa.runs.push_back(std::move(row));
  }
  return oa;
}

// Two levels: column j (1-based) is the XOR of the basic columns whose bits are set in j, with
// the basic column of bit 0 varying slowest (Taguchi's standard order).
OrthogonalArray two_level_array(std::string name, int basics) {
  OrthogonalArray oa;
  oa.name = std::move(name);
  oa.levels = 2;
  const int runs = 1 << basics, columns = runs - 1;
  for (int r = 0; r < runs; ++r) {
    int bits = 0;  // bit k = basic column k of run r (basic 0 = slowest)
    for (int k = 0; k < basics; ++k)
      if (r & (1 << (basics - 1 - k))) bits |= 1 << k;
    std::vector<int> row;
    for (int j = 1; j <= columns; ++j)
      row.push_back(__builtin_popcount(static_cast<unsigned>(j & bits)) % 2 + 1);
    oa.runs.push_back(std::move(row));
  }
  return oa;
}

// L16(4^5) over GF(4) = {0, 1, x, x+1} (addition XOR, multiplication mod x^2 + x + 1):
// columns a, b, a + b, a + 2b, a + 3b.
OrthogonalArray l16_four_level() {
  constexpr std::array<std::array<int, 4>, 4> mul{
      {{0, 0, 0, 0}, {0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}}};
  OrthogonalArray oa;
  oa.name = "L16(4^5)";
  oa.levels = 4;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      std::vector<int> row{a + 1, b + 1};
      for (int k = 1; k <= 3; ++k)
        row.push_back((a ^ mul[static_cast<std::size_t>(k)][static_cast<std::size_t>(b)]) + 1);
      oa.runs.push_back(std::move(row));
    }
  return oa;
}

double sum(std::span<const double> v) { return std::accumulate(v.begin(), v.end(), 0.0); }

void check_same_length(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size() || a.empty())
    throw std::invalid_argument(
        fmt::format("DOE: columns of {} and {} values", a.size(), b.size()));
}

Fit finish_fit(Fit fit, std::span<const double> y) {
  fit.sse = sum_of_squared_errors(y, fit.predicted);
  return fit;
}

// Least squares y ~ design * beta (QR with column pivoting).
Eigen::VectorXd least_squares(const Eigen::MatrixXd& design, std::span<const double> y) {
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(y.size()));
  for (std::size_t i = 0; i < y.size(); ++i) rhs(static_cast<Eigen::Index>(i)) = y[i];
  return design.colPivHouseholderQr().solve(rhs);
}

Fit exponential_fit(std::string model, std::string label, std::span<const double> x, double a,
                    double b, double x0) {
  Fit fit;
  fit.model = std::move(model);
  fit.label = std::move(label);
  fit.coefficients = {a, b, x0};
  fit.formula = fmt::format("y = {:.6g} * {:.6g}^(x - {:.6g})", a, b, x0);
  fit.at = [a, b, x0](double xv) { return a * std::pow(b, xv - x0); };
  for (double xi : x) fit.predicted.push_back(fit.at(xi));
  return fit;
}

}  // namespace

std::vector<int> OrthogonalArray::column(std::size_t c) const {
  std::vector<int> out;
  for (const auto& row : runs) out.push_back(row.at(c));
  return out;
}

OrthogonalArray orthogonal_array(std::string_view name) {
  if (name == "L4") return two_level_array("L4(2^3)", 2);
  if (name == "L8") return two_level_array("L8(2^7)", 3);
  if (name == "L16") return two_level_array("L16(2^15)", 4);
  if (name == "L9") return prime_field_array("L9(3^4)", 3, 2, {{1, 0}, {0, 1}, {1, 1}, {2, 1}});
  if (name == "L27")
    return prime_field_array("L27(3^13)", 3, 3,
                             {{1, 0, 0},
                              {0, 1, 0},
                              {1, 1, 0},
                              {2, 1, 0},
                              {0, 0, 1},
                              {1, 0, 1},
                              {2, 0, 1},
                              {0, 1, 1},
                              {1, 1, 1},
                              {2, 1, 1},
                              {0, 2, 1},
                              {1, 2, 1},
                              {2, 2, 1}});
  if (name == "L16_4") return l16_four_level();
  throw std::invalid_argument(
      fmt::format("unknown orthogonal array '{}' (valid: L4, L8, L9, L16, L16_4, L27)", name));
}

std::vector<std::string> orthogonal_array_names() {
  return {"L4", "L8", "L9", "L16", "L16_4", "L27"};
}

bool balanced_pair(std::span<const int> a, std::span<const int> b) {
  if (a.size() != b.size() || a.empty()) return false;
  std::map<std::pair<int, int>, std::size_t> counts;
  std::map<int, int> levels_a, levels_b;
  for (std::size_t r = 0; r < a.size(); ++r) {
    ++counts[{a[r], b[r]}];
    levels_a[a[r]] = 1;
    levels_b[b[r]] = 1;
  }
  const std::size_t cells = levels_a.size() * levels_b.size();
  if (counts.size() != cells || a.size() % cells != 0) return false;
  for (const auto& [cell, n] : counts)
    if (n != a.size() / cells) return false;
  return true;
}

bool is_orthogonal(const std::vector<std::vector<int>>& columns) {
  for (std::size_t i = 0; i < columns.size(); ++i)
    for (std::size_t j = i + 1; j < columns.size(); ++j)
      if (!balanced_pair(columns[i], columns[j])) return false;
  return true;
}

FactorRange range_analysis(std::span<const double> factor, std::span<const double> response,
                           bool minimise) {
  check_same_length(factor, response);
  std::map<double, std::pair<double, std::size_t>> by_level;
  for (std::size_t r = 0; r < factor.size(); ++r) {
    auto& [s, n] = by_level[factor[r]];
    s += response[r];
    ++n;
  }
  FactorRange out;
  for (const auto& [level, sn] : by_level) {
    out.levels.push_back(level);
    out.sums.push_back(sn.first);
    out.counts.push_back(sn.second);
    out.means.push_back(sn.first / static_cast<double>(sn.second));
  }
  const auto [lo, hi] = std::minmax_element(out.means.begin(), out.means.end());
  out.range = *hi - *lo;
  out.best_level = out.levels[static_cast<std::size_t>((minimise ? lo : hi) - out.means.begin())];
  return out;
}

SumOfSquares column_sum_of_squares(std::span<const double> factor,
                                   std::span<const double> response) {
  const FactorRange r = range_analysis(factor, response, true);
  const double total = sum(response);
  double q = 0.0;
  for (std::size_t k = 0; k < r.levels.size(); ++k)
    q += r.sums[k] * r.sums[k] / static_cast<double>(r.counts[k]);
  return {q - total * total / static_cast<double>(response.size()),
          static_cast<int>(r.levels.size()) - 1};
}

Anova analyse_variance(const std::vector<std::vector<double>>& factors,
                       const std::vector<std::string>& names,
                       const std::vector<std::vector<double>>& errors,
                       std::span<const double> response) {
  if (names.size() != factors.size()) throw std::invalid_argument("ANOVA: one name per factor");
  const double n = static_cast<double>(response.size());
  Anova out;
  const double total = sum(response);
  out.correction_term = total * total / n;
  double squares = 0.0;
  for (double y : response) squares += y * y;
  out.total = {
      "total", squares - out.correction_term, static_cast<int>(response.size()) - 1, 0.0, {}, {}};

  double factor_s = 0.0;
  int factor_df = 0;
  for (std::size_t f = 0; f < factors.size(); ++f) {
    const SumOfSquares ss = column_sum_of_squares(factors[f], response);
    AnovaRow row{names[f], ss.s, ss.df, ss.df > 0 ? ss.s / ss.df : 0.0, {}, {}};
    factor_s += ss.s;
    factor_df += ss.df;
    out.factors.push_back(std::move(row));
  }
  out.error.source = "error";
  if (errors.empty()) {
    out.error.s = std::max(out.total.s - factor_s, 0.0);
    out.error.df = out.total.df - factor_df;
  } else {
    for (const auto& e : errors) {
      const SumOfSquares ss = column_sum_of_squares(e, response);
      out.error.s += ss.s;
      out.error.df += ss.df;
    }
  }
  out.unassigned = out.total.s - factor_s - out.error.s;
  if (out.error.df > 0) {
    out.error.ms = out.error.s / out.error.df;
    for (AnovaRow& row : out.factors) {
      if (row.df <= 0 || !(out.error.ms > 0)) continue;
      row.f = row.ms / out.error.ms;
      row.p = f_upper_tail(*row.f, row.df, out.error.df);
    }
  }
  return out;
}

double incomplete_beta(double a, double b, double x) {
  if (!(a > 0 && b > 0)) throw std::invalid_argument("incomplete beta: a, b must be > 0");
  if (x <= 0) return 0.0;
  if (x >= 1) return 1.0;
  // The continued fraction converges fast for x < (a + 1)/(a + b + 2); else use symmetry.
  if (x > (a + 1) / (a + b + 2)) return 1.0 - incomplete_beta(b, a, 1.0 - x);
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  // Modified Lentz evaluation of 1/(1+ d1/(1+ d2/(1+ ...))) (Numerical Recipes betacf).
  constexpr double tiny = 1e-300;
  double c = 1.0, d = 1.0 - (a + b) * x / (a + 1);
  if (std::abs(d) < tiny) d = tiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 10000; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((a + m2 - 1) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) return std::exp(log_front) * h / a;
  }
  throw std::runtime_error(fmt::format("incomplete beta I_{}({}, {}) did not converge", x, a, b));
}

double f_cdf(double f, double d1, double d2) {
  if (f <= 0) return 0.0;
  return incomplete_beta(d1 / 2, d2 / 2, d1 * f / (d1 * f + d2));
}

double f_upper_tail(double f, double d1, double d2) {
  if (f <= 0) return 1.0;
  return incomplete_beta(d2 / 2, d1 / 2, d2 / (d2 + d1 * f));
}

double f_critical(double alpha, double d1, double d2) {
  if (!(alpha > 0 && alpha < 1)) throw std::invalid_argument("F critical value: alpha in (0, 1)");
  double lo = 0.0, hi = 1.0;
  while (f_upper_tail(hi, d1, d2) > alpha) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f_upper_tail(mid, d1, d2) > alpha ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

std::string significance(double p) {
  if (p < 0.01) return "highly significant (p < 0.01)";
  if (p < 0.05) return "significant (p < 0.05)";
  if (p < 0.10) return "fairly significant (p < 0.10)";
  if (p < 0.25) return "some influence (p < 0.25)";
  return "not significant (p >= 0.25)";
}

double sum_of_squared_errors(std::span<const double> y, std::span<const double> predicted) {
  check_same_length(y, predicted);
  double s = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) s += (y[i] - predicted[i]) * (y[i] - predicted[i]);
  return s;
}

Fit fit_linear(std::span<const double> x, std::span<const double> y) {
  check_same_length(x, y);
  Eigen::MatrixXd design(static_cast<Eigen::Index>(x.size()), 2);
  for (std::size_t i = 0; i < x.size(); ++i) design.row(static_cast<Eigen::Index>(i)) << 1.0, x[i];
  const Eigen::VectorXd beta = least_squares(design, y);
  Fit fit;
  fit.model = "linear (least squares)";
  fit.label = "linear LS";
  fit.coefficients = {beta(0), beta(1)};
  fit.formula = fmt::format("y = {:.6g} + {:.6g} x", beta(0), beta(1));
  fit.at = [a = beta(0), b = beta(1)](double xv) { return a + b * xv; };
  for (double xi : x) fit.predicted.push_back(fit.at(xi));
  return finish_fit(std::move(fit), y);
}

Fit fit_quadratic(std::span<const double> x, std::span<const double> y) {
  check_same_length(x, y);
  Eigen::MatrixXd design(static_cast<Eigen::Index>(x.size()), 3);
  for (std::size_t i = 0; i < x.size(); ++i)
    design.row(static_cast<Eigen::Index>(i)) << 1.0, x[i], x[i] * x[i];
  const Eigen::VectorXd beta = least_squares(design, y);
  Fit fit;
  fit.model = "quadratic (least squares)";
  fit.label = "quadratic LS";
  fit.coefficients = {beta(0), beta(1), beta(2)};
  fit.formula = fmt::format("y = {:.6g} + {:.6g} x + {:.6g} x^2", beta(0), beta(1), beta(2));
  fit.at = [a = beta(0), b = beta(1), c = beta(2)](double xv) { return a + b * xv + c * xv * xv; };
  for (double xi : x) fit.predicted.push_back(fit.at(xi));
  return finish_fit(std::move(fit), y);
}

Fit fit_exponential_log_linear(std::span<const double> x, std::span<const double> y, double x0) {
  check_same_length(x, y);
  std::vector<double> log_y;
  for (double v : y) {
    if (!(v > 0)) throw std::invalid_argument("exponential fit: every y must be > 0");
    log_y.push_back(std::log(v));
  }
  Eigen::MatrixXd design(static_cast<Eigen::Index>(x.size()), 2);
  for (std::size_t i = 0; i < x.size(); ++i)
    design.row(static_cast<Eigen::Index>(i)) << 1.0, x[i] - x0;
  const Eigen::VectorXd beta = least_squares(design, log_y);
  return finish_fit(
      exponential_fit("exponential (log-linear least squares)", "exponential log-linear LS", x,
                      std::exp(beta(0)), std::exp(beta(1)), x0),
      y);
}

Fit fit_exponential_nonlinear(std::span<const double> x, std::span<const double> y, double x0) {
  const Fit start = fit_exponential_log_linear(x, y, x0);
  // Parameters (a, k) with y = a e^{k (x - x0)}, b = e^k: Levenberg-Marquardt on the residuals.
  double a = start.coefficients[0], k = std::log(start.coefficients[1]);
  auto sse = [&](double aa, double kk) {
    double s = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double r = y[i] - aa * std::exp(kk * (x[i] - x0));
      s += r * r;
    }
    return s;
  };
  double current = sse(a, k), lambda = 1e-3;
  for (int iteration = 0; iteration < 200; ++iteration) {
    Eigen::Matrix2d jtj = Eigen::Matrix2d::Zero();
    Eigen::Vector2d jtr = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double e = std::exp(k * (x[i] - x0));
      const Eigen::Vector2d grad(e, a * (x[i] - x0) * e);  // d model / d(a, k)
      jtj += grad * grad.transpose();
      jtr += grad * (y[i] - a * e);
    }
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::Matrix2d damped = jtj;
      damped.diagonal() *= 1.0 + lambda;
      const Eigen::Vector2d step = damped.ldlt().solve(jtr);
      const double trial = sse(a + step(0), k + step(1));
      if (trial < current) {
        const double gain = current - trial;
        a += step(0);
        k += step(1);
        current = trial;
        lambda = std::max(lambda / 10, 1e-12);
        improved = gain > 1e-15 * std::max(current, 1e-300);
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  return finish_fit(exponential_fit("exponential (nonlinear least squares)",
                                    "exponential nonlinear LS", x, a, std::exp(k), x0),
                    y);
}

Fit fit_two_point_parabola(std::span<const double> x, std::span<const double> y, std::size_t i,
                           std::size_t j) {
  check_same_length(x, y);
  if (i >= x.size() || j >= x.size() || x[i] == x[j])
    throw std::invalid_argument("two-point parabola: two points with different x needed");
  const double k = (y[j] - y[i]) / ((x[j] - x[i]) * (x[j] - x[i]));
  Fit fit;
  fit.model = "parabola through two points (book 5-46)";
  fit.label = "book parabola 5-46";
  fit.coefficients = {k, x[i], y[i]};
  fit.formula = fmt::format("y = {:.6g} (x - {:.6g})^2 + {:.6g}", k, x[i], y[i]);
  fit.at = [k, xi = x[i], yi = y[i]](double xv) { return k * (xv - xi) * (xv - xi) + yi; };
  for (double xv : x) fit.predicted.push_back(fit.at(xv));
  return finish_fit(std::move(fit), y);
}

Fit fit_two_point_exponential(std::span<const double> x, std::span<const double> y, std::size_t i,
                              std::size_t j) {
  check_same_length(x, y);
  if (i >= x.size() || j >= x.size() || x[i] == x[j] || !(y[i] > 0 && y[j] > 0))
    throw std::invalid_argument(
        "two-point exponential: two points with different x and y > 0 needed");
  const double b = std::pow(y[j] / y[i], 1.0 / (x[j] - x[i]));
  Fit fit = exponential_fit("exponential through two points (book 5-47)", "book exponential 5-47",
                            x, y[i], b, x[i]);
  return finish_fit(std::move(fit), y);
}

}  // namespace chatterlab::doe
