#pragma once
// Replay of a quantised plan (MODELS.md P7, seed 004): every machine state the plan passes
// through (pulses spread evenly in each segment: pulse j of n at fraction (j - 1/2)/n) goes
// through the forward kinematics; the tool's deviation from the generatrix, measured along the
// profile normal, is the produced-profile error. The same instants replayed with the exact
// (unrounded) targets interpolated linearly in each segment give the linearisation part; the
// difference per state is the quantisation part.
#include <vector>

#include "planner/scheduler.hpp"

namespace chatterlab::planner {

struct ErrorStats {
  double max_abs_mm = 0.0, mean_mm = 0.0, mean_abs_mm = 0.0, rms_mm = 0.0;
};

struct ProfileErrors {
  ErrorStats total, linearisation, quantisation;
  double area_percent = 0.0;  // seed 004: area between produced and nominal / area under f, %
  std::size_t states = 0;
  double x_at_max_mm = 0.0;
  // Per segment (plots along x): segment middle, smallest and largest total deviation.
  std::vector<double> segment_x_mm, segment_min_mm, segment_max_mm;
};

ProfileErrors replay_errors(const Schedule& schedule, const Generatrix& generatrix,
                            const Kinematics& kinematics);

}  // namespace chatterlab::planner
