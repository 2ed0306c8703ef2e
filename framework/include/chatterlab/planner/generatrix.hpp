#pragma once
// The generatrix y = f(x) of a solid of revolution (MODELS.md P3): x axial position from the
// fixture reference plane, y radius, both in mm, on [x_min_mm, x_max_mm]. From a muparser
// expression in x (`_pi` is pi) or from a point table (natural cubic spline through the points).
#include <memory>
#include <string>
#include <vector>

namespace chatterlab::planner {

struct GeneratrixValue {
  double f = 0.0;   // radius, mm
  double d1 = 0.0;  // f'
  double d2 = 0.0;  // f'', 1/mm
};

class Generatrix {
 public:
  virtual ~Generatrix() = default;
  virtual double x_min_mm() const = 0;
  virtual double x_max_mm() const = 0;
  // f, f', f'' at x. Not thread-safe (an expression parser evaluates in place): one object per
  // thread.
  virtual GeneratrixValue evaluate(double x_mm) const = 0;
  virtual std::string describe() const = 0;
};

// f from a muparser expression in `x`. Derivatives by 6th-order central differences over a
// 7-point stencil with step h = 1e-4 (x_max - x_min) (errors ~1e-11 relative for smooth f; the
// tests compare with analytic derivatives), so f must be defined 3h beyond both ends.
// Throws std::invalid_argument with the parser's message for a bad expression.
std::unique_ptr<Generatrix> expression_generatrix(const std::string& expression, double x_min_mm,
                                                  double x_max_mm);

// Natural cubic spline through (x_i, y_i), x strictly increasing, at least 3 points
// (std::invalid_argument otherwise).
std::unique_ptr<Generatrix> spline_generatrix(std::vector<double> x_mm, std::vector<double> y_mm);

// Checks that f is finite, continuous and has a continuous slope on its range (sampled on 4096
// intervals, suspicious intervals bisected: a true jump keeps its size when the interval halves).
// Throws std::invalid_argument saying what is wrong and where ("not finite at x = 12.5",
// "jumps by 3.2 mm near x = 300", "slope jumps by 0.5 near x = 300").
void check_smooth(const Generatrix& generatrix);

}  // namespace chatterlab::planner
