// Geometry analysis (docs/planner.md, "Geometry analysis"): the expression tree against muparser,
// exact derivatives, interval enclosures that contain every sampled value, jumps and kinks found
// wherever they are (also on any grid a sampler would use), near-steps and other features
// narrower than the resolution refused with their place, the true curvature (expressions and
// spline knots), and the smoothing spline (limits, trace, GCV noise estimate, tolerance mode).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "chatterlab/planner/generatrix.hpp"
#include "planner/expression.hpp"
#include "planner/geometry.hpp"
#include "planner/smoothing_spline.hpp"

namespace chatterlab::planner {
namespace {

std::vector<Singularity> singularities(const std::string& expression, double a, double b,
                                       double resolution = default_geometry_resolution_mm) {
  return expression_generatrix(expression, a, b)->analyse(resolution).singularities;
}

TEST(Expression, AgreesWithMuparserOnItsGrammar) {
  // expression_generatrix throws when the tree and muparser differ anywhere on 65 points.
  for (const char* e : {"-x^2", "2^-x", "2^3^2 + x", "-2*x^2^0.5", "x < 3 && x > 1 ? 1 : 2",
                        "3 - 2 - 1 - x", "12/3/2*x", "1 < 2 == 1", "x == 3", "x != 3", "1+-x",
                        "min(x, 3, 2*x)", "max(x, 2)", "sum(x, 1)", "avg(x, 1, 2)", "atan2(x, 1)",
                        "sign(x - 3)", "rint(x / 7)", "abs(x - 3)^1.5", "log(x)", "ln(x)",
                        "log2(x)", "log10(x)", "exp(-x/4)", "sqrt(x)", "sinh(x/9)", "cosh(x/9)",
                        "tanh(x)", "asinh(x)", "acosh(x + 1)", "atanh(x/20)", "asin(x/20)",
                        "acos(x/20)", "atan(x)", "tan(x/20)", "_pi*x + _e", ".5e1*x",
                        "0 ? 1 : x > 5 ? 2 : 3"})
    EXPECT_NO_THROW(expression_generatrix(e, 0.1, 10.0)) << e;
  EXPECT_THROW(expression_generatrix("x +* 2", 0, 1), std::invalid_argument);
  EXPECT_THROW(expression_generatrix("foo(x)", 0, 1), std::invalid_argument);
}

TEST(Expression, JetsAreExactDerivatives) {
  // f = 30 e^{-x/400} sin((x + 25 pi)/100) + 130 (MODELS.md P3 problem 2): analytic f', f''.
  const Expression e = Expression::parse("30*exp(-x/400)*sin((x + 25*_pi)/100) + 130");
  for (double x : {0.0, 54.04, 321.6, 600.0}) {
    const double g = std::exp(-x / 400), s = std::sin((x + 25 * std::numbers::pi) / 100),
                 c = std::cos((x + 25 * std::numbers::pi) / 100);
    const Jet j = e.jet(x);
    EXPECT_NEAR(j.d1, 30 * g * (-s / 400 + c / 100), 1e-15);
    EXPECT_NEAR(j.d2, 30 * g * (s / 160000 - 2 * c / 40000 - s / 10000), 1e-16);
  }
  // Quotient, power with a variable exponent, atan2.
  const Jet q = Expression::parse("x^x / (1 + x)").jet(2.0);  // x^x = e^{x ln x}
  const double p = 4.0, p1 = p * (std::log(2.0) + 1), p2 = p1 * (std::log(2.0) + 1) + p / 2;
  EXPECT_NEAR(q.d1, (p1 * 3 - p) / 9, 1e-14);
  EXPECT_NEAR(q.d2, (9 * p2 - 2 * (3 * p1 - p)) / 27, 1e-13);  // p''/(1+x) - 2 (p'(1+x) - p)/(1+x)^3
  const Jet t = Expression::parse("atan2(x, 2)").jet(1.0);
  EXPECT_NEAR(t.d1, 2.0 / 5, 1e-15);
  EXPECT_NEAR(t.d2, -2.0 * 2 * 1 / 25, 1e-15);
}

// An enclosure over an interval contains f, f', f'' at every point of it (property test over
// random intervals of several smooth expressions).
TEST(Expression, EnclosuresContainEverySampledValue) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> where(0.5, 40.0), width(1e-6, 8.0);
  for (const char* text : {"30*exp(-x/400)*sin((x + 25*_pi)/100) + 130", "130 - 8*exp(-((x-15)/3)^2)",
                           "120 + 40*sin(x/15)", "sqrt(x)*log(x + 1)", "x^3/(1 + x^2)", "tanh((x-20)/2)",
                           "atan(x - 10)*cosh(x/30)", "x^1.5 - 2^x/1e6"}) {
    const Expression e = Expression::parse(text);
    for (int trial = 0; trial < 200; ++trial) {
      const double lo = where(rng), hi = lo + width(rng);
      const IntervalJet j = e.enclose({lo, hi});
      ASSERT_FALSE(j.may_switch) << text;
      for (int k = 0; k <= 20; ++k) {
        const double x = lo + (hi - lo) * k / 20.0;
        const Jet p = e.jet(x);
        EXPECT_TRUE(j.v.contains(p.v)) << text << " f at " << x;
        EXPECT_TRUE(j.d1.contains(p.d1)) << text << " f' at " << x;
        EXPECT_TRUE(j.d2.contains(p.d2)) << text << " f'' at " << x;
      }
    }
  }
  // Switch flags: abs is flagged over an interval holding its zero (ends included), not beside it.
  const Expression a = Expression::parse("abs(x - 3)");
  EXPECT_TRUE(a.enclose({2.0, 4.0}).may_switch);
  EXPECT_TRUE(a.enclose({3.0, 4.0}).may_switch);
  EXPECT_FALSE(a.enclose({3.5, 4.0}).may_switch);
  EXPECT_TRUE(Expression::parse("x < 3 ? 1 : 2").enclose({2.9, 3.1}).may_switch);
  EXPECT_TRUE(Expression::parse("log(x - 3)").enclose({2.0, 4.0}).may_be_undefined);
}

// The audit's kinks: 100 + |x - c| on [0, 600] was refused only where c missed the old 4096-cell
// grid. Found now at every c, the grid's nodes included, with the slope jump 2 and the place.
TEST(GeometryAnalysis, KinksAreFoundWhereverTheyAre) {
  for (double c : {150.0, 300.0, 337.5, 100.0, 250.0, 600.0 / 4096 * 1234, 0.001, 599.99, 123.456789}) {
    const auto found = singularities(fmt::format("100 + abs(x - {})", c), 0.0, 600.0);
    ASSERT_EQ(found.size(), 1u) << c;
    EXPECT_EQ(found[0].kind, Singularity::Kind::kink) << c;
    EXPECT_NEAR(found[0].x_mm, c, 1e-6) << c;
    EXPECT_NEAR(found[0].size, 2.0, 1e-6) << c;
  }
  // 100 + |x - c| is a valley corner: concave, infinite curvature, edge-radius limit 0 there;
  // 100 - |x - c| a ridge: convex.
  const GeometryAnalysis valley = expression_generatrix("100 + abs(x - 300)", 0, 600)->analyse(0.01);
  EXPECT_TRUE(valley.singularities.at(0).concave);
  EXPECT_TRUE(std::isinf(valley.max_concave_curvature_per_mm));
  EXPECT_NEAR(valley.max_concave_curvature_at_x_mm, 300.0, 1e-6);
  EXPECT_NE(valley.singularities[0].describe(0.01).find("no wheel edge radius fits: limit 0 mm"), std::string::npos);
  const GeometryAnalysis ridge = expression_generatrix("100 - abs(x - 300)", 0, 600)->analyse(0.01);
  EXPECT_FALSE(ridge.singularities.at(0).concave);
  EXPECT_EQ(ridge.max_concave_curvature_per_mm, 0.0);
  // A kink inside a ternary (two lines meeting), a slope jump of 0.75.
  const auto v = singularities("x < 200 ? 100 + 0.5*x : 200 - 0.25*(x - 200)", 0, 600);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].kind, Singularity::Kind::kink);
  EXPECT_NEAR(v[0].x_mm, 200.0, 1e-6);
  EXPECT_NEAR(v[0].size, 0.75, 1e-9);
  // Jumps: a step of 3 in a ternary, a step through a comparison, rint.
  const auto j = singularities("x < 300 ? 100 : 103", 0, 600);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0].kind, Singularity::Kind::jump);
  EXPECT_NEAR(j[0].x_mm, 300.0, 1e-6);
  EXPECT_NEAR(j[0].size, 3.0, 1e-9);
  EXPECT_EQ(singularities("100 + 0.5*(x > 123.25)", 0, 600).at(0).kind, Singularity::Kind::jump);
  EXPECT_EQ(singularities("100 + rint(x/200)", 0, 600).size(), 3u);  // at 100, 300, 500
  // Smooth junctions are not singular: equal values and slopes (a C1 fillet built with ?:).
  EXPECT_TRUE(singularities("x < 300 ? 100 : 100", 0, 600).empty());
  EXPECT_TRUE(singularities("x < 300 ? 100 + (x-300)^2/1000 : 100 + (x-300)^2/500", 0, 600).empty());
  EXPECT_TRUE(singularities("100 + max(x - 300, 0)^2/100", 0, 600).empty());
}

