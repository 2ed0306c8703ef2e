#pragma once
// det M and d det M / ds of small complex matrices (row-major n x n), for characteristic
// functions written as matrices (the framework's delay systems, linear_dde's fast path). Both
// destroy their arguments; no allocation for n <= 8.
#include <cstddef>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

// det(a) by Gaussian elimination with partial pivoting.
Complex complex_determinant(Complex* a, std::size_t n);

// det(M) and, by Jacobi's formula, d det = det(M) tr(M^{-1} dM); closed forms for n <= 2. An
// exactly singular M (s an exact root) falls back to the sum of the determinants with one column
// taken from dM.
CharacteristicValue complex_determinant_and_derivative(Complex* m, Complex* dm, std::size_t n);

}  // namespace chatterlab
