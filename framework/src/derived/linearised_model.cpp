// LinearisedModel (chatterlab/linearised_model.hpp): the linear system of a model written once,
// assembled from the Jacobian of its own physics. docs/derived_stability.md.
#include "chatterlab/linearised_model.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/derived_model.hpp"
#include "derived/surface_system.hpp"

namespace chatterlab {

using Eigen::Index;
using Eigen::MatrixXd;

namespace {

MatrixXd to_eigen(const JacobianMatrix& j) {
  MatrixXd out(static_cast<Index>(j.rows), static_cast<Index>(j.cols));
  for (std::size_t r = 0; r < j.rows; ++r)
    for (std::size_t c = 0; c < j.cols; ++c) out(static_cast<Index>(r), static_cast<Index>(c)) = j(r, c);
  return out;
}

}  // namespace

void surface_system_matrices(const SurfaceLayout& layout, const JacobianMatrix& jacobian_in, MatrixXd& a0,
                             std::vector<MatrixXd>& delayed) {
  const MatrixXd jacobian = to_eigen(jacobian_in);
  const auto n = static_cast<Index>(layout.states), r = static_cast<Index>(layout.regenerated.size());
  const Index size = n + r;
  // Variables: x (n), then S_r. Jacobian inputs: x, S_r(t - T_r); outputs: x', removed_r.
  a0 = MatrixXd::Zero(size, size);
  delayed.assign(static_cast<std::size_t>(r), MatrixXd::Zero(size, size));
  a0.topLeftCorner(n, n) = jacobian.topLeftCorner(n, n);             // x' from x
  a0.bottomLeftCorner(r, n) = jacobian.bottomLeftCorner(r, n);       // removed_r from x
  for (Index k = 0; k < r; ++k) {
    a0(n + k, n + k) = -1.0;                                         // 0 = -S_r(t) + ...
    MatrixXd& ak = delayed[static_cast<std::size_t>(k)];
    ak.col(n + k).head(n) = jacobian.col(n + k).head(n);             // x' from S_k(t - T_k)
    ak.col(n + k).tail(r) = jacobian.col(n + k).tail(r);             // removed_r from S_k(t - T_k)
    ak(n + k, n + k) += 1.0;                                         // ... + S_k(t - T_k)
  }
}

LinearDelaySystem surface_linear_system(const LinearisedModel& model, const ProcessPoint& point) {
  const SurfaceLayout layout = model.surface_layout();
  LinearDelaySystem system;
  const auto n = static_cast<Index>(layout.states), size = static_cast<Index>(layout.size());
  system.mass = MatrixXd::Zero(size, size);
  system.mass.topLeftCorner(n, n).setIdentity();
  std::vector<MatrixXd> delayed;
  surface_system_matrices(layout, model.jacobian(point), system.a0, delayed);
  for (std::size_t k = 0; k < delayed.size(); ++k) {
    const auto rotor = static_cast<std::size_t>(layout.regenerated[k]);
    const double rpm = point.speed_rpm[rotor] > 0.0 ? point.speed_rpm[rotor] : layout.nominal_speed_rpm[rotor];
    system.delayed.push_back({60.0 / rpm, std::move(delayed[k]), {}});
  }
  return system;
}

std::unique_ptr<CharacteristicFunction> derived_characteristic(const LinearisedModel& model, const ProcessPoint& point) {
  return std::make_unique<DelayCharacteristic>(surface_linear_system(model, point));
}

namespace derived_detail {

double state_block_frequency_hz(const JacobianMatrix& jacobian, std::size_t states) {
  if (states == 0) return 0.0;
  const auto n = static_cast<Index>(states);
  Eigen::EigenSolver<MatrixXd> solver(to_eigen(jacobian).topLeftCorner(n, n), false);
  if (solver.info() != Eigen::Success) return 0.0;
  double largest = 0.0;
  for (const auto& lambda : solver.eigenvalues()) largest = std::max(largest, std::abs(lambda));
  return largest / (2.0 * std::numbers::pi);
}

}  // namespace derived_detail

}  // namespace chatterlab
