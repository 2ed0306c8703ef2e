#pragma once
// Parametric cubic spline through planar points, parameterised by cumulative chord length
// (MODELS.md K1, seed 002): x(l), y(l) cubic on each chord, C2 at the points; ends natural
// (zero second derivative), clamped (given end tangents) or periodic (closed curve, C2 across
// the closing point T_n = T_0). Used for cam lift tables and point-table profiles.
#include <array>
#include <vector>

namespace chatterlab::planner {

enum class SplineEnds { natural, clamped, periodic };

class ParametricSpline {
 public:
  // points: T_0..T_n (periodic: T_n must equal T_0 or is appended). clamped: start/end tangent
  // directions (any length; scaled to unit length per unit chord). Throws std::invalid_argument
  // for fewer than 3 distinct points, repeated consecutive points or a non-finite coordinate.
  ParametricSpline(std::vector<std::array<double, 2>> points, SplineEnds ends,
                   std::array<double, 2> start_tangent = {1, 0},
                   std::array<double, 2> end_tangent = {1, 0});

  double length() const { return l_.back(); }  // total chord length
  const std::vector<double>& knots() const { return l_; }
  const std::vector<std::array<double, 2>>& points() const { return p_; }
  // Position, first and second derivative with respect to l at l (periodic: l taken modulo the
  // length; otherwise clamped to [0, length]).
  void evaluate(double l, std::array<double, 2>& position, std::array<double, 2>& d1,
                std::array<double, 2>& d2) const;
  std::array<double, 2> position(double l) const;

  // Periodic star-shaped curves around the origin (cams): the parameter l where the polar angle
  // of the curve equals angle_rad (bisection on the monotone polar angle), and the polar radius
  // there.
  double parameter_at_polar_angle(double angle_rad) const;
  double polar_radius(double angle_rad) const;

 private:
  std::vector<std::array<double, 2>> p_;
  std::vector<double> l_;
  std::array<std::vector<double>, 2> m_;  // second derivatives at the knots, per coordinate
  bool periodic_;
};

// A cam lift table: polar radius at cam angles (deg).
struct LiftTable {
  std::vector<double> angle_deg, radius_mm;
};

struct CamFit {
  std::vector<double> chosen_angles_deg;  // the spline's points (after insertion), sorted
  double max_radius_error_mm = 0.0, mean_abs_radius_error_mm = 0.0;
  double max_x_error_mm = 0.0, max_y_error_mm = 0.0;
  double worst_angle_deg = 0.0;
  std::size_t inserted = 0;
};

// Closed spline through the table rows at `chosen_angles_deg` (their radii from the table), errors
// against every table row (radius, and x, y at the row's angle). With target_error_mm > 0, the
// worst row is added as a spline point until every row is within the target (K3 adaptive
// insertion); the final spline is returned through `spline`.
CamFit fit_cam(const LiftTable& table, std::vector<double> chosen_angles_deg, double target_error_mm,
               ParametricSpline* spline = nullptr);

}  // namespace chatterlab::planner
