#pragma once
// Stability decided on the imaginary axis alone: the Nyquist criterion (the argument principle on
// the right half plane) for a model that knows its dynamics only at s = j w, e.g. a machine given
// by its measured FRF (docs/models/measured_frf.md).
//
// A model offers this route through Model::return_difference(): a function F(s) that is analytic
// and has no poles in Re s >= 0, tends to 1 for |s| -> infinity there, and whose zeros in Re s > 0
// are exactly the model's unstable characteristic roots. Then the number of unstable roots is
// N = -(1/pi) x (change of arg F(j w) for w from 0 to infinity) (F(-j w) = conj F(j w) gives the
// lower half). For MODELS.md G1 with a measured compliance H(j w),
//     F = D / (1 + kc/(kg A) + kc/(kw B)) = 1 + kc H / (1 + kc/(kg A) + kc/(kw B)),
//     A = 1 - e^{-Tg s}, B = 1 - e^{-Tw s},
// the divisor has no zeros in Re s >= 0 (Re 1/A > 1/2 there), so F qualifies.
#include <memory>
#include <string>
#include <vector>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

class ReturnDifference {
 public:
  virtual ~ReturnDifference() = default;

  // F(j w) and dF/dw at w >= 0 [rad/s] (CharacteristicValue::derivative holds dF/dw, the
  // derivative along the axis). Must be cheap and must not modify the object (thread-safe).
  virtual CharacteristicValue at(double omega_rad_s) const = 0;

  // A frequency above which |F(j w) - 1| < 1 holds for every higher w (and on the arc of that
  // radius in Re s > 0): F cannot encircle 0 any more, so the count stops there. 0 when
  // |F - 1| < 1 everywhere (nothing can be unstable). Proven from the model's data.
  virtual double winding_limit_rad_s() const = 0;

  // Frequencies up to max_rad_s around which F turns fast (the lattices 2 pi n/T of the delays,
  // where F passes through 1 in G1's F): the count and the lobe scan place samples there.
  virtual void fast_frequencies(double max_rad_s, std::vector<double>& out) const = 0;

  // Characteristic frequency of the system [Hz] (highest structural mode): bands default to a
  // multiple of it, as for the characteristic function.
  virtual double natural_frequency_scale_hz() const = 0;
};

struct NyquistCount {
  int unstable_roots = 0;     // zeros of F in Re s > 0, conjugate pairs counted twice
  double min_modulus = 0.0;   // smallest |F(j w)| met: how close the axis came to a root
  double min_modulus_frequency_hz = 0.0;
  int evaluations = 0;
  bool reliable = true;       // false: the phase could not be followed (a root on the axis)
  std::string note;           // why not reliable
};

// Follows arg F(j w) from 0 to winding_limit_rad_s() with steps that keep the phase change per
// step below pi/6 (refining geometrically towards every fast frequency), and counts.
// Deterministic and thread-safe.
NyquistCount count_unstable_roots(const ReturnDifference& f);

}  // namespace chatterlab
