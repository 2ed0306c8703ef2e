#include "chatterlab/planner/generatrix.hpp"

#include <fmt/format.h>
#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace chatterlab::planner {

namespace {

class ExpressionGeneratrix final : public Generatrix {
 public:
  ExpressionGeneratrix(const std::string& expression, double x_min, double x_max)
      : expression_(expression), x_min_(x_min), x_max_(x_max),
        step_(1e-4 * std::max(x_max - x_min, 1e-3)) {
    try {
      parser_.DefineVar("x", &x_);
      parser_.SetExpr(expression);
      x_ = x_min;
      parser_.Eval();  // parses: syntax errors and unknown names surface here
    } catch (const mu::Parser::exception_type& e) {
      throw std::invalid_argument(fmt::format("cannot parse \"{}\": {}", expression, e.GetMsg()));
    }
  }
  double x_min_mm() const override { return x_min_; }
  double x_max_mm() const override { return x_max_; }
  std::string describe() const override { return "y = " + expression_; }

  GeneratrixValue evaluate(double x) const override {
    // 6th-order central differences (truncation h^6 f^(7)/140 and h^6 f^(8)/560).
    double v[7];
    for (int i = 0; i < 7; ++i) v[i] = value(x + (i - 3) * step_);
    const double h = step_;
    GeneratrixValue out;
    out.f = v[3];
    out.d1 = (-v[0] + 9 * v[1] - 45 * v[2] + 45 * v[4] - 9 * v[5] + v[6]) / (60 * h);
    out.d2 = (2 * v[0] - 27 * v[1] + 270 * v[2] - 490 * v[3] + 270 * v[4] - 27 * v[5] + 2 * v[6]) /
             (180 * h * h);
    return out;
  }

 private:
  double value(double x) const {
    x_ = x;
    try {
      return parser_.Eval();
    } catch (const mu::Parser::exception_type& e) {
      throw std::invalid_argument(fmt::format("cannot evaluate \"{}\" at x = {}: {}", expression_,
                                              x, e.GetMsg()));
    }
  }

  std::string expression_;
  double x_min_, x_max_, step_;
  mutable double x_ = 0.0;
  mutable mu::Parser parser_;
};

// Natural cubic spline (second derivatives M_i, M_0 = M_n = 0).
class SplineGeneratrix final : public Generatrix {
 public:
  SplineGeneratrix(std::vector<double> x, std::vector<double> y) : x_(std::move(x)), y_(std::move(y)) {
    const std::size_t n = x_.size();
    if (n < 3 || y_.size() != n)
      throw std::invalid_argument("a point table needs at least 3 points (x, y)");
    for (std::size_t i = 0; i + 1 < n; ++i)
      if (!(x_[i + 1] > x_[i]))
        throw std::invalid_argument(fmt::format(
            "x must increase strictly: point {} has x = {} after x = {}", i + 2, x_[i + 1], x_[i]));
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(x_[i]) || !std::isfinite(y_[i]))
        throw std::invalid_argument(fmt::format("point {} is not finite", i + 1));
    // Tridiagonal system for the interior M_i (Thomas algorithm).
    m_.assign(n, 0.0);
    std::vector<double> c(n, 0.0), d(n, 0.0);
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const double h0 = x_[i] - x_[i - 1], h1 = x_[i + 1] - x_[i];
      const double rhs = 6 * ((y_[i + 1] - y_[i]) / h1 - (y_[i] - y_[i - 1]) / h0);
      const double diag = 2 * (h0 + h1) - h0 * c[i - 1];
      c[i] = h1 / diag;
      d[i] = (rhs - h0 * d[i - 1]) / diag;
    }
    for (std::size_t i = n - 2; i >= 1; --i) m_[i] = d[i] - c[i] * m_[i + 1];
  }
  double x_min_mm() const override { return x_.front(); }
  double x_max_mm() const override { return x_.back(); }
  std::string describe() const override {
    return fmt::format("natural cubic spline through {} points", x_.size());
  }
  GeneratrixValue evaluate(double x) const override {
    const auto it = std::upper_bound(x_.begin() + 1, x_.end() - 1, x);
    const auto i = static_cast<std::size_t>(it - x_.begin()) - 1;
    const double h = x_[i + 1] - x_[i], a = (x_[i + 1] - x) / h, b = (x - x_[i]) / h;
    GeneratrixValue out;
    out.f = a * y_[i] + b * y_[i + 1] + ((a * a * a - a) * m_[i] + (b * b * b - b) * m_[i + 1]) * h * h / 6;
    out.d1 = (y_[i + 1] - y_[i]) / h - (3 * a * a - 1) * h / 6 * m_[i] + (3 * b * b - 1) * h / 6 * m_[i + 1];
    out.d2 = a * m_[i] + b * m_[i + 1];
    return out;
  }

 private:
  std::vector<double> x_, y_, m_;
};