// The audit's near-step: 5 tanh((x - 300)/0.001) turns the tangent by about 1.5 rad within
// 0.005 mm at each corner: refused at the default resolution (0.01 mm), at both corners.
TEST(GeometryAnalysis, FeaturesNarrowerThanTheResolutionAreRefusedWithTheirPlace) {
  const auto found = singularities("100 + 5*tanh((x-300)/0.001)", 0, 600);
  ASSERT_EQ(found.size(), 2u);
  for (const Singularity& s : found) {
    EXPECT_EQ(s.kind, Singularity::Kind::narrow_feature);
    EXPECT_NEAR(s.x_mm, 300.0, 0.01);
    EXPECT_GT(s.size, 100.0);  // rad/mm
  }
  const std::string message = found[0].describe(0.01);
  EXPECT_NE(message.find("narrower than the resolution 0.01 mm at x = 299.99"), std::string::npos) << message;
  // A 20 nm step of the same width turns the tangent slowly enough to plan; at a finer
  // resolution the same shape is still accepted, a coarser one refuses a gentler feature.
  EXPECT_TRUE(singularities("100 + 1e-5*tanh((x-300)/0.001)", 0, 600).empty());
  EXPECT_TRUE(singularities("130 - 8*exp(-((x-150)/10)^2)", 0, 300, 0.01).empty());
  EXPECT_FALSE(singularities("130 - 8*exp(-((x-150)/10)^2)", 0, 300, 10.0).empty());
  // Domain: not finite, a vertical tangent.
  const auto log_domain = singularities("log(x - 10)", 0, 600);
  ASSERT_FALSE(log_domain.empty());
  EXPECT_EQ(log_domain[0].kind, Singularity::Kind::not_finite);
  EXPECT_LT(log_domain[0].x_mm, 10.0);
  const auto root = singularities("100 + sqrt(x)", 0, 100);
  ASSERT_FALSE(root.empty());
  EXPECT_EQ(root[0].kind, Singularity::Kind::vertical_tangent);
  EXPECT_EQ(root[0].x_mm, 0.0);
}

