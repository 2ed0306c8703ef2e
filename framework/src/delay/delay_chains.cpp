#include "chatterlab/delay_chains.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// log z without clog's extra-precision path (z is finite and nonzero here).
Complex logarithm(Complex z) { return {0.5 * std::log(std::norm(z)), std::arg(z)}; }

}  // namespace

std::vector<Complex> unit_roots(std::size_t points) {
  std::vector<Complex> unit(points);
  for (std::size_t j = 0; j < points; ++j)
    unit[j] = std::polar(1.0, kTwoPi * static_cast<double>(j) / static_cast<double>(points));
  return unit;
}

void coefficients_from_unit_root_values(std::span<const Complex> values, std::span<const Complex> unit_roots,
                                        std::span<Complex> coefficients) {
  const std::size_t points = values.size();
  for (std::size_t k = 0; k < points; ++k) {
    Complex c = 0.0;
    for (std::size_t j = 0; j < points; ++j) c += values[j] * std::conj(unit_roots[(j * k) % points]);
    coefficients[k] = c / static_cast<double>(points);
  }
}

void nonzero_polynomial_roots(std::span<const Complex> coefficients, std::vector<Complex>& roots) {
  roots.clear();
  const std::size_t points = coefficients.size();
  if (points == 0) return;
  // (Squared magnitudes throughout: std::abs on complex numbers is glibc's slow hypot.)
  double largest = 0.0;
  for (std::size_t k = 0; k < points; ++k) largest = std::max(largest, std::norm(coefficients[k]));
  std::size_t degree = points - 1;
  while (degree > 0 && std::norm(coefficients[degree]) <= 1e-24 * largest) --degree;
  if (degree == 1) {
    roots.push_back(-coefficients[0] / coefficients[1]);
  } else if (degree == 2) {
    const Complex b = coefficients[1], disc = std::sqrt(b * b - 4.0 * coefficients[2] * coefficients[0]);
    const Complex q = -0.5 * (b + ((std::conj(b) * disc).real() >= 0.0 ? disc : -disc));
    if (q != Complex(0.0)) roots = {q / coefficients[2], coefficients[0] / q};
  } else if (degree > 2) {
    const auto d = static_cast<Eigen::Index>(degree);
    Eigen::MatrixXcd companion = Eigen::MatrixXcd::Zero(d, d);
    for (Eigen::Index i = 0; i < d; ++i) {
      companion(0, i) = -coefficients[degree - 1 - static_cast<std::size_t>(i)] / coefficients[degree];
      if (i + 1 < d) companion(i + 1, i) = 1.0;
    }
    Eigen::ComplexEigenSolver<Eigen::MatrixXcd> solver(companion, false);
    if (solver.info() == Eigen::Success)
      for (const auto& z : solver.eigenvalues()) roots.push_back(z);
  }
  std::erase_if(roots, [](Complex z) { return !(std::norm(z) > 0.0) || !std::isfinite(std::norm(z)); });
}

bool append_chain_guesses(double tau_s, double max_angular_frequency_rad_s, int fixed_point_steps,
                          const ChainFactors& chain_factors, std::vector<Complex>& guesses) {
  const long lattice_points = static_cast<long>(max_angular_frequency_rad_s * tau_s / kTwoPi) + 2;
  bool any_chain = false;
  std::vector<Complex> start_factors, factors;
  for (long m = 0; m < lattice_points; ++m) {
    const Complex lattice(0.0, kTwoPi * static_cast<double>(m));
    chain_factors(lattice / tau_s, start_factors);
    for (Complex z : start_factors) {
      Complex s = (lattice - logarithm(z)) / tau_s;
      for (int step = 0; step < fixed_point_steps; ++step) {
        chain_factors(s, factors);
        if (factors.empty()) break;
        // Follow the same chain: the factor nearest the previous one (relative distance).
        z = *std::min_element(factors.begin(), factors.end(), [&](Complex p, Complex q) {
          return std::norm(p / z - 1.0) < std::norm(q / z - 1.0);
        });
        s = (lattice - logarithm(z)) / tau_s;
      }
      if (std::isfinite(s.real()) && std::isfinite(s.imag())) guesses.push_back(s);
      any_chain = true;
    }
  }
  return any_chain;
}

}  // namespace chatterlab