// Bisects [a, b] towards the half with the larger change of g; returns the change left after
// `halvings` halvings (a jump keeps its size, a smooth change shrinks like the interval).
template <class G>
double jump_left(const G& g, double a, double b, int halvings, double& where) {
  double ga = g(a), gb = g(b);
  for (int i = 0; i < halvings; ++i) {
    const double m = 0.5 * (a + b), gm = g(m);
    if (std::abs(gm - ga) >= std::abs(gb - gm)) {
      b = m;
      gb = gm;
    } else {
      a = m;
      ga = gm;
    }
  }
  where = 0.5 * (a + b);
  return std::abs(gb - ga);
}

template <class G>
void check_continuous(const G& g, double x0, double x1, const char* what, double smallest_jump,
                      int halvings) {
  constexpr int intervals = 4096;
  std::vector<double> v(intervals + 1);
  const double dx = (x1 - x0) / intervals;
  for (int i = 0; i <= intervals; ++i) {
    const double x = x0 + i * dx;
    v[static_cast<std::size_t>(i)] = g(x);
    if (!std::isfinite(v[static_cast<std::size_t>(i)]))
      throw std::invalid_argument(fmt::format("{} is not finite at x = {}", what, x));
  }
  for (std::size_t i = 0; i < intervals; ++i) {
    const double d = std::abs(v[i + 1] - v[i]);
    const double left = i > 0 ? std::abs(v[i] - v[i - 1]) : 0.0;
    const double right = i + 1 < intervals ? std::abs(v[i + 2] - v[i + 1]) : 0.0;
    if (d <= 4 * std::max(left, right) + smallest_jump) continue;
    double where = 0.0;
    const double a = x0 + static_cast<double>(i) * dx;
    const double left_over = jump_left(g, a, a + dx, halvings, where);
    if (left_over > 0.25 * d)
      throw std::invalid_argument(
          fmt::format("{} jumps by {:.4g} near x = {:.6g} (must be continuous)", what, left_over, where));
  }
}

}  // namespace

std::unique_ptr<Generatrix> expression_generatrix(const std::string& expression, double x_min_mm,
                                                  double x_max_mm) {
  return std::make_unique<ExpressionGeneratrix>(expression, x_min_mm, x_max_mm);
}

std::unique_ptr<Generatrix> spline_generatrix(std::vector<double> x_mm, std::vector<double> y_mm) {
  return std::make_unique<SplineGeneratrix>(std::move(x_mm), std::move(y_mm));
}

void check_smooth(const Generatrix& generatrix) {
  const double a = generatrix.x_min_mm(), b = generatrix.x_max_mm();
  double scale = 0.0;
  for (int i = 0; i <= 16; ++i) {
    const GeneratrixValue v = generatrix.evaluate(a + (b - a) * i / 16.0);
    if (!std::isfinite(v.f) || !std::isfinite(v.d1) || !std::isfinite(v.d2))
      throw std::invalid_argument(fmt::format(
          "f is not finite (with its derivatives) at x = {} (it must be defined a little beyond "
          "the x range as well)", a + (b - a) * i / 16.0));
    scale = std::max(scale, std::abs(v.f));
  }
  check_continuous([&](double x) { return generatrix.evaluate(x).f; }, a, b, "f", 1e-9 * scale, 40);
  // The slope as a secant over +-delta (the derivative stencil would smooth a kink over its
  // width): bisection stops at ~10 delta, where a kink still shows its full size. Slope jumps
  // below 1e-4 (0.006 deg) are below the secant's rounding noise and harmless for a plan.
  const double delta = 1e-6 * (b - a);
  auto slope = [&](double x) {
    return (generatrix.evaluate(x + delta).f - generatrix.evaluate(x - delta).f) / (2 * delta);
  };
  check_continuous(slope, a, b, "the slope f'", 1e-4, 4);
}

}  // namespace chatterlab::planner
