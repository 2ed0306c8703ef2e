#pragma once
// Retarded root chains of a delay system, for characteristic functions that want initial guesses
// on them (the framework's DelayCharacteristic, linear_dde's fast path). For the longest delay
// tau, a root s satisfies z = e^{-tau s} with z a root of det(M0(s) - C z), a polynomial in z
// ("chain factors"; M0: the system without that delay's term, C: its matrix), i.e.
// s = (2 pi j m - Log z(s)) / tau. For large tau the right side varies slowly with s, so a
// fixed-point step from the lattice point 2 pi j m / tau lands next to the root of chain m, and
// Newton on the characteristic function finishes.
#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

// The roots of unity e^{2 pi i j / points}, j = 0..points-1: where a polynomial of degree
// < points is sampled to recover its coefficients.
std::vector<Complex> unit_roots(std::size_t points);

// The coefficients of the polynomial of degree < values.size() whose values at unit_roots(points)
// are `values` (the inverse discrete Fourier transform: exact). `coefficients` has values.size()
// elements.
void coefficients_from_unit_root_values(std::span<const Complex> values, std::span<const Complex> unit_roots,
                                        std::span<Complex> coefficients);

// The finite nonzero roots z of sum_k coefficients[k] z^k, into `roots` (cleared first). Top
// coefficients that rounding left tiny (|c_k|^2 <= 1e-24 max |c|^2) do not count towards the
// degree; closed forms up to degree 2 (the quadratic without cancellation), companion-matrix
// eigenvalues beyond.
void nonzero_polynomial_roots(std::span<const Complex> coefficients, std::vector<Complex>& roots);

// The roots z of the chain polynomial at s, as nonzero_polynomial_roots returns them.
using ChainFactors = std::function<void(Complex s, std::vector<Complex>& factors)>;

// One guess per chain root of the band |Im s| <= max_angular_frequency_rad_s, appended to
// `guesses`: from each lattice point 2 pi j m / tau, `fixed_point_steps` steps of
// s = (2 pi j m - Log z) / tau, each following the same chain (the factor nearest the previous
// one). Returns false when the chain polynomial had no root at any lattice point (no delayed
// coupling in the longest delay's matrix).
bool append_chain_guesses(double tau_s, double max_angular_frequency_rad_s, int fixed_point_steps,
                          const ChainFactors& chain_factors, std::vector<Complex>& guesses);

}  // namespace chatterlab
