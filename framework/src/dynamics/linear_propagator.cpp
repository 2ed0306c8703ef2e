#include "dynamics/linear_propagator.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace chatterlab::dynamics_detail {

namespace {

using Complex = std::complex<double>;

// Eigenvector matrices worse conditioned than this (in the balanced coordinates) count as not
// diagonalisable: the modal formula would lose more than half the digits.
constexpr double kMaxCondition = 1e8;

// Monomial coefficients c (in u = tau / h) of the cubic whose averages over four cells of one
// step each equal the given cell values: c = M f. The cells are u in [-1, 0], [0, 1], [1, 2],
// [2, 3] (centred: the step and its neighbours) or [0, 1] .. [3, 4] (the run's first step).
// Rows are c_0..c_3, columns the cells.
struct CellInverse {
  double m[4][4];
  explicit CellInverse(double first_cell) {
    Eigen::Matrix4d averages;  // averages(j, m) = mean of u^m over cell j
    for (int j = 0; j < 4; ++j) {
      const double a = first_cell + j;
      for (int power = 0; power < 4; ++power)
        averages(j, power) = (std::pow(a + 1.0, power + 1) - std::pow(a, power + 1)) / (power + 1);
    }
    const Eigen::Matrix4d inverse = averages.inverse();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) m[i][j] = inverse(i, j);
  }
};
const CellInverse kCentred(-1.0), kFirst(0.0);

}  // namespace

void phi_functions(Complex z, Complex phi[5]) {
  constexpr double inverse_factorial[5] = {1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0};
  const double size2 = std::norm(z);  // |z|^2 without hypot (the engine calls this per mode and piece)
  if (size2 <= 4.0) {
    // phi_4 = (1/4!) (1 + z/5 (1 + z/6 (1 + ...))) by Horner, then downward (stable for |z| <= 2:
    // errors grow by at most 2 per step). Terms: the first neglected one, |z|^K / (K + 4)!, is below
    // 1e-17 relative for K = 10, 14, 21 at |z| <= 1/4, 1, 2.
    const int terms = size2 <= 0.0625 ? 10 : size2 <= 1.0 ? 14 : 21;
    Complex acc = 1.0;
    for (int k = terms; k >= 1; --k) acc = 1.0 + z * acc * (1.0 / static_cast<double>(k + 4));
    phi[4] = acc * inverse_factorial[4];
    for (int j = 4; j > 0; --j) phi[j - 1] = inverse_factorial[j - 1] + z * phi[j];
    return;
  }
  phi[0] = std::exp(z);
  for (int j = 0; j < 4; ++j) phi[j + 1] = (phi[j] - inverse_factorial[j]) / z;
}

LinearPropagator::LinearPropagator(const LinearForm& form, std::size_t n, double h, std::span<const double> scales)
    : n_(n), h_(h), z_(n) {
  auto check_size = [&](const std::vector<double>& v, std::size_t size, const char* what) {
    if (v.size() != size)
      throw std::logic_error(fmt::format("LinearForm::{} has {} entries, expected {} (state size {})", what,
                                         v.size(), size, n));
  };
  check_size(form.contact_matrix, n * n, "contact_matrix");
  check_size(form.free_matrix, n * n, "free_matrix");
  check_size(form.contact_input, n, "contact_input");
  check_size(form.free_input, n, "free_input");
  contact_.a = form.contact_matrix;
  contact_.b = form.contact_input;
  free_.a = form.free_matrix;
  free_.b = form.free_input;
  for (Side* side : {&contact_, &free_}) {
    side->row_start.assign(1, 0);
    side->ab.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        const double a = side->a[i * n + j];
        side->ab[i] += a * side->b[j];
        if (a == 0.0) continue;
        side->column.push_back(j);
        side->value.push_back(a);
      }
      side->row_start.push_back(side->column.size());
    }
  }
  if (!decompose(contact_, scales, "contact") || !decompose(free_, scales, "free")) {
    ok_ = false;
    return;
  }
  // Whole-step matrices: the modal formula applied to the unit vectors.
  std::vector<double> unit(n, 0.0), column(n);
  for (Side* s : {&contact_, &free_}) {
    s->e.assign(n * n, 0.0);
    const double no_forcing[4] = {0.0, 0.0, 0.0, 0.0};
    for (std::size_t j = 0; j < n; ++j) {
      unit[j] = 1.0;
      modal_piece(*s, no_forcing, 0.0, h, unit.data(), column.data());
      unit[j] = 0.0;
      for (std::size_t i = 0; i < n; ++i) s->e[i * n + j] = column[i];
    }
    for (ForcingNodes nodes : {ForcingNodes::centred, ForcingNodes::first_step}) {
      std::vector<double>& w = s->w[static_cast<int>(nodes)];
      w.assign(n * 4, 0.0);
      for (int j = 0; j < 4; ++j) {
        double forcing[4] = {0.0, 0.0, 0.0, 0.0};
        forcing[j] = 1.0;
        modal_piece(*s, cubic(nodes, forcing, h).c, 0.0, h, unit.data(), column.data());
        for (std::size_t i = 0; i < n; ++i) w[i * 4 + static_cast<std::size_t>(j)] = column[i];
      }
    }
  }
}