// True curvature: the largest concave curvature kappa = f''/(1 + f'^2)^1.5, attained value and
// certified bound, against closed forms.
TEST(GeometryAnalysis, LargestConcaveCurvatureIsTheTrueOne) {
  // 100 + x^2/1000: radius 500 mm at x = 0.
  GeometryAnalysis g = expression_generatrix("100 + x^2/1000", -50, 50)->analyse(0.01);
  EXPECT_NEAR(1 / g.max_concave_curvature_per_mm, 500.0, 1e-6);
  EXPECT_NEAR(g.max_concave_curvature_at_x_mm, 0.0, 1e-3);
  EXPECT_LE(g.max_concave_curvature_bound_per_mm, g.max_concave_curvature_per_mm * (1 + 1e-6));
  EXPECT_GE(g.max_concave_curvature_bound_per_mm, g.max_concave_curvature_per_mm);
  // The fillet of the audit: f'' = 16/100 at x = 150 with f' = 0: radius 6.25 mm exactly.
  g = expression_generatrix("130 - 8*exp(-((x-150)/10)^2)", 0, 300)->analyse(0.01);
  EXPECT_NEAR(1 / g.max_concave_curvature_per_mm, 6.25, 1e-6);
  // Problem 2: 722.66 mm at x = 321.65 (docs/planner.md).
  g = expression_generatrix("30*exp(-x/400)*sin((x + 25*_pi)/100) + 130", 0, 600)->analyse(0.01);
  EXPECT_NEAR(1 / g.max_concave_curvature_per_mm, 722.658, 1e-3);
  EXPECT_NEAR(g.max_concave_curvature_at_x_mm, 321.65, 0.01);
  EXPECT_GE(g.max_concave_curvature_bound_per_mm, g.max_concave_curvature_per_mm);
  // The bound: within 1e-7 relative + 1e-7 /mm of the attained value (where the branch and bound
  // stops refining).
  EXPECT_LE(g.max_concave_curvature_bound_per_mm, g.max_concave_curvature_per_mm * (1 + 1e-6) + 1e-7);
  // Convex parts: no concave curvature (problem 1).
  g = expression_generatrix("-7/18000*(600 - x)^2 + 0.45*(600 - x)", 0, 600)->analyse(0.01);
  EXPECT_EQ(g.max_concave_curvature_per_mm, 0.0);
}

