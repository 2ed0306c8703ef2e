#include "roots/newton.hpp"

#include <algorithm>
#include <cmath>

namespace chatterlab::roots_detail {

namespace {

double step_tolerance(Complex s, const NewtonSettings& settings) {
  return settings.relative_tolerance * std::max(magnitude(s), settings.length_scale);
}

// Newton restricted to the real axis (E is real there): confirms a root that converged to within
// rounding of the axis really is real, and makes its imaginary part exactly 0.
std::optional<double> real_newton(Evaluator& evaluate, double x, const NewtonSettings& settings) {
  for (int iteration = 0; iteration < 8; ++iteration) {
    CharacteristicValue e = evaluate(Complex(x, 0.0));
    double value = e.value.real(), derivative = e.derivative.real();
    if (value == 0.0) return x;
    if (!std::isfinite(value) || !std::isfinite(derivative) || derivative == 0.0) return std::nullopt;
    double step = value / derivative;
    x -= step;
    if (std::abs(step) <= step_tolerance(Complex(x, 0.0), settings)) return x;
  }
  return std::nullopt;
}

}  // namespace

void newton_steps(Evaluator& evaluate, NewtonIterate& it, int steps, const NewtonSettings& settings) {
  using Status = NewtonIterate::Status;
  for (int k = 0; k < steps && it.status == Status::running; ++k) {
    if (it.iterations >= settings.max_iterations) {
      it.status = Status::failed;
      return;
    }
    ++it.iterations;
    // On the model's Newton form E/G (same zeros; fewer steps where G captures the roots' lattice).
    CharacteristicValue e = evaluate.newton_form(it.s);
    // An exact zero ends the iteration even if E' is not finite there (a model may form E' from
    // E'/E, which is 0 * inf at a zero).
    bool converged = e.value == Complex(0.0);
    if (!converged) {
      if (!is_finite(e.value) || !is_finite(e.derivative) || e.derivative == Complex(0.0)) {
        it.status = Status::failed;
        return;
      }
      Complex step = divide(e.value, e.derivative);
      it.s -= step;
      it.last_step = magnitude(step);
      converged = it.last_step <= step_tolerance(it.s, settings);
    } else {
      it.last_step = 0.0;
    }
    Complex& s = it.s;
    if (!is_finite(s) || s.real() > settings.max_real_part ||
        std::abs(s.imag()) > settings.max_imag_part) {
      it.status = Status::failed;
      return;
    }
    if (!converged) continue;
    it.status = Status::converged;
    if (s.imag() < 0.0) s = std::conj(s);
    // A real root approached from a complex guess keeps a rounding-sized imaginary part; a
    // genuine complex pair that close to the axis would not converge on the real axis.
    if (s.imag() <= 1e3 * step_tolerance(s, settings)) {
      if (auto x = real_newton(evaluate, s.real(), settings);
          x && std::abs(*x - s.real()) <= 1e3 * step_tolerance(s, settings))
        s = Complex(*x, 0.0);
    }
  }
}

std::optional<Complex> newton(Evaluator& evaluate, Complex guess, const NewtonSettings& settings) {
  NewtonIterate it;
  it.s = guess;
  newton_steps(evaluate, it, settings.max_iterations, settings);
  if (it.status == NewtonIterate::Status::converged) return it.s;
  return std::nullopt;
}

double RootSet::tolerance(Complex s) const {
  return relative_tolerance_ * std::max(magnitude(s), length_scale_);
}

bool RootSet::contains(Complex s) const {
  double tol = tolerance(s);
  auto first = std::lower_bound(roots_.begin(), roots_.end(), s.imag() - 2.0 * tol,
                                [](Complex r, double im) { return r.imag() < im; });
  for (auto it = first; it != roots_.end() && it->imag() <= s.imag() + 2.0 * tol; ++it)
    if (magnitude(*it - s) <= std::max(tol, tolerance(*it))) return true;
  return false;
}

bool RootSet::insert(Complex s) {
  if (contains(s)) return false;
  auto at = std::lower_bound(roots_.begin(), roots_.end(), s, [](Complex a, Complex b) {
    return a.imag() < b.imag() || (a.imag() == b.imag() && a.real() < b.real());
  });
  roots_.insert(at, s);
  return true;
}

}  // namespace chatterlab::roots_detail
