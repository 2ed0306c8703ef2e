#pragma once
// det M and d det M / ds of small complex matrices (row-major n x n), for characteristic
// functions written as matrices (the framework's delay systems, linear_dde's fast path). Both
// destroy their arguments; no allocation for n <= 8.
#include <cstddef>
#include <vector>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

// Storage for `size` complex numbers: on the stack up to N (no allocation per evaluation for
// small systems), else on the heap. Left uninitialised (callers write before they read): a
// std::array<Complex, N> would zero-fill N complex numbers on every evaluation.
template <std::size_t N>
class ComplexScratch {
 public:
  explicit ComplexScratch(std::size_t size) {
    if (size > N) heap_.resize(size);
  }
  Complex* data() { return heap_.empty() ? reinterpret_cast<Complex*>(stack_) : heap_.data(); }

 private:
  alignas(Complex) unsigned char stack_[N * sizeof(Complex)];
  std::vector<Complex> heap_;
};

// det(a) by Gaussian elimination with partial pivoting.
Complex complex_determinant(Complex* a, std::size_t n);

// det(M) and, by Jacobi's formula, d det = det(M) tr(M^{-1} dM); closed forms for n <= 2. An
// exactly singular M (s an exact root) falls back to the sum of the determinants with one column
// taken from dM.
CharacteristicValue complex_determinant_and_derivative(Complex* m, Complex* dm, std::size_t n);

}  // namespace chatterlab
