#pragma once
// MODELS.md G6 (book eqs 3-1..3-6): forced vibration of wheel and workpiece from wheel unbalance,
//
//   m1 x1'' + c1 x1' + (k + k1) x1 + k x2 = F,   m2 x2'' + c2 x2' + (k + k2) x2 + k x1 = 0,
//   k = kc kg/(kc + kg),   F = U w^2 cos(w t),  w = 2 pi n_g/60 (the wheel's rotation).
//
// x1 (wheel centre) and x2 (work axis) are measured towards each other, so the contact chain (kc
// in series with kg) is compressed by x1 + x2 and carries f = k (x1 + x2). The relative motion of
// the wheel surface and the work surface (the change of depth of cut, 3-2, 3-5) is the grinding
// spring's share f/kg = (x1 + x2)/(1 + kg/kc). Undamped: 3-3 with the printed typos corrected
// ((wa1^2 - w^2)(wa2^2 - w^2) in the denominator, not w1, w2; 4 k^2 in 3-4, not 4 k2^2);
// damped: the 2 x 2 complex solve. Docs: docs/models/closed_forms.md (G6).
#include <complex>

namespace chatterlab {

struct UnbalanceTwoDofParameters {
  double wheel_mass_kg = 0.0;                       // m1
  double wheel_damping_n_s_per_m = 0.0;             // c1
  double wheel_support_stiffness_n_per_m = 0.0;     // k1
  double work_mass_kg = 0.0;                        // m2
  double work_damping_n_s_per_m = 0.0;              // c2
  double work_support_stiffness_n_per_m = 0.0;      // k2
  double contact_stiffness_n_per_m = 0.0;           // kc
  double grinding_stiffness_n_per_m = 0.0;          // kg
  double unbalance_kg_m = 0.0;                      // U (mass times eccentricity)
  double wheel_speed_rpm = 0.0;                     // n_g: forcing frequency w = 2 pi n_g/60
  double work_speed_rpm = 0.0;                      // n_w (lobes per revolution, 3-6)
};

namespace unbalance {

// k = kc kg/(kc + kg) [N/m] (contact and grinding stiffness in series).
double coupling_stiffness_n_per_m(const UnbalanceTwoDofParameters& p);

// Undamped natural frequencies w_a1 < w_a2 [rad/s] (3-4, corrected).
struct NaturalFrequencies {
  double lower_rad_s;
  double upper_rad_s;
};
NaturalFrequencies natural_frequencies(const UnbalanceTwoDofParameters& p);

// Undamped relative-motion amplitude Delta X [m] at forcing frequency w (3-3, corrected); signed:
// negative means in antiphase with the force. Infinite at w = w_a1, w_a2.
double undamped_relative_amplitude_m(const UnbalanceTwoDofParameters& p, double frequency_rad_s);

// Damped steady state at forcing frequency w: complex amplitudes (x = Re(X e^{j w t})) of the
// wheel centre, the work axis and the relative surface motion (x1 + x2)/(1 + kg/kc).
struct SteadyState {
  std::complex<double> wheel_m;
  std::complex<double> work_m;
  std::complex<double> relative_m;
};
SteadyState steady_state(const UnbalanceTwoDofParameters& p, double frequency_rad_s);

// The forcing frequency of the wheel unbalance, w = 2 pi n_g/60 [rad/s].
double forcing_frequency_rad_s(const UnbalanceTwoDofParameters& p);
// Steady state at the wheel's own speed (F = U w^2).
SteadyState unbalance_response(const UnbalanceTwoDofParameters& p);

// Waviness lobes per workpiece revolution from the unbalance, Z = n_g/n_w (3-6).
double lobes_per_revolution(const UnbalanceTwoDofParameters& p);

}  // namespace unbalance
}  // namespace chatterlab
