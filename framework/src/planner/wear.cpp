#include "planner/wear.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace chatterlab::planner {

std::function<double(double)> sweep_function(const WearSweep& sweep, double x0_mm) {
  const double amplitude = sweep.amplitude_mm, period = sweep.period_mm;
  if (sweep.law == "triangle")
    return [=](double x) {
      const double phase = std::fmod((x - x0_mm) / period + 0.25, 1.0);  // starts at 0, rising
      return amplitude * (phase < 0.5 ? 4 * phase - 1 : 3 - 4 * phase);
    };
  if (sweep.law == "sine")
    return [=](double x) { return amplitude * std::sin(2 * std::numbers::pi * (x - x0_mm) / period); };
  if (sweep.law == "stepped") {
    const int steps = std::max(sweep.steps, 2);
    return [=](double x) {
      const double phase = std::fmod((x - x0_mm) / period, 1.0);
      const int level = std::min(steps - 1, static_cast<int>(phase * steps));
      return amplitude * (-1.0 + 2.0 * level / (steps - 1));
    };
  }
  return nullptr;
}

WearDistribution wear_distribution(const std::vector<double>& zeta, const std::vector<double>& durations,
                                   double half_width, std::size_t bins) {
  // Dwell spread along the linear zeta path of each segment (16 pieces per segment).
  constexpr int pieces = 16;
  double lo = 0.0, hi = 0.0;
  for (double z : zeta) {
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  WearDistribution out;
  out.used_width_mm = hi - lo;
  // Bins over the swept range (a narrow sweep on a wide face is judged on its own width;
  // used_width_mm says how much of the face it uses); no sweep: one circle, the whole face.
  if (!(hi - lo > 1e-9)) {
    lo = -half_width;
    hi = half_width;
  }
  out.dwell_s.assign(bins, 0.0);
  const double width = (hi - lo) / static_cast<double>(bins);
  for (std::size_t i = 0; i < bins; ++i)
    out.bin_centre_mm.push_back(lo + (static_cast<double>(i) + 0.5) * width);
  for (std::size_t k = 0; k < durations.size(); ++k)
    for (int p = 0; p < pieces; ++p) {
      const double z = zeta[k] + (p + 0.5) / pieces * (zeta[k + 1] - zeta[k]);
      const double u = std::clamp((z - lo) / width, 0.0, static_cast<double>(bins) - 1e-9);
      out.dwell_s[static_cast<std::size_t>(u)] += durations[k] / pieces;
    }
  if (out.used_width_mm > 1e-9) {
    double sum = 0.0, sum_sq = 0.0;
    for (double d : out.dwell_s) {
      sum += d;
      sum_sq += d * d;
    }
    const double mean = sum / static_cast<double>(bins);
    const double var = std::max(0.0, sum_sq / static_cast<double>(bins) - mean * mean);
    out.uniformity = mean > 0 ? 1.0 - std::sqrt(var) / mean : 0.0;
  }  // else 0: all dwell on one circle of the wheel
  return out;
}

}  // namespace chatterlab::planner
