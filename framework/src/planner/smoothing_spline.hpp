#pragma once
// Natural cubic splines through a point table y(x) (MODELS.md P3 point tables; docs/planner.md,
// "Measured parts"): interpolating, or smoothing (Reinsch): the natural cubic spline g that
// minimises
//     sum_i (y_i - g(x_i))^2 + lambda * integral g''(x)^2 dx
// with lambda chosen so that the RMS residual equals a stated tolerance, or by generalised
// cross-validation (GCV: minimise n RSS / (n - tr A)^2, A the influence matrix). The penalty
// makes g'' = 0 at the ends, which would bend a curved part straight there: the smoothing acts on
// y - t, t a cubic carrying the ends' curvature (local quadratic fits to the end points). Solved in O(n)
// on the banded system (R + lambda Q^T Q) gamma = Q^T y of Green & Silverman (1994, ch. 2); the
// trace of A from the band of the inverse (Hutchinson & de Hoog 1985).
#include <cstddef>
#include <string>
#include <vector>

#include "planner/expression.hpp"

namespace chatterlab::planner {

// A natural cubic spline by its knot values g_i and second derivatives m_i (m_0 = m_n = 0).
struct CubicSpline {
  std::vector<double> x, g, m;
  Jet evaluate(double at) const;  // g, g', g'' (clamped to the end segments outside [x_0, x_n])
};

// Throws std::invalid_argument (fewer than 3 points, x not strictly increasing, non-finite).
void check_point_table(const std::vector<double>& x, const std::vector<double>& y);

CubicSpline interpolating_spline(const std::vector<double>& x, const std::vector<double>& y);

struct SmoothingSpline {
  CubicSpline spline;
  double lambda = 0.0;                 // the penalty weight chosen, mm^3
  double residual_rms_mm = 0.0;        // sqrt(mean (y_i - g(x_i))^2)
  double residual_max_mm = 0.0;        // largest |y_i - g(x_i)|
  double effective_parameters = 0.0;   // tr A: n for interpolation, 2 for a straight line
  double gcv_score = 0.0;              // n RSS / (n - tr A)^2 at lambda (mm^2)
  double noise_estimate_mm = 0.0;      // sqrt(RSS / (n - tr A)): the residual's noise level
  std::string method;                  // "cross_validated" or "tolerance"
};

// lambda by GCV over 1e-8..1e14 x (mean spacing)^3 (a grid, then golden section).
SmoothingSpline cross_validated_spline(const std::vector<double>& x, const std::vector<double>& y);
// lambda such that the RMS residual equals tolerance_mm (bisection in log lambda; a straight line
// when even that fits within the tolerance).
SmoothingSpline tolerance_spline(const std::vector<double>& x, const std::vector<double>& y,
                                 double tolerance_mm);
// The smoothing spline for a given lambda (exposed for tests: lambda -> 0 interpolates,
// lambda -> infinity gives the least-squares line about the end trend). keep_end_curvature
// false: plain Reinsch (natural ends; effective_parameters is then the trace of the linear map
// y -> g).
SmoothingSpline smoothing_spline(const std::vector<double>& x, const std::vector<double>& y,
                                 double lambda, bool keep_end_curvature = true);

}  // namespace chatterlab::planner
