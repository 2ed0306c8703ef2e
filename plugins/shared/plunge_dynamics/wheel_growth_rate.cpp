#include "shared/plunge_dynamics/wheel_growth_rate.hpp"

#include <algorithm>
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

WheelChatterClosedForm wheel_chatter_at_speed(
    double kg, double kc, const std::function<std::complex<double>(double)>& compliance, double tg,
    double max_frequency_hz) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  const double w_max = two_pi * max_frequency_hz;
  const double step = std::min(0.05 / tg, two_pi * 0.1);
  WheelChatterClosedForm out;
  // Lattice mismatch w Tg - phase, wrapped into (-pi, pi]: zero where the lattice admits a root.
  auto mismatch = [&](double w, std::complex<double> h) {
    const double phase = lattice_phase_rad(1.0, kg / kc, kg * h);
    return std::remainder(w * tg - phase, two_pi);
  };
  double w_prev = step, g_prev = mismatch(w_prev, compliance(w_prev));
  for (double w = 2.0 * step; w <= w_max; w += step) {
    const std::complex<double> h = compliance(w);
    const double rho_here = growth_rate_per_rev_from_compliance(kg, kc, h);
    if (!(out.max_growth_rate_per_rev >= rho_here)) out.max_growth_rate_per_rev = rho_here;
    const double g = mismatch(w, h);
    // A sign change without the 2 pi jump of the wrap is a lattice frequency.
    if ((g_prev < 0.0) != (g < 0.0) && std::abs(g - g_prev) < std::numbers::pi) {
      const double w_root = w_prev - g_prev * (w - w_prev) / (g - g_prev);
      const double rho = growth_rate_per_rev_from_compliance(kg, kc, compliance(w_root));
      if (!(out.growth_rate_per_rev >= rho)) {
        out.growth_rate_per_rev = rho;
        out.chatter_frequency_hz = w_root / two_pi;
      }
    }
    w_prev = w;
    g_prev = g;
  }
  if (std::isfinite(out.growth_rate_per_rev)) out.growth_rate_per_s = two_pi * out.growth_rate_per_rev / tg;
  return out;
}

}  // namespace chatterlab::wheel_growth
