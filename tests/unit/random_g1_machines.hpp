#pragma once
// Random MODELS.md G1 machines for the cross-checks of the G1 routes (g1_fast_path_test,
// rightmost_root_crosscheck_test): a seeded generator, its uniform and log-uniform draws, and the
// speeds and stiffnesses of a machine drawn in one fixed order (the modes are the caller's).
#include <cmath>
#include <cstdint>
#include <random>

#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab::testing {

class RandomG1Machines {
 public:
  explicit RandomG1Machines(std::uint32_t seed) : random_(seed) {}

  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(random_); }
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }

  // Wheel and work speeds uniform in their ranges [rpm]; kc log-uniform in [3e7, 3e8], kg in
  // [5e8, max_wheel_wear_stiffness], kw in [5e7, 5e8] N/m; no modes, both chains on.
  PlungeRegenerativeParameters machine(double wheel_lo_rpm, double wheel_hi_rpm, double work_lo_rpm,
                                       double work_hi_rpm, double max_wheel_wear_stiffness_n_per_m) {
    PlungeRegenerativeParameters p;
    p.wheel_speed_rpm = uniform(wheel_lo_rpm, wheel_hi_rpm);
    p.work_speed_rpm = uniform(work_lo_rpm, work_hi_rpm);
    p.contact_stiffness_n_per_m = log_uniform(3e7, 3e8);
    p.wheel_wear_stiffness_n_per_m = log_uniform(5e8, max_wheel_wear_stiffness_n_per_m);
    p.work_removal_stiffness_n_per_m = log_uniform(5e7, 5e8);
    return p;
  }
  // A mode with its frequency uniform in [lo_hz, hi_hz], damping ratio in [0.02, 0.08] and
  // stiffness log-uniform in [3e7, 3e8] N/m.
  StructuralMode mode(double lo_hz, double hi_hz) {
    const double f = uniform(lo_hz, hi_hz), zeta = uniform(0.02, 0.08);
    return {f, zeta, log_uniform(3e7, 3e8)};
  }

 private:
  std::mt19937 random_;
};

}  // namespace chatterlab::testing
