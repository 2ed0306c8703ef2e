#pragma once
// Independent references for root-finder tests: Newton in long double (64-bit mantissa, ~1e-19)
// on a scalar quasi-polynomial, and the rightmost root of a band by brute force (Newton from a
// dense grid of starts), against which find_rightmost_root is checked.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <optional>
#include <utility>

namespace chatterlab::testing {

using LongComplex = std::complex<long double>;

// f(s) and f'(s).
using ScalarFunction = std::function<std::pair<LongComplex, LongComplex>(LongComplex)>;

// Newton from s: the root when a step falls below 1e-18 max(|s|, 1) within 100 steps, else none.
inline std::optional<LongComplex> long_double_newton(const ScalarFunction& f, LongComplex s) {
  for (int i = 0; i < 100; ++i) {
    auto [value, derivative] = f(s);
    const LongComplex step = value / derivative;
    s -= step;
    if (!std::isfinite(static_cast<double>(std::abs(s)))) return std::nullopt;
    if (std::abs(step) <= 1e-18L * std::max(std::abs(s), 1.0L)) return s;
  }
  return std::nullopt;
}

// The rightmost root with 0 <= Im s <= band, by Newton from every start of the grid
// re_min..re_max x 0..band with spacing `step` (a test failure when none converges).
inline LongComplex brute_force_rightmost(const ScalarFunction& f, double band, double re_min, double re_max,
                                         double step = 0.05) {
  std::optional<LongComplex> best;
  for (double x = re_min; x <= re_max; x += step)
    for (double y = 0.0; y <= band; y += step)
      if (auto r = long_double_newton(f, LongComplex(x, y))) {
        const LongComplex root(r->real(), std::abs(r->imag()));
        if (root.imag() <= band && (!best || root.real() > best->real())) best = root;
      }
  if (!best) ADD_FAILURE() << "brute force found no root";
  return best.value_or(0.0L);
}

}  // namespace chatterlab::testing
