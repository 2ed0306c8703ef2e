#pragma once
// What a model supplies for linear stability: its characteristic function, written as an ENTIRE
// function E(s) (denominators multiplied out) so that the argument principle counts zeros only.
// Example: MODELS.md G1 eq 2-16 multiplied by (1 - e^{-Tg s})(1 - e^{-Tw s}) and by the modal
// denominators. The multiplication adds known zeros (the neutral root s = 0 of the cumulative
// removal chain); the model declares them in neutral_roots() and the solver excludes them.
//
// E must have real coefficients (E(conj s) = conj E(s)): roots come in conjugate pairs, so every
// list below covers the upper half plane Im s >= 0 only and the conjugates are implied.
#include <complex>
#include <string>
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

  // E(s) and E'(s). Must be cheap: the solver calls it 10^4..10^5 times per grid point. Must not
  // modify the object (the solver may be called from several threads on separate objects; an
  // evaluate() that writes shared state would break determinism).
  virtual CharacteristicValue evaluate(Complex s) const = 0;

  // Optional: F = E/G and F' for a factor G chosen so that F is closer to linear near the roots
  // than E (e.g. a neutral delay chain's asymptotic factor 1 + c - e^{-T s}, whose zeros are the
  // roots' high-frequency limit): the search's Newton iterations run on F and converge in fewer
  // steps. F has E's zeros wherever G != 0 (Newton is repelled from G's zeros, F's poles); the
  // certificate always counts the zeros of E itself, so this affects speed only. Default: E.
  virtual CharacteristicValue newton_form(Complex s) const { return evaluate(s); }

  // Zeros of E(s) that are not characteristic roots (s = 0 for G1), with 0 <= Im s <=
  // max_angular_frequency (a little beyond is fine). Each listed once per multiplicity; the
  // conjugates (Im < 0) are implied. The solver never reports them and subtracts them from its
  // contour counts, so each must be an exact zero of E (to rounding).
  virtual std::vector<Complex> neutral_roots(double /*max_angular_frequency_rad_s*/) const {
    return {};
  }

  // Starting guesses for Newton covering 0 <= Im s <= max_angular_frequency (E has real
  // coefficients, so roots come in conjugate pairs and the upper half plane suffices).
  // A model knows where its roots live (delay-pole lattices, structural poles); good guesses
  // make the search fast, the certificate makes it safe.
  virtual void initial_guesses(double max_angular_frequency_rad_s,
                               std::vector<Complex>& guesses) const = 0;

  // An upper bound on Re s over all zeros of E (bounds the certificate contour on the right).
  // Must be proven from the model's structure (e.g. a norm bound), not estimated: the
  // certificate is only as good as this bound.
  virtual double real_part_bound() const = 0;

  // Characteristic frequency of the system [Hz] (highest structural natural frequency); the
  // default search band is a documented multiple of it.
  virtual double natural_frequency_scale_hz() const = 0;

  // What the certificate can say beyond the band |Im s| <= band_rad_s for a contour whose left
  // edge is Re s = certified_real_part, appended to RightmostRoot::certificate (empty: nothing).
  // E.g. that every root right of that edge is proven to lie inside the band (the certificate is
  // then global), or, for a neutral system, where the root chains beyond the band accumulate (the
  // spectrum of its difference operator). Must only state what the model's structure proves.
  virtual std::string certificate_note(double /*certified_real_part*/, double /*band_rad_s*/) const {
    return {};
  }
};

}  // namespace chatterlab
