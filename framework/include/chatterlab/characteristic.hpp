#pragma once
// What a model supplies for linear stability: its characteristic function, written as an ENTIRE
// function E(s) (denominators multiplied out) so that the argument principle counts zeros only.
// Example: MODELS.md G1 eq 2-16 multiplied by (1 - e^{-Tg s})(1 - e^{-Tw s}) and by the modal
// denominators. The multiplication adds known zeros (the neutral root s = 0 of the cumulative
// removal chain); the model declares them in neutral_roots() and the solver excludes them.
#include <complex>
#include <vector>

namespace chatterlab {

using Complex = std::complex<double>;

struct CharacteristicValue {
  Complex value;       // E(s)
  Complex derivative;  // dE/ds
};

class CharacteristicFunction {
 public:
  virtual ~CharacteristicFunction() = default;

  // E(s) and E'(s). Must be cheap: the solver calls it 10^4..10^5 times per grid point.
  virtual CharacteristicValue evaluate(Complex s) const = 0;

  // Zeros of E(s) that are not characteristic roots (s = 0 for G1). Each listed once per
  // multiplicity. The solver never reports them and subtracts them from contour counts.
  virtual std::vector<Complex> neutral_roots() const { return {}; }

  // Starting guesses for Newton covering 0 <= Im s <= max_angular_frequency (E has real
  // coefficients, so roots come in conjugate pairs and the upper half plane suffices).
  // A model knows where its roots live (delay-pole lattices, structural poles); good guesses
  // make the search fast, the certificate makes it safe.
  virtual void initial_guesses(double max_angular_frequency_rad_s,
                               std::vector<Complex>& guesses) const = 0;

  // An upper bound on Re s over all zeros of E (bounds the certificate contour on the right).
  virtual double real_part_bound() const = 0;

  // Characteristic frequency of the system [Hz] (highest structural natural frequency); the
  // default search band is a documented multiple of it.
  virtual double natural_frequency_scale_hz() const = 0;
};

}  // namespace chatterlab
