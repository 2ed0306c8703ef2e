#include "chatterlab/planner/generatrix.hpp"

#include <fmt/format.h>
#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "planner/geometry.hpp"

namespace chatterlab::planner {

namespace {

// f from the expression's syntax tree (exact derivatives). muparser parses the text first (its
// messages for bad syntax) and is the reference the tree's values are checked against, so the
// grammar and the functions mean what they mean in muparser.
class ExpressionGeneratrix final : public Generatrix {
 public:
  ExpressionGeneratrix(const std::string& expression, double x_min, double x_max)
      : x_min_(x_min), x_max_(x_max) {
    mu::Parser parser;
    double x = x_min;
    try {
      parser.DefineVar("x", &x);
      parser.SetExpr(expression);
      parser.Eval();  // parses: syntax errors and unknown names surface here
    } catch (const mu::Parser::exception_type& e) {
      throw std::invalid_argument(fmt::format("cannot parse \"{}\": {}", expression, e.GetMsg()));
    }
    try {
      tree_ = Expression::parse(expression);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format(
          "\"{}\" is valid muparser but outside the grammar the geometry analysis reads ({})",
          expression, e.what()));
    }
    for (int i = 0; i <= 64; ++i) {
      x = x_min + (x_max - x_min) * i / 64.0;
      const double reference = parser.Eval(), ours = tree_.value(x);
      const bool both_nan = std::isnan(reference) && std::isnan(ours);
      if (!both_nan && !(std::abs(reference - ours) <= 1e-12 * std::max(1.0, std::abs(reference))))
        throw std::invalid_argument(fmt::format(
            "\"{}\": the analysed expression gives {} at x = {} where muparser gives {} (please "
            "report this)", expression, ours, x, reference));
    }
  }
  double x_min_mm() const override { return x_min_; }
  double x_max_mm() const override { return x_max_; }
  std::string describe() const override { return "y = " + tree_.text(); }
  GeneratrixValue evaluate(double x) const override {
    const Jet j = tree_.jet(x);
    return {j.v, j.d1, j.d2};
  }
  GeometryAnalysis analyse(double resolution_mm) const override {
    return analyse_expression(tree_, x_min_, x_max_, resolution_mm);
  }

 private:
  Expression tree_;
  double x_min_, x_max_;
};

class SplineGeneratrix final : public Generatrix {
 public:
  SplineGeneratrix(CubicSpline spline, std::string description)
      : spline_(std::move(spline)), description_(std::move(description)) {}
  double x_min_mm() const override { return spline_.x.front(); }
  double x_max_mm() const override { return spline_.x.back(); }
  std::string describe() const override { return description_; }
  GeneratrixValue evaluate(double x) const override {
    const Jet j = spline_.evaluate(x);
    return {j.v, j.d1, j.d2};
  }
  GeometryAnalysis analyse(double resolution_mm) const override {
    return analyse_spline(spline_, resolution_mm);
  }
  std::vector<double> knots_mm() const override { return spline_.x; }

 private:
  CubicSpline spline_;
  std::string description_;
};

}  // namespace

std::string Singularity::describe(double resolution_mm) const {
  switch (kind) {
    case Kind::not_finite: return fmt::format("f is not finite at x = {:.6g}", x_mm);
    case Kind::vertical_tangent:
      return fmt::format("the slope f' is not finite (a vertical tangent) at x = {:.6g}", x_mm);
    case Kind::jump: return fmt::format("f jumps by {:.4g} mm at x = {:.6g} (must be continuous)", size, x_mm);
    case Kind::kink:
      return fmt::format("the slope f' jumps by {:.4g} at x = {:.6g} (a kink: the slope must be continuous; {})",
                         size, x_mm,
                         concave ? "a concave corner, where no wheel edge radius fits: limit 0 mm"
                                 : "a convex corner, where the work would have to turn at once");
    case Kind::narrow_feature:
      return fmt::format(
          "a feature narrower than the resolution {} mm at x = {:.6g}: the tangent turns at {:.4g} "
          "rad/mm (more than 1 rad within {} mm of x)",
          resolution_mm, x_mm, size, resolution_mm);
  }
  return {};
}

std::unique_ptr<Generatrix> expression_generatrix(const std::string& expression, double x_min_mm,
                                                  double x_max_mm) {
  return std::make_unique<ExpressionGeneratrix>(expression, x_min_mm, x_max_mm);
}

std::unique_ptr<Generatrix> cubic_spline_generatrix(CubicSpline spline, std::string description) {
  return std::make_unique<SplineGeneratrix>(std::move(spline), std::move(description));
}

std::unique_ptr<Generatrix> spline_generatrix(std::vector<double> x_mm, std::vector<double> y_mm) {
  const std::size_t n = x_mm.size();
  return cubic_spline_generatrix(interpolating_spline(x_mm, y_mm),
                                 fmt::format("natural cubic spline through {} points", n));
}

GeometryAnalysis check_smooth(const Generatrix& generatrix, double resolution_mm) {
  GeometryAnalysis analysis = generatrix.analyse(resolution_mm);
  const auto& found = analysis.singularities;
  if (!found.empty()) {
    std::string message = found.front().describe(resolution_mm);
    if (found.size() > 1) {
      message += "; also ";
      for (std::size_t i = 1; i < std::min<std::size_t>(found.size(), 4); ++i)
        message += (i > 1 ? ", " : "") + found[i].describe(resolution_mm);
      if (found.size() > 4) message += fmt::format(" and {} more", found.size() - 4);
    }
    throw std::invalid_argument(message);
  }
  return analysis;
}

}  // namespace chatterlab::planner
