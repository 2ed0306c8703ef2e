#pragma once
// Wear spreading (MODELS.md P6): the contact point sweeps across the cylindrical wheel's face,
// zeta(x) in [-A, A], as a function of the axial contact position x (at the planned constant
// axial speed this is a sweep in time with period period_mm / v). Laws: triangle (constant-speed
// back-and-forth, seed 003: uniform dwell), sine (seed 000: arcsine-distributed dwell, piling up
// at the face's edges), stepped (seed 004: N discrete contact positions held in turn).
#include <functional>
#include <string>
#include <vector>

namespace chatterlab::planner {

struct WearSweep {
  std::string law = "none";  // none, triangle, sine, stepped
  double amplitude_mm = 0.0;  // A
  double period_mm = 0.0;     // axial travel per sweep cycle
  int steps = 5;              // stepped: number of contact positions
};

// zeta(x) for the sweep starting at x0 (nullptr for "none").
std::function<double(double)> sweep_function(const WearSweep& sweep, double x0_mm);

// Dwell of the contact on the wheel: time the contact spends in each of `bins` equal bins of the
// swept range of zeta ([-half_width, half_width] without a sweep), from knot positions zeta_k and
// segment durations (zeta linear in time inside a segment).
struct WearDistribution {
  std::vector<double> bin_centre_mm, dwell_s;
  double uniformity = 0.0;  // 1 - (coefficient of variation of dwell over the bins); 0: no sweep
  double used_width_mm = 0.0;  // range of zeta actually swept
};
WearDistribution wear_distribution(const std::vector<double>& zeta_at_knots_mm,
                                   const std::vector<double>& durations_s, double half_width_mm,
                                   std::size_t bins = 40);

}  // namespace chatterlab::planner
