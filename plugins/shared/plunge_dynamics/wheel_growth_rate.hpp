#pragma once
// MODELS.md G3: closed-form growth rate of wheel-regenerative chatter, corrected eq 2-68 (= 5-33),
// and the per-revolution amplitude recursion of variable-speed grinding, eqs 5-36..5-39.
// Docs: docs/models/closed_forms.md (G3), with the error table against exact roots.
//
// Wheel regeneration only (eq 2-66): -1/(kg (1 - e^{-Tg s})) = Gm(s)/km + 1/kc. With
// rho = Tg sigma/(2 pi) and W = p Gm + q = p (x + j y) + q, p = kg/km, q = kg/kc (eq 2-67):
//   e^{-2 pi rho} e^{-j w Tg} = 1 + 1/W,
// so  rho = -(1/(4 pi)) ln[1 + (1 + 2 (p x + q)) / (p^2 y^2 + (p x + q)^2)]   (corrected 2-68;
// the printed 2-68 has a spurious 1/p^2 inside the logarithm, 5-33 has it right)
// and the lattice phase w Tg = -arg(1 + 1/W) (mod 2 pi) fixes which wheel speeds chatter at w.
// The formula is exact when Gm is evaluated at the root s = sigma + j w; the closed form
// evaluates it at s = j w (error ~ sigma |dW/ds| |d rho/dW|: good while |sigma| << zeta w_n).
#include <complex>
#include <functional>
#include <limits>
#include <span>

namespace chatterlab::wheel_growth {

// rho (growth per wheel revolution, A_{n+1}/A_n = e^{2 pi rho}) from p = kg/km, q = kg/kc and the
// normalised structure Gm = x + j y (dimensionless; Gm(0) = 1 for one mode). Corrected eq 2-68.
double growth_rate_per_rev(double p, double q, std::complex<double> normalised_structure);

// The same from the machine compliance H = Gm/km [m/N]: W = kg H + kg/kc.
double growth_rate_per_rev_from_compliance(double wheel_wear_stiffness_n_per_m,
                                           double contact_stiffness_n_per_m,
                                           std::complex<double> compliance_m_per_n);

// The wheel-lattice phase w Tg in [0, 2 pi) at which a chatter frequency w with this W is a root:
// -arg(1 + 1/W) mod 2 pi. (Wheel speeds n_g = 60 w / (phase + 2 pi n) for n = 0, 1, ...)
double lattice_phase_rad(double p, double q, std::complex<double> normalised_structure);

// Eq 5-37/5-39: amplitude after n revolutions with growth rates rho_1..rho_n,
// A_n = A_0 exp(2 pi sum rho_i). Constant speed (5-38) is rho_i = rho_max for every i.
double amplitude_after_revolutions(double initial_amplitude, std::span<const double> growth_rates_per_rev);

// ln(A_n/A_0) = 2 pi sum rho_i (never overflows; for long schedules).
double log_amplification(std::span<const double> growth_rates_per_rev);

// G3 at one wheel speed, the closed form beside the root (Model::closed_forms()): the frequencies
// w in (0, max_frequency] at which the wheel lattice admits a root, w Tg = lattice phase (mod
// 2 pi), found as sign changes of the wrapped difference on a grid of 0.05 rad of w Tg (and at
// most 0.1 Hz), the closed-form rho at each, and the largest. The neutral root at w = 0 is left
// out. max_growth_rate_per_rev is rho_max over every frequency of the band: the rate some wheel
// speed reaches (the constant-speed bound of 5-38).
struct WheelChatterClosedForm {
  static constexpr double none = std::numeric_limits<double>::quiet_NaN();
  double growth_rate_per_rev = none;   // largest rho over this speed's lattice frequencies
  double growth_rate_per_s = none;     // 2 pi rho / Tg
  double chatter_frequency_hz = none;  // the frequency of that rho
  double max_growth_rate_per_rev = none;
};
WheelChatterClosedForm wheel_chatter_at_speed(
    double wheel_wear_stiffness_n_per_m, double contact_stiffness_n_per_m,
    const std::function<std::complex<double>(double frequency_rad_s)>& compliance_m_per_n,
    double wheel_period_s, double max_frequency_hz);

}  // namespace chatterlab::wheel_growth
