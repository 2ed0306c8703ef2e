#include "shared/plunge_dynamics/wheel_growth_rate.hpp"

#include <cmath>
#include <numbers>

namespace chatterlab::wheel_growth {

double growth_rate_per_rev(double p, double q, std::complex<double> gm) {
  const std::complex<double> w = p * gm + q;  // eq 2-67: W = p (x + j y) + q
  // |1 + 1/W|^2 = 1 + (1 + 2 Re W)/|W|^2; log1p keeps small growth rates accurate.
  return -std::log1p((1.0 + 2.0 * w.real()) / std::norm(w)) / (4.0 * std::numbers::pi);
}

double growth_rate_per_rev_from_compliance(double kg, double kc, std::complex<double> h) {
  return growth_rate_per_rev(1.0, kg / kc, kg * h);
}

double lattice_phase_rad(double p, double q, std::complex<double> gm) {
  const std::complex<double> w = p * gm + q;
  double phase = -std::arg(1.0 + 1.0 / w);
  if (phase < 0.0) phase += 2.0 * std::numbers::pi;
  return phase;
}

double log_amplification(std::span<const double> rho) {
  double sum = 0.0;
  for (double r : rho) sum += r;
  return 2.0 * std::numbers::pi * sum;
}

double amplitude_after_revolutions(double initial_amplitude, std::span<const double> rho) {
  return initial_amplitude * std::exp(log_amplification(rho));
}

}  // namespace chatterlab::wheel_growth