// A spline's curvature peaks at its knots (f'' is linear between them): a table whose middle
// point is raised has its largest concave curvature at the knots beside it, which a sampler
// between knots misses.
TEST(GeometryAnalysis, SplineCurvatureIsTakenAtTheKnots) {
  std::vector<double> x, y;
  for (int i = 0; i <= 20; ++i) {
    x.push_back(10.0 * i);
    y.push_back(100.0 + (i == 10 ? 0.05 : 0.0));
  }
  const CubicSpline s = interpolating_spline(x, y);
  const GeometryAnalysis g = analyse_spline(s, 0.01);
  double at_knots = 0;  // kappa at the knots, from the spline's own second derivatives
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Jet j = s.evaluate(x[i]);
    at_knots = std::max(at_knots, j.d2 / std::pow(1 + j.d1 * j.d1, 1.5));
  }
  EXPECT_NEAR(g.max_concave_curvature_per_mm, at_knots, 1e-12);
  EXPECT_TRUE(g.max_concave_curvature_at_x_mm == 90.0 || g.max_concave_curvature_at_x_mm == 110.0);
  EXPECT_GE(g.max_concave_curvature_bound_per_mm, g.max_concave_curvature_per_mm);
}

std::vector<double> noisy(const std::vector<double>& x, double sigma, unsigned seed,
                          std::vector<double>* truth = nullptr) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double> y;
  for (double v : x) {
    const double f = 30 * std::exp(-v / 400) * std::sin((v + 25 * std::numbers::pi) / 100) + 130;
    if (truth) truth->push_back(f);
    y.push_back(f + noise(rng));
  }
  return y;
}

std::vector<double> grid(double a, double b, std::size_t n) {
  std::vector<double> x;
  for (std::size_t i = 0; i <= n; ++i) x.push_back(a + (b - a) * static_cast<double>(i) / static_cast<double>(n));
  return x;
}

TEST(SmoothingSpline, LimitsTraceAndEndCurvature) {
  const std::vector<double> x = grid(0, 600, 60);
  std::vector<double> truth;
  const std::vector<double> y = noisy(x, 0.002, 3, &truth);
  // lambda -> 0 interpolates (n parameters), lambda -> infinity leaves 2 (a line about the end
  // trend).
  const SmoothingSpline tight = smoothing_spline(x, y, 1e-10);
  EXPECT_LT(tight.residual_max_mm, 1e-9);
  EXPECT_NEAR(tight.effective_parameters, 61.0, 1e-3);
  EXPECT_NEAR(smoothing_spline(x, y, 1e16).effective_parameters, 2.0, 1e-3);
  // tr A from the band of the inverse (Hutchinson & de Hoog) equals the trace of the linear map
  // y -> g built column by column (the smoothing of e_j, read at point j), on uneven spacing.
  std::vector<double> xs;
  for (int i = 0; i < 14; ++i) xs.push_back(i + 0.3 * std::sin(1.7 * i));
  for (const double lambda : {0.01, 0.7, 50.0}) {
    double trace = 0.0;
    for (std::size_t j = 0; j < xs.size(); ++j) {
      std::vector<double> e(xs.size(), 0.0);
      e[j] = 1.0;
      trace += smoothing_spline(xs, e, lambda, false).spline.g[j];
    }
    EXPECT_NEAR(smoothing_spline(xs, std::vector<double>(xs.size(), 1.0), lambda, false).effective_parameters,
                trace, 1e-9) << lambda;
  }
  // Noise: GCV estimates sigma = 2 um within 25 % and the smoothed curve is nearer the truth
  // than the data.
  const std::vector<double> xd = grid(0, 600, 300);
  std::vector<double> true_d;
  const std::vector<double> yd = noisy(xd, 0.002, 11, &true_d);
  const SmoothingSpline cv = cross_validated_spline(xd, yd);
  EXPECT_NEAR(cv.noise_estimate_mm, 0.002, 0.0005);
  double err = 0;
  for (std::size_t i = 0; i < xd.size(); ++i) err = std::max(err, std::abs(cv.spline.evaluate(xd[i]).v - true_d[i]));
  EXPECT_LT(err, 0.003);
  // Tolerance mode: the RMS residual is the stated tolerance; the ends keep their curvature (the
  // natural condition would bend them straight: residuals of several sigma at x = 0).
  const SmoothingSpline tol = tolerance_spline(xd, yd, 0.002);
  EXPECT_NEAR(tol.residual_rms_mm, 0.002, 1e-9);
  EXPECT_LT(tol.residual_max_mm, 5 * 0.002);
  const Jet end = tol.spline.evaluate(0.0);
  const double f2_at_0 = 30 * (std::sin(0.25 * std::numbers::pi) / 160000 - 2 * std::cos(0.25 * std::numbers::pi) / 40000 -
                               std::sin(0.25 * std::numbers::pi) / 10000);
  EXPECT_NEAR(end.d2, f2_at_0, 0.25 * std::abs(f2_at_0));
}

}  // namespace
}  // namespace chatterlab::planner
