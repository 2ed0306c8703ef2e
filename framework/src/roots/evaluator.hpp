#pragma once
// Internal to find_rightmost_root: counted, budgeted access to E(s).
#include <cmath>
#include <stdexcept>

#include "chatterlab/characteristic.hpp"

namespace chatterlab::roots_detail {

// Thrown inside the search when the evaluation budget is spent; find_rightmost_root turns it into
// an uncertified result (never lets it escape).
class BudgetExhausted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Evaluator {
 public:
  Evaluator(const CharacteristicFunction& function, long budget)
      : function_(function), budget_(budget) {}

  CharacteristicValue operator()(Complex s) {
    count_one();
    return function_.evaluate(s);
  }
  // The function's Newton form (CharacteristicFunction::newton_form), counted alike.
  CharacteristicValue newton_form(Complex s) {
    count_one();
    return function_.newton_form(s);
  }

  long count() const { return count_; }

 private:
  void count_one() {
    if (++count_ > budget_) throw BudgetExhausted("evaluation budget exhausted");
  }
  const CharacteristicFunction& function_;
  long budget_;
  long count_ = 0;
};

inline bool is_finite(Complex z) { return std::isfinite(z.real()) && std::isfinite(z.imag()); }

// |z| without hypot's overflow care (glibc's hypot dominated the profile). Only for values far
// from the overflow limit: points s, steps, E'/E ratios; not for E itself.
inline double magnitude(Complex z) { return std::sqrt(z.real() * z.real() + z.imag() * z.imag()); }

// log z = ln|z| + i arg z without clog's extra-precision path; falls back to std::log when |z|^2
// over- or underflows.
inline Complex logarithm(Complex z) {
  const double n = z.real() * z.real() + z.imag() * z.imag();
  if (!(n > 1e-300) || !(n < 1e300)) return std::log(z);
  return {0.5 * std::log(n), std::atan2(z.imag(), z.real())};
}

// Principal square root (same branch as std::sqrt) without csqrt's hypot.
inline Complex square_root(Complex z) {
  const double r = magnitude(z);
  if (r == 0.0) return 0.0;
  const double t = std::sqrt(0.5 * (r + std::abs(z.real())));
  if (z.real() >= 0.0) return {t, z.imag() / (2.0 * t)};
  return {std::abs(z.imag()) / (2.0 * t), std::copysign(t, z.imag())};
}

// a / b by Smith's algorithm, inline (libgcc's __divdc3 was the next hot spot); no special
// handling of infinities, which the callers reject anyway.
inline Complex divide(Complex a, Complex b) {
  if (std::abs(b.real()) >= std::abs(b.imag())) {
    const double r = b.imag() / b.real(), d = b.real() + b.imag() * r;
    return {(a.real() + a.imag() * r) / d, (a.imag() - a.real() * r) / d};
  }
  const double r = b.real() / b.imag(), d = b.real() * r + b.imag();
  return {(a.real() * r + a.imag()) / d, (a.imag() * r - a.real()) / d};
}

}  // namespace chatterlab::roots_detail
