#pragma once
// Test support (framework tests only): MODELS.md G1 written once as GrindingEquations, and eq 2-16
// multiplied out by hand in long double, the independent reference the derived route is held to.
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <span>
#include <vector>

#include "chatterlab/derived_model.hpp"

namespace chatterlab::test_support {

// G1 time domain (MODELS.md): modal displacements q_i (x = sum q_i),
//   q_i'' + 2 zeta_i w_i q_i' + w_i^2 q_i = (w_i^2 / k_i) F,
//   F = (U0 - Wg(t - Tg) - Ww(t - Tw) - x) / (1/kc + 1/kg + 1/kw),  removal F/kg and F/kw.
struct G1Equations {
  double kc = 1e8, kg = 5e9, kw = 5e7, wheel_rpm = 1450.0, work_rpm = 55.0;
  std::vector<std::array<double, 3>> modes = {{184.08, 0.05, 5e7}, {305.6, 0.04, 8e7}};  // f [Hz], zeta, k [N/m]
  bool wheel = true, work = true;

  std::size_t state_size() const { return 2 * modes.size(); }
  bool regenerates(Rotor r) const { return r == Rotor::wheel ? wheel : work; }
  double nominal_speed_rpm(Rotor r) const { return r == Rotor::wheel ? wheel_rpm : work_rpm; }
  double displacement_m(std::span<const double> x) const {
    double sum = 0.0;
    for (std::size_t i = 0; i < modes.size(); ++i) sum += x[2 * i];
    return sum;
  }
  template <class S>
  void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const {
    S x = S(0.0);
    for (std::size_t i = 0; i < modes.size(); ++i) x += in.state[2 * i];
    const double compliance = 1.0 / kc + (wheel ? 1.0 / kg : 0.0) + (work ? 1.0 / kw : 0.0);
    const S interference = in.infeed_m - x - in.previous_surface_m[0] - in.previous_surface_m[1];
    out.penetration_m = interference;
    out.normal_force_n = interference / compliance;
    out.removed_m[0] = wheel ? out.normal_force_n / kg : S(0.0);
    out.removed_m[1] = work ? out.normal_force_n / kw : S(0.0);
  }
  template <class S>
  void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& c, std::span<S> dx) const {
    for (std::size_t i = 0; i < modes.size(); ++i) {
      const double w = 2.0 * std::numbers::pi * modes[i][0], zeta = modes[i][1], k = modes[i][2];
      dx[2 * i] = in.state[2 * i + 1];
      dx[2 * i + 1] = w * w * (c.normal_force_n / k - in.state[2 * i]) - 2.0 * zeta * w * in.state[2 * i + 1];
    }
  }

  // Eq 2-16 multiplied out: E = prod P_i (A B + alpha B + beta A) + A B sum_i (kc/k_i) prod_{j != i} P_j,
  // A = 1 - e^{-Tg s}, B = 1 - e^{-Tw s}, alpha = kc/kg, beta = kc/kw, P = s^2/w^2 + 2 zeta s/w + 1.
  std::complex<long double> closed_form(std::complex<long double> s) const {
    using LC = std::complex<long double>;
    const long double tg = 60.0L / wheel_rpm, tw = 60.0L / work_rpm;
    const LC a = wheel ? 1.0L - std::exp(-tg * s) : LC(1.0L), b = work ? 1.0L - std::exp(-tw * s) : LC(1.0L);
    const long double alpha = wheel ? kc / kg : 0.0L, beta = work ? kc / kw : 0.0L;
    LC product = 1.0L, coupled = 0.0L;
    for (const auto& m : modes) {
      const long double w = 2.0L * std::numbers::pi_v<long double> * m[0];
      const LC p = s * s / (w * w) + 2.0L * static_cast<long double>(m[1]) * s / w + 1.0L;
      coupled = coupled * p + static_cast<long double>(kc / m[2]) * product;
      product *= p;
    }
    return product * (a * b + alpha * b + beta * a) + a * b * coupled;
  }
};

}  // namespace chatterlab::test_support
