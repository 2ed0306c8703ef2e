#include "models/measured_frf/g1_return_difference.hpp"

#include <cmath>
#include <numbers>

namespace chatterlab {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}

G1ReturnDifference::G1ReturnDifference(const G1Process& process, Compliance compliance, double winding_limit_rad_s,
                                       double natural_frequency_scale_hz)
    : process_(process),
      alpha_(process.alpha()),
      beta_(process.beta()),
      compliance_(std::move(compliance)),
      winding_limit_rad_s_(winding_limit_rad_s),
      natural_frequency_scale_hz_(natural_frequency_scale_hz) {}

CharacteristicValue G1ReturnDifference::at(double w) const {
  const ComplianceValue h = compliance_(w / kTwoPi);
  const Complex h_w = h.derivative_per_hz / kTwoPi;
  // A = 1 - e^{-j w T}, dA/dw = j T e^{-j w T}; a chain switched off is A = 1, alpha = 0.
  auto chain = [w](bool on, double period, Complex& value, Complex& derivative) {
    if (!on) {
      value = 1.0;
      derivative = 0.0;
      return;
    }
    const Complex delayed = std::polar(1.0, -w * period);
    value = 1.0 - delayed;
    derivative = Complex(0.0, period) * delayed;
  };
  Complex a, a_w, b, b_w;
  chain(process_.wheel_regeneration, process_.wheel_period_s, a, a_w);
  chain(process_.work_regeneration, process_.work_period_s, b, b_w);
  const double kc = process_.contact_stiffness_n_per_m;
  const Complex n = kc * h.value * a * b;
  const Complex d = a * b + alpha_ * b + beta_ * a;
  if (d == 0.0) return {1.0, 0.0};  // w = 0 with both chains on: the limit F = 1
  const Complex n_w = kc * (h_w * a * b + h.value * (a_w * b + a * b_w));
  const Complex d_w = a_w * b + a * b_w + alpha_ * b_w + beta_ * a_w;
  return {1.0 + n / d, (n_w * d - n * d_w) / (d * d)};
}

void G1ReturnDifference::fast_frequencies(double max_rad_s, std::vector<double>& out) const {
  for (auto [on, period] : {std::pair{process_.wheel_regeneration, process_.wheel_period_s},
                            std::pair{process_.work_regeneration, process_.work_period_s}}) {
    if (!on) continue;
    const double spacing = kTwoPi / period;
    for (double w = 0.0; w <= max_rad_s; w += spacing) out.push_back(w);
  }
}

}  // namespace chatterlab
