#pragma once
// Wheel limits (MODELS.md P5): the largest edge-arc radius that touches the part only at the
// contact point, and the interference of the wheel section with the part along a plan.
#include <vector>

#include "chatterlab/planner/generatrix.hpp"

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
};

// For every contact point P (outward normal n, towards the wheel) a circle of radius r tangent at
// P stays outside the part iff r <= |Q-P|^2 / (2 (Q-P).n) for every profile point Q with
// (Q-P).n > 0 (seed 000's normal-line condition, 5.21-5.23); near P this tends to the radius of
// curvature (1+f'^2)^1.5 / f'' of a concave part (f'' > 0). Minimised over P on `samples` points.
EdgeRadiusLimit largest_edge_radius(const Generatrix& generatrix, std::size_t samples = 2001);

struct Interference {
  double depth_mm = 0.0;  // deepest penetration of the wheel section into the part (0: none)
  double x_mm = 0.0;      // contact position where it happens
  std::size_t contacts_with_interference = 0;
};

// Checks the wheel section placed as P4 places it (tangent at the contact, contact at offset
// zeta along the face) at each contact x in `contacts_mm` (zeta from `contact_on_tool_mm`, same
// length or empty). Penetrations below tolerance_mm are ignored.
Interference check_interference(const Generatrix& generatrix, const WheelSection& wheel,
                                const std::vector<double>& contacts_mm,
                                const std::vector<double>& contact_on_tool_mm,
                                double tolerance_mm = 1e-4);

}  // namespace chatterlab::planner
