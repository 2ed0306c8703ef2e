#pragma once
// Geometry analysis of a generatrix (docs/planner.md, "Geometry analysis"): what the planner may
// assume about f on its whole range, proved rather than sampled.
#include <memory>
#include <string>

#include "chatterlab/planner/generatrix.hpp"
#include "planner/expression.hpp"
#include "planner/smoothing_spline.hpp"

namespace chatterlab::planner {

// Branch and bound over [a, b] with interval enclosures of f, f', f'' (Expression::enclose):
// - an interval whose enclosure may be undefined, or may hold a switch (abs, sign, rint, min,
//   max, ?:, a comparison), is bisected down to 1e-10 (b - a); there the switch is classified
//   from exact one-sided jets at its ends: a jump of f, a jump of f' (kink), or a smooth junction;
//   a value that is not finite there is reported as such;
// - on a smooth interval the enclosure of the turn rate |f''|/(1 + f'^2) is compared with
//   1/resolution (bisected to resolution/64 where it is not clearly below; a point above it is a
//   feature narrower than the resolution), and the enclosure of the concave curvature with the
//   largest value attained so far (bisected until no interval can exceed it by 1e-7 relative).
GeometryAnalysis analyse_expression(const Expression& expression, double a, double b,
                                    double resolution_mm);

// A C2 cubic spline has no jumps or kinks; its curvature and turn rate are maximised piece by
// piece (32 samples per piece, knots included, then golden-section refinement of the best).
GeometryAnalysis analyse_spline(const CubicSpline& spline, double resolution_mm);

// The spline as a generatrix (`description` is what describe() returns).
std::unique_ptr<Generatrix> cubic_spline_generatrix(CubicSpline spline, std::string description);

}  // namespace chatterlab::planner
