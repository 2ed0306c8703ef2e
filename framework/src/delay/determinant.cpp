#include "delay/determinant.hpp"

#include "chatterlab/complex_determinant.hpp"

namespace chatterlab::delay_detail {

Complex eliminate(Complex* a, Complex* rhs, std::size_t n) {
  Complex det = 1.0;
  for (std::size_t col = 0; col < n; ++col) {
    std::size_t pivot = col;
    for (std::size_t r = col + 1; r < n; ++r)
      if (std::norm(a[r * n + col]) > std::norm(a[pivot * n + col])) pivot = r;
    if (a[pivot * n + col] == Complex(0.0)) return 0.0;
    if (pivot != col) {
      std::swap_ranges(a + col * n, a + col * n + n, a + pivot * n);
      if (rhs) std::swap_ranges(rhs + col * n, rhs + col * n + n, rhs + pivot * n);
      det = -det;
    }
    const Complex p = a[col * n + col];
    det *= p;
    for (std::size_t r = col + 1; r < n; ++r) {
      const Complex f = a[r * n + col] / p;
      for (std::size_t c = col + 1; c < n; ++c) a[r * n + c] -= f * a[col * n + c];
      if (rhs)
        for (std::size_t c = 0; c < n; ++c) rhs[r * n + c] -= f * rhs[col * n + c];
    }
  }
  return det;
}

CharacteristicValue determinant_and_derivative(Complex* m, Complex* dm, std::size_t n) {
  switch (n) {
    case 0: return {1.0, 0.0};
    case 1: return {m[0], dm[0]};
    case 2: return {m[0] * m[3] - m[1] * m[2], dm[0] * m[3] + m[0] * dm[3] - dm[1] * m[2] - m[1] * dm[2]};
    default: break;
  }
  const std::size_t nn = n * n;
  ComplexScratch<3 * 64> storage(3 * nn);
  Complex* m_original = storage.data();  // kept for the singular fallback
  Complex* dm_original = m_original + nn;
  Complex* work = m_original + 2 * nn;
  std::copy(m, m + nn, m_original);
  std::copy(dm, dm + nn, dm_original);
  const Complex det = eliminate(m, dm, n);
  if (det != Complex(0.0)) {
    // Back substitution U X = L^{-1} P dM column by column; tr X = tr(M^{-1} dM).
    Complex trace = 0.0;
    for (std::size_t c = 0; c < n; ++c) {
      for (std::size_t r = n; r-- > 0;) {
        Complex v = dm[r * n + c];
        for (std::size_t k = r + 1; k < n; ++k) v -= m[r * n + k] * dm[k * n + c];
        dm[r * n + c] = v / m[r * n + r];
      }
      trace += dm[c * n + c];
    }
    return {det, det * trace};
  }
  Complex derivative = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    std::copy(m_original, m_original + nn, work);
    for (std::size_t r = 0; r < n; ++r) work[r * n + j] = dm_original[r * n + j];
    derivative += determinant(work, n);
  }
  return {0.0, derivative};
}

}  // namespace chatterlab::delay_detail

namespace chatterlab {

Complex complex_determinant(Complex* a, std::size_t n) { return delay_detail::determinant(a, n); }

CharacteristicValue complex_determinant_and_derivative(Complex* m, Complex* dm, std::size_t n) {
  return delay_detail::determinant_and_derivative(m, dm, n);
}

}  // namespace chatterlab
