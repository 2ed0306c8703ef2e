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
  WearDistribution out;
  out.dwell_s.assign(bins, 0.0);
  const double width = 2 * half_width / static_cast<double>(bins);
  for (std::size_t i = 0; i < bins; ++i)
    out.bin_centre_mm.push_back(-half_width + (static_cast<double>(i) + 0.5) * width);
  auto bin_of = [&](double z) {
    const double u = std::clamp((z + half_width) / width, 0.0, static_cast<double>(bins) - 1e-9);
    return static_cast<std::size_t>(u);
  };
  double lo = 0.0, hi = 0.0;
  for (std::size_t k = 0; k < durations.size(); ++k) {
    // Split the segment into small pieces: dwell spread along the linear zeta path.
    const int pieces = 16;
    for (int p = 0; p < pieces; ++p) {
      const double u = (p + 0.5) / pieces;
      const double z = zeta[k] + u * (zeta[k + 1] - zeta[k]);
      out.dwell_s[bin_of(z)] += durations[k] / pieces;
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
  }
  out.used_width_mm = hi - lo;
  // Uniformity over the bins the sweep covers (a sweep narrower than the face is judged on its
  // own width; used_width_mm says how much of the face it uses).
  double sum = 0.0, sum_sq = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < bins; ++i) {
    if (out.bin_centre_mm[i] + 0.5 * width < lo || out.bin_centre_mm[i] - 0.5 * width > hi) continue;
    sum += out.dwell_s[i];
    sum_sq += out.dwell_s[i] * out.dwell_s[i];
    ++used;
  }
  if (used > 1 && sum > 0) {
    const double mean = sum / static_cast<double>(used);
    const double var = std::max(0.0, sum_sq / static_cast<double>(used) - mean * mean);
    out.uniformity = 1.0 - std::sqrt(var) / mean;
  } else {
    out.uniformity = 0.0;  // all dwell on one circle of the wheel
  }
  return out;
}

}  // namespace chatterlab::planner
