#pragma once
// Internal to find_rightmost_root: Newton's method on E(s) (on the model's Newton form E/G,
// CharacteristicFunction::newton_form) and the set of located roots.
#include <optional>
#include <vector>

#include "roots/evaluator.hpp"

namespace chatterlab::roots_detail {

struct NewtonSettings {
  double relative_tolerance = 1e-13;  // stop when |step| <= tol * max(|s|, length_scale)
  int max_iterations = 60;
  double length_scale = 1.0;          // absolute floor for the tolerance [rad/s]
  double max_real_part = 0.0;         // iterates beyond this have left every zero (bound of E)
  double max_imag_part = 0.0;         // iterates beyond this are out of interest
};

// A Newton iteration that can be paused and resumed (the search runs a few steps on every guess,
// then finishes only the candidates that may still become the rightmost root).
struct NewtonIterate {
  enum class Status { running, converged, failed };
  Status status = Status::running;
  Complex s;                // current iterate (the root when converged, mapped to Im >= 0)
  double last_step = 0.0;   // |s_k - s_{k-1}|; after quadratic convergence sets in, an upper
                            // estimate of the remaining distance to the root
  int iterations = 0;
};

// Advances `it` by at most `steps` Newton steps (stops early on convergence or failure). Fails
// when the iteration diverges, leaves the region or meets a non-finite value. A converged root is
// mapped to Im >= 0 (E has real coefficients); roots within rounding of the real axis are snapped
// onto it (and confirmed by a real Newton iteration), so that a real root counts once, not as a
// conjugate pair.
void newton_steps(Evaluator& evaluate, NewtonIterate& it, int steps, const NewtonSettings& settings);

// Newton from `guess` to convergence; nothing when it fails.
std::optional<Complex> newton(Evaluator& evaluate, Complex guess, const NewtonSettings& settings);

// Distinct roots, all with Im >= 0, kept sorted by Im for a fast duplicate test.
class RootSet {
 public:
  RootSet(double relative_tolerance, double length_scale)
      : relative_tolerance_(relative_tolerance), length_scale_(length_scale) {}

  // Same root (to the set's tolerance) as one already held?
  bool contains(Complex s) const;
  // Adds s unless it duplicates a held root; returns whether it was added.
  bool insert(Complex s);
  const std::vector<Complex>& roots() const { return roots_; }
  double tolerance(Complex s) const;

 private:
  double relative_tolerance_;
  double length_scale_;
  std::vector<Complex> roots_;  // sorted by imag, then real
};

}  // namespace chatterlab::roots_detail
