#pragma once
// Wheel limits (MODELS.md P5): the largest edge-arc radius that touches the part only at the
// contact point, and the interference of the wheel section with the part along a plan.
#include <vector>

#include "chatterlab/planner/generatrix.hpp"
#include "planner/scheduler.hpp"

namespace chatterlab::planner {

struct WheelSection {
  bool profiled = false;      // false: cylindrical face (a straight line of width thickness_mm)
  double thickness_mm = 0.0;  // face width a (cylindrical)
  double edge_radius_mm = 0.0;  // arc radius r (profiled)
  double edge_angle_deg = 180.0;  // opening angle alpha of the arc (profiled)
};

struct EdgeRadiusLimit {
  double radius_mm = 0.0;  // +inf when no part of the profile limits it
  double x_mm = 0.0;       // contact position that sets the limit
  bool local = false;      // set by the local curvature (concave part) rather than a distant point
  // The local term's certified bound: no concave radius of curvature anywhere is below it
  // (GeometryAnalysis::max_concave_curvature_bound_per_mm); +inf for a convex part.
  double curvature_bound_radius_mm = 0.0;
};

// For every contact point P (outward normal n, towards the wheel) a circle of radius r tangent at
// P stays outside the part iff r <= |Q-P|^2 / (2 (Q-P).n) for every profile point Q with
// (Q-P).n > 0 (seed 000's normal-line condition, 5.21-5.23); near P this tends to the radius of
// curvature (1+f'^2)^1.5 / f'' of a concave part (f'' > 0). The local term is the true smallest
// concave radius of curvature from the geometry analysis (every point of the range, spline knots
// included); the distant term is minimised over P and Q on `samples` points.
EdgeRadiusLimit largest_edge_radius(const Generatrix& generatrix, const GeometryAnalysis& geometry,
                                    std::size_t samples = 2001);
// Analyses the generatrix at the default resolution first.
EdgeRadiusLimit largest_edge_radius(const Generatrix& generatrix, std::size_t samples = 2001);

// Largest edge radius the wheel itself can carry: an arc of opening alpha is 2 r sin(alpha/2)
// wide and must fit the face width a (a cylindrical wheel: alpha as given, default 180 deg).
double wheel_geometry_edge_radius_mm(const WheelSection& wheel);

struct Interference {
  double depth_mm = 0.0;  // deepest penetration of the wheel section beyond the contact's own cut
  double x_mm = 0.0;      // where on the part (x of the deepest section point)
  double contact_x_mm = 0.0;  // where the contact was then
  double time_s = 0.0;    // plan time of that state (along a plan)
  std::size_t contacts_with_interference = 0;  // states (or ideal contacts) beyond the tolerance
  std::size_t segments_with_interference = 0;  // along a plan
  std::size_t states_checked = 0;
  double tolerance_mm = 0.0;
};

// Ideal placements (validation): the wheel section tangent at each contact x in `contacts_mm`,
// the contact at the section's nominal point (middle of the face, bottom of the edge arc).
// Penetrations up to tolerance_mm are ignored.
Interference check_interference(const Generatrix& generatrix, const WheelSection& wheel,
                                const std::vector<double>& contacts_mm, double tolerance_mm = 1e-4);

// Along the quantised plan: every machine state (each pulse, spread evenly in its segment) goes
// through the forward kinematics; the tool frame in the part (nominal point O, along-rails U,
// across W) follows from forward() at tool points (0,0), (1,0), (0,1); the section (face
// [-a/2, a/2] x {0}, or edge arc (r sin phi, r (1 - cos phi)), |phi| <= alpha/2) is probed for
// its deepest point below the generatrix (samples dense enough that a point between two of them
// lies at most half the tolerance deeper, 64 to 4096, then golden-section refinement where a
// sample comes that close; the
// generatrix tabulated as a cubic Hermite on 20000 intervals). Interference at a state: the
// deepest penetration minus the contact's own cut-in (the profile error, reported separately),
// beyond tolerance_mm (default 1 um: a nut step tilts a 20 mm half face by 0.2 um).
Interference check_interference_along_plan(const Schedule& schedule, const Generatrix& generatrix,
                                           const Kinematics& kinematics, const WheelSection& wheel,
                                           double tolerance_mm = 1e-3);

}  // namespace chatterlab::planner
