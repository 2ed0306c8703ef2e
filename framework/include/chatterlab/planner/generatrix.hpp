#pragma once
// The generatrix y = f(x) of a solid of revolution (MODELS.md P3): x axial position from the
// fixture reference plane, y radius, both in mm, on [x_min_mm, x_max_mm]. From a muparser
// expression in x (`_pi` is pi) or from a point table (a natural cubic spline through the points,
// or a smoothing spline through measured points: docs/planner.md, "Measured parts").
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace chatterlab::planner {

struct GeneratrixValue {
  double f = 0.0;   // radius, mm
  double d1 = 0.0;  // f'
  double d2 = 0.0;  // f'', 1/mm
};

// The default geometry resolution: features narrower than this are refused (docs/planner.md,
// "Geometry analysis").
inline constexpr double default_geometry_resolution_mm = 0.01;

// A place where the generatrix cannot be planned: a jump of f or of its slope, a value that is
// not finite, an infinite slope, or a feature narrower than the resolution (the tangent angle theta = atan f' turns
// by more than 1 rad within one resolution step of x: |f''| / (1 + f'^2) > 1 / resolution).
struct Singularity {
  enum class Kind { not_finite, vertical_tangent, jump, kink, narrow_feature };
  Kind kind = Kind::not_finite;
  double x_mm = 0.0;
  double size = 0.0;  // jump: |delta f| (mm); kink: |delta f'|; narrow feature: |theta'| (rad/mm)
  bool concave = false;  // kink: the slope increases (a valley corner: no edge radius fits there)
  std::string describe(double resolution_mm) const;
};

// What the geometry analysis proves about f on its whole range (not on samples).
struct GeometryAnalysis {
  double resolution_mm = 0.0;
  std::vector<Singularity> singularities;  // sorted by x; empty: plannable at this resolution
  // Largest concave curvature kappa = f'' / (1 + f'^2)^1.5 > 0 (a valley: the edge radius may not
  // exceed 1/kappa): the value attained at x, and a bound no point of the range exceeds. A
  // concave kink is infinite curvature: edge-radius limit 0 there.
  double max_concave_curvature_per_mm = 0.0;  // 0: convex (or straight) everywhere
  double max_concave_curvature_at_x_mm = 0.0;
  double max_concave_curvature_bound_per_mm = 0.0;
  // Largest tangent turn rate |theta'| = |f''| / (1 + f'^2) found, and where.
  double max_turn_rate_rad_per_mm = 0.0;
  double max_turn_rate_at_x_mm = 0.0;
  std::size_t evaluations = 0;  // interval enclosures or point evaluations used
  std::string method;
};

class Generatrix {
 public:
  virtual ~Generatrix() = default;
  virtual double x_min_mm() const = 0;
  virtual double x_max_mm() const = 0;
  // f, f', f'' at x (exact derivatives: differentiated expression or spline). Thread-safe.
  virtual GeneratrixValue evaluate(double x_mm) const = 0;
  virtual std::string describe() const = 0;
  // Proves smoothness and bounds the curvature over the whole range (docs/planner.md, "Geometry
  // analysis"): an expression by interval enclosures of f, f', f'' with its switches (abs, ?:,
  // comparisons, ...) located and classified; a spline piece by piece, knots included.
  virtual GeometryAnalysis analyse(double resolution_mm) const = 0;
  // Points where the curve's definition changes (spline knots); empty for an expression.
  virtual std::vector<double> knots_mm() const { return {}; }
};

// f from a muparser expression in `x`, differentiated exactly. The expression is checked against
// muparser itself at 65 points (the grammar is muparser's). Throws std::invalid_argument with the
// parser's message for a bad expression.
std::unique_ptr<Generatrix> expression_generatrix(const std::string& expression, double x_min_mm,
                                                  double x_max_mm);

// Natural cubic spline through (x_i, y_i), x strictly increasing, at least 3 points
// (std::invalid_argument otherwise).
std::unique_ptr<Generatrix> spline_generatrix(std::vector<double> x_mm, std::vector<double> y_mm);

// Analyses the generatrix at `resolution_mm` and throws std::invalid_argument naming what is
// wrong and where ("f jumps by 3 at x = 300", "the slope f' jumps by 2 at x = 300 (a kink)",
// "f is not finite at x = 12.5", "a feature narrower than the resolution ... at x = 300").
GeometryAnalysis check_smooth(const Generatrix& generatrix,
                              double resolution_mm = default_geometry_resolution_mm);

}  // namespace chatterlab::planner