bool LinearPropagator::decompose(Side& side, std::span<const double> scales, const char* name) {
  const auto n = static_cast<Eigen::Index>(n_);
  // Balanced coordinates y = D^-1 x (D = the state scales): displacements and velocities of a
  // mode at w then enter with entries ~w, not w^2 next to 1.
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      a(i, j) = side.a[static_cast<std::size_t>(i * n + j)] * scales[static_cast<std::size_t>(j)] /
                scales[static_cast<std::size_t>(i)];
  Eigen::EigenSolver<Eigen::MatrixXd> solver(a, true);
  if (solver.info() != Eigen::Success) {
    problem_ = fmt::format("the {} matrix has no eigen-decomposition", name);
    return false;
  }
  const Eigen::MatrixXcd v = solver.eigenvectors();
  Eigen::FullPivLU<Eigen::MatrixXcd> lu(v);
  const Eigen::MatrixXcd v_inv = lu.inverse();
  const double condition = v.cwiseAbs().colwise().sum().maxCoeff() * v_inv.cwiseAbs().colwise().sum().maxCoeff();
  const double residual = (a.cast<Complex>() * v - v * solver.eigenvalues().asDiagonal()).norm();
  if (!lu.isInvertible() || !(condition < kMaxCondition) || !(residual <= 1e-10 * std::max(a.norm(), 1e-300))) {
    problem_ = fmt::format("the {} matrix is not diagonalisable to working accuracy (eigenvector condition "
                           "{:.3g}, residual {:.3g})", name, condition, residual);
    return false;
  }
  side.lambda.resize(n_);
  side.v.resize(n_ * n_);
  side.v_inv.resize(n_ * n_);
  side.beta.assign(n_, 0.0);
  for (Eigen::Index i = 0; i < n; ++i) {
    side.lambda[static_cast<std::size_t>(i)] = solver.eigenvalues()(i);
    for (Eigen::Index j = 0; j < n; ++j) {
      // Back to x units: V_x = D V_y, V_x^-1 = V_y^-1 D^-1.
      side.v[static_cast<std::size_t>(i * n + j)] = v(i, j) * scales[static_cast<std::size_t>(i)];
      side.v_inv[static_cast<std::size_t>(i * n + j)] = v_inv(i, j) / scales[static_cast<std::size_t>(j)];
    }
  }
  for (std::size_t i = 0; i < n_; ++i)
    for (std::size_t j = 0; j < n_; ++j) side.beta[i] += side.v_inv[i * n_ + j] * side.b[j];
  return true;
}

ForcingCubic LinearPropagator::cubic(ForcingNodes nodes, const double forcing[4], double h) {
  const auto& m = (nodes == ForcingNodes::centred ? kCentred : kFirst).m;
  ForcingCubic out;
  out.h = h;
  for (int i = 0; i < 4; ++i)
    out.c[i] = m[i][0] * forcing[0] + m[i][1] * forcing[1] + m[i][2] * forcing[2] + m[i][3] * forcing[3];
  return out;
}

void LinearPropagator::modal_piece(const Side& side, const double c[4], double a, double b, const double* x,
                                   double* x_out) const {
  const double d = b - a, s = a / h_;
  // Taylor coefficients of the forcing at a: p^(m)(a) d^(m+1) (the factors of phi_(m+1)).
  const double q[4] = {(c[0] + s * (c[1] + s * (c[2] + s * c[3]))) * d,
                       (c[1] + s * (2.0 * c[2] + s * 3.0 * c[3])) / h_ * d * d,
                       (2.0 * c[2] + 6.0 * c[3] * s) / (h_ * h_) * d * d * d,
                       6.0 * c[3] / (h_ * h_ * h_) * d * d * d * d};
  Complex phi[5];
  for (std::size_t i = 0; i < n_; ++i) {
    Complex zi = 0.0;
    const Complex* row = &side.v_inv[i * n_];
    for (std::size_t j = 0; j < n_; ++j) zi += row[j] * x[j];
    phi_functions(side.lambda[i] * d, phi);
    z_[i] = phi[0] * zi + side.beta[i] * (q[0] * phi[1] + q[1] * phi[2] + q[2] * phi[3] + q[3] * phi[4]);
  }
  for (std::size_t i = 0; i < n_; ++i) {
    double sum = 0.0;
    const Complex* row = &side.v[i * n_];
    for (std::size_t j = 0; j < n_; ++j) sum += row[j].real() * z_[j].real() - row[j].imag() * z_[j].imag();
    x_out[i] = sum;
  }
}

void LinearPropagator::step(bool in_contact, ForcingNodes nodes, const double* x, const double forcing[4],
                            double* x_out) const {
  const Side& s = side(in_contact);
  const double* w = s.w[static_cast<int>(nodes)].data();
  for (std::size_t i = 0; i < n_; ++i) {
    const double* e = &s.e[i * n_];
    double sum = w[4 * i] * forcing[0] + w[4 * i + 1] * forcing[1] + w[4 * i + 2] * forcing[2] + w[4 * i + 3] * forcing[3];
    for (std::size_t j = 0; j < n_; ++j) sum += e[j] * x[j];
    x_out[i] = sum;
  }
}

void LinearPropagator::piece(bool in_contact, const ForcingCubic& forcing, double a, double b, const double* x,
                             double* x_out) const {
  modal_piece(side(in_contact), forcing.c, a, b, x, x_out);
}

void LinearPropagator::derivative(bool in_contact, const double* x, double forcing, double* dx) const {
  const Side& s = side(in_contact);
  for (std::size_t i = 0; i < n_; ++i) {
    double sum = s.b[i] * forcing;
    for (std::size_t k = s.row_start[i]; k < s.row_start[i + 1]; ++k) sum += s.value[k] * x[s.column[k]];
    dx[i] = sum;
  }
}

void LinearPropagator::reforce(bool in_contact, double df, double d_rate, double* dx, double* d2x) const {
  const Side& s = side(in_contact);
  for (std::size_t i = 0; i < n_; ++i) {
    dx[i] += s.b[i] * df;
    d2x[i] += s.ab[i] * df + s.b[i] * d_rate;
  }
}

}  // namespace chatterlab::dynamics_detail
