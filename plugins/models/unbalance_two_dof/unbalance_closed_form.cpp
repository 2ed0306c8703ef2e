#include "models/unbalance_two_dof/unbalance_closed_form.hpp"

#include <cmath>
#include <numbers>

namespace chatterlab::unbalance {

double coupling_stiffness_n_per_m(const UnbalanceTwoDofParameters& p) {
  return p.contact_stiffness_n_per_m * p.grinding_stiffness_n_per_m /
         (p.contact_stiffness_n_per_m + p.grinding_stiffness_n_per_m);
}

NaturalFrequencies natural_frequencies(const UnbalanceTwoDofParameters& p) {
  const double k = coupling_stiffness_n_per_m(p);
  const double a = (k + p.wheel_support_stiffness_n_per_m) / p.wheel_mass_kg;
  const double b = (k + p.work_support_stiffness_n_per_m) / p.work_mass_kg;
  const double root = std::sqrt((b - a) * (b - a) + 4.0 * k * k / (p.wheel_mass_kg * p.work_mass_kg));
  // Lower root without cancellation: product of the two squared frequencies is a b - k^2/(m1 m2).
  const double upper2 = 0.5 * (a + b + root);
  const double lower2 = (a * b - k * k / (p.wheel_mass_kg * p.work_mass_kg)) / upper2;
  return {std::sqrt(lower2), std::sqrt(upper2)};
}

double undamped_relative_amplitude_m(const UnbalanceTwoDofParameters& p, double w) {
  const NaturalFrequencies n = natural_frequencies(p);
  const double w2 = w * w;
  const double force = p.unbalance_kg_m * w2;
  return force * (p.work_support_stiffness_n_per_m - p.work_mass_kg * w2) /
         (p.wheel_mass_kg * p.work_mass_kg * (n.lower_rad_s * n.lower_rad_s - w2) *
          (n.upper_rad_s * n.upper_rad_s - w2) *
          (1.0 + p.grinding_stiffness_n_per_m / p.contact_stiffness_n_per_m));
}

SteadyState steady_state(const UnbalanceTwoDofParameters& p, double w) {
  using C = std::complex<double>;
  const double k = coupling_stiffness_n_per_m(p);
  const C a11(k + p.wheel_support_stiffness_n_per_m - p.wheel_mass_kg * w * w, p.wheel_damping_n_s_per_m * w);
  const C a22(k + p.work_support_stiffness_n_per_m - p.work_mass_kg * w * w, p.work_damping_n_s_per_m * w);
  const C det = a11 * a22 - k * k;
  const double force = p.unbalance_kg_m * w * w;
  const C wheel = force * a22 / det, work = -force * k / det;  // Cramer's rule
  return {wheel, work, (wheel + work) / (1.0 + p.grinding_stiffness_n_per_m / p.contact_stiffness_n_per_m)};
}

double forcing_frequency_rad_s(const UnbalanceTwoDofParameters& p) {
  return 2.0 * std::numbers::pi * p.wheel_speed_rpm / 60.0;
}

SteadyState unbalance_response(const UnbalanceTwoDofParameters& p) {
  return steady_state(p, forcing_frequency_rad_s(p));
}

double lobes_per_revolution(const UnbalanceTwoDofParameters& p) {
  return p.wheel_speed_rpm / p.work_speed_rpm;
}

}  // namespace chatterlab::unbalance
