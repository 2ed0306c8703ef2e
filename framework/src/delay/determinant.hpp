#pragma once
// det M and d det M / ds of small complex matrices (row-major, n x n), without allocation for
// n <= 8: the inner loop of every characteristic evaluation of a delay system.
#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/complex_determinant.hpp"

namespace chatterlab::delay_detail {

// Gaussian elimination with partial pivoting of a (row-major n x n), in place: a becomes U above
// the diagonal; the same row operations are applied to `rhs` (n x n, may be null), which becomes
// L^{-1} P rhs. Returns det(a), or 0 when a pivot is exactly 0 (then a is left half reduced).
Complex eliminate(Complex* a, Complex* rhs, std::size_t n);

inline Complex determinant(Complex* a, std::size_t n) { return eliminate(a, nullptr, n); }

// det(M) and, by Jacobi's formula, d det = det(M) tr(M^{-1} dM); closed forms for n <= 2. m and
// dm are destroyed. An exactly singular M (s an exact root) falls back to the sum of the
// determinants with one column taken from dM.
CharacteristicValue determinant_and_derivative(Complex* m, Complex* dm, std::size_t n);

}  // namespace chatterlab::delay_detail
