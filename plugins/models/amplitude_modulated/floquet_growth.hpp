#pragma once
// MODELS.md G7 (book eqs 3-10..3-20): Floquet growth rate of wheel-regenerative chatter whose
// force is amplitude-modulated by the wheel unbalance,
//
//   m x1'' + c x1' + k x1 = F_p,   x = x1 + x2,   x2 = F_p/(kc b),
//   F_p(t) = -kg b (1 + Q sin w0 t) (x(t) - mu x(t - Tg)),   Tg = 2 pi / w0 = 60 / n_g.
//
// Eliminating x2: F_p = -kappa(t) (x1 - mu x(t - Tg)), kappa = kg b g/(1 + (kg/kc) g),
// g = 1 + Q sin w0 t, and x = (x1 + (kg/kc) g mu x(t - Tg))/(1 + (kg/kc) g): an ODE for x1 driven by
// the delayed relative displacement x, whose coefficients have the delay as their period.
// Its monodromy operator (one wheel revolution) is discretised by semi-discretisation
// (Insperger-Stepan): exact exponential integration of the oscillator on each step with kappa
// frozen at the step midpoint and the delayed x interpolated by a cubic through four samples; the
// step count is doubled until the fourth-order Richardson correction of the growth rate is below
// the tolerance. Docs: docs/models/closed_forms.md (G7).
#include <complex>
#include <vector>

namespace chatterlab {

struct AmplitudeModulatedParameters {
  double mass_kg = 0.0;                      // m
  double damping_n_s_per_m = 0.0;            // c
  double stiffness_n_per_m = 0.0;            // k
  double grinding_stiffness_n_per_m = 0.0;   // kg b (per-width stiffness times width)
  double contact_stiffness_n_per_m = 0.0;    // kc b
  double overlap_factor = 1.0;               // mu, 0 <= mu <= 1
  double modulation_depth = 0.0;             // Q, 0 <= Q < 1
  double wheel_speed_rpm = 0.0;              // w0 = 2 pi n_g/60, period Tg = 60/n_g
};

struct FloquetOptions {
  int initial_steps_per_period = 0;    // 0: about 0.5 rad of the stiffest frequency per step
  int max_steps_per_period = 4096;
  double tolerance_per_s = 1e-3;       // accepted Richardson correction (plus 1e-6 |s|)
  int sideband_orders = 3;             // report harmonics k = -K..K around the carrier
};

struct FloquetSideband {
  int order = 0;                    // k: frequency = carrier + k w0
  double frequency_hz = 0.0;
  double relative_amplitude = 0.0;  // |Phi_{r*+k}| / |Phi_{r*}| of the structure displacement x1
};

// (G7FloquetResult, not FloquetResult: chatterlab/floquet.hpp has the framework's, and one
// library must not define two types of one name.)
struct G7FloquetResult {
  std::complex<double> dominant_multiplier;  // largest |mu| of the monodromy operator
  double growth_rate_per_s = 0.0;            // sigma = ln|mu| / Tg, extrapolated in N
  // Richardson correction |sigma(N) - sigma(N/2)|/15 applied to sigma(N): the convergence check
  double growth_rate_change_per_s = 0.0;
  bool converged = false;                    // change <= tolerance
  int steps_per_period = 0;                  // N of the reported result
  // The Floquet solution x1 = sum_r Phi_r e^{(sigma + j (w_mu + r w0)) t} (eq 3-18): its largest
  // harmonic is the carrier (chatter frequency), the others the sidebands spaced by w0 (eq 3-20).
  double carrier_frequency_hz = 0.0;
  std::vector<FloquetSideband> sidebands;  // k = -K..K (k = 0 is the carrier, amplitude 1)
};

// Throws std::invalid_argument for parameters outside the limits above (non-positive m, k, kg b,
// kc b or speed; negative c; mu outside [0, 1]; Q outside [0, 1)).
G7FloquetResult floquet_growth(const AmplitudeModulatedParameters& parameters,
                             const FloquetOptions& options = {});

}  // namespace chatterlab
