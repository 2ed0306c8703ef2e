#pragma once
// Cylindricity by error separation (MODELS.md E6; book 6.6): each axial section j is separated
// on its own (any method of error_separation.hpp), then
//   dr(j)   = R(0)/G(0) = (sum c_q mean Y_q)/(sum c_q): the section's mean radius difference
//             (this is why the probe signals must not be zero-meaned);
//   u(j), v(j) = mean of dx, dy over the revolution: the non-rotating offset between part and
//             probe carriage, i.e. the slide straightness;
//   (cx(j), cy(j)): the section's least-squares centre in the part's frame, from the rotating
//             once-per-revolution part of (dx, dy): with dx = u + A cos th + B sin th and
//             dy = v + C cos th + D sin th, cx = (A - D)/2, cy = (B + C)/2 (an eccentric section
//             e cos(th - psi) shows as dx = e cos(th - psi), dy = -e sin(th - psi)); the
//             counter-rotating rest is synchronous spindle error;
// and the 3-D form F(th, z_j) = dr(j) + r_j(th) + cx(j) cos th + cy(j) sin th. The cylindricity
// is the peak-to-valley of F about its least-squares cylinder
// F ~ R0 + (a0 + a1 z) cos th + (b0 + b1 z) sin th (axis a straight line, radius constant).
#include <functional>
#include <span>
#include <vector>

#include "study_kinds/error_separation/error_separation.hpp"

namespace chatterlab::error_separation {

struct CylinderSection {
  double z = 0.0;
  Separation separation;
  double mean_radius_difference = 0.0;  // dr(j)
  double straightness_u = 0.0, straightness_v = 0.0;
  double centre_x = 0.0, centre_y = 0.0;
};

struct Cylinder {
  std::vector<CylinderSection> sections;
  std::vector<std::vector<double>> form;      // F(th_i, z_j), [section][sample]
  std::vector<std::vector<double>> residual;  // F minus its least-squares cylinder
  double ls_radius = 0.0;                     // R0 of the least-squares cylinder
  double axis_x0 = 0.0, axis_x_slope = 0.0, axis_y0 = 0.0, axis_y_slope = 0.0;
  double cylindricity = 0.0;  // peak-to-valley of `residual`
};

// probes_per_section[j][q]: probe q's N samples of section j (one revolution, averaged already).
// `separate` runs the chosen method on one section. Throws std::invalid_argument when a section's
// mean radius cannot be separated (G(0) = 0) or fewer than two sections are given.
Cylinder reconstruct_cylinder(
    std::span<const std::vector<std::vector<double>>> probes_per_section, std::span<const double> z,
    const std::function<Separation(std::span<const std::vector<double>>)>& separate);

}  // namespace chatterlab::error_separation
