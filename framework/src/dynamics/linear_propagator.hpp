#pragma once
// Exact propagation of a model's LinearForm (chatterlab/dynamics.hpp) over the fixed-step
// engine's steps. On one contact side the state obeys dx/dt = A x + b f(t) with f the scalar
// forcing, known ahead of the state; over the step [t_k, t_k + h] f is taken as the cubic whose
// averages over four step-long cells ("nodes": [t_k - h, t_k], [t_k, t_k + h], .. [t_k + 2h,
// t_k + 3h]; the run's first step uses [t_k, t_k + h] .. [t_k + 3h, t_k + 4h]) equal f's exact
// averages there. Averages, not point values: a rough surface (random initial waviness is white
// noise at the surface grid) read at points would alias its fine structure into the band of the
// modes. With A = V diag(lambda) V^-1 (modal form) the solution is exact for that cubic:
//
//   z = V^-1 x,   z_i(t + d) = e^{lambda_i d} z_i(t) + beta_i sum_{m=0..3} p^(m)(t) d^(m+1) phi_(m+1)(lambda_i d)
//
// (beta = V^-1 b, p^(m) the forcing polynomial's derivatives, phi_j the exponential integrator
// functions). Whole steps use the same formula applied once to the unit vectors: the real
// matrices E (n x n) and W (n x 4) with x(t_k + h) = E x(t_k) + W f_nodes, i.e. n^2 + 4n
// multiply-adds per step. Pieces of a step (contact events, form changes) are propagated
// through the modal form directly.
#include <complex>
#include <cstddef>
#include <span>
#include <vector>

#include "chatterlab/dynamics.hpp"

namespace chatterlab::dynamics_detail {

// Which four step-long cells the forcing nodes average over (the header comment).
enum class ForcingNodes { centred, first_step };

// The forcing over a step: p(tau) = sum c_m (tau / h)^m, tau = t - t_k in [0, h].
struct ForcingCubic {
  double c[4] = {0.0, 0.0, 0.0, 0.0};
  double h = 1.0;
  double value(double tau) const {
    const double u = tau / h;
    return c[0] + u * (c[1] + u * (c[2] + u * c[3]));
  }
  double rate(double tau) const {
    const double u = tau / h;
    return (c[1] + u * (2.0 * c[2] + u * 3.0 * c[3])) / h;
  }
};

class LinearPropagator {
 public:
  // The form's two sides for steps of h; `scales` (the model's state scales for a unit
  // displacement) balance the matrix before its eigen-decomposition. ok() is false when a side's
  // matrix is not diagonalisable to working accuracy (defective or nearly so); the engine then
  // integrates by Runge-Kutta instead.
  LinearPropagator(const LinearForm& form, std::size_t n, double h, std::span<const double> scales);
  bool ok() const { return ok_; }
  const std::string& problem() const { return problem_; }

  // x_out = x(t_k + h) from x = x(t_k) (x_out may not alias x).
  void step(bool in_contact, ForcingNodes nodes, const double* x, const double forcing[4], double* x_out) const;
  // The cubic through the cell averages `forcing` over cells of h (once per step: pieces and
  // slopes use it).
  static ForcingCubic cubic(ForcingNodes nodes, const double forcing[4], double h);
  // x_out = x(t_k + b) from x = x(t_k + a), 0 <= a <= b <= h, under the step's forcing cubic.
  void piece(bool in_contact, const ForcingCubic& forcing, double a, double b, const double* x, double* x_out) const;
  // dx/dt = A x + b f.
  void derivative(bool in_contact, const double* x, double forcing, double* dx) const;
  // The slopes dx/dt and d2x/dt2 of a state after the forcing changes by df and its rate by
  // d_rate (the next step's cubic meets the previous one's value at their common end only to its
  // accuracy): dx/dt += b df, d2x/dt2 += A b df + b d_rate, without a matrix product.
  void reforce(bool in_contact, double df, double d_rate, double* dx, double* d2x) const;

 private:
  using Complex = std::complex<double>;
  struct Side {
    std::vector<double> a, b;               // the form's matrix and input
    // A's nonzero entries row by row (structural matrices are sparse: G1's modal matrix has
    // n/2 + 2 entries in half its rows), and A b.
    std::vector<std::size_t> row_start, column;
    std::vector<double> value, ab;
    std::vector<Complex> lambda, v, v_inv;  // eigenvalues, V and V^-1 (row-major, in x units)
    std::vector<Complex> beta;              // V^-1 b
    std::vector<double> e;                  // E, row-major n x n
    std::vector<double> w[2];               // W per node set, row-major n x 4
  };
  bool decompose(Side& side, std::span<const double> scales, const char* name);
  void modal_piece(const Side& side, const double c[4], double a, double b, const double* x, double* x_out) const;
  const Side& side(bool in_contact) const { return in_contact ? contact_ : free_; }

  std::size_t n_;
  double h_;
  Side contact_, free_;
  bool ok_ = true;
  std::string problem_;
  mutable std::vector<Complex> z_;  // scratch (a propagator belongs to one run)
};

// phi_1..phi_4 of z (phi_j(z) = sum_k z^k / (k + j)!), accurate for any z: a series with the
// stable downward recurrence phi_(j-1) = 1/(j-1)! + z phi_j for |z| < 1, e^z and the upward
// recurrence phi_(j+1) = (phi_j - 1/j!) / z beyond.
void phi_functions(std::complex<double> z, std::complex<double> phi[5]);

}  // namespace chatterlab::dynamics_detail
