#pragma once
// Linear delay systems from equations written once in DDE-BIFTOOL's general form (sys_rhs,
// sys_tau, lhs_matrix): the linearisation at a steady state by forward-mode automatic
// differentiation (dual.hpp), as the matrices of delay_system.hpp. Grinding models with
// regenerated surfaces use derived_model.hpp instead. docs/derived_stability.md.
#include <span>
#include <vector>

#include "chatterlab/delay_system.hpp"
#include "chatterlab/dual.hpp"

namespace chatterlab {

// The general form (DDE-BIFTOOL's sys_rhs / sys_tau / lhs_matrix conventions): n states, constant
// delays tau_k, and
//   E x'(t) - sum_k B_k x'(t - tau_k) = f(x(t), x(t - tau_1), ..., x(t - tau_K)),
// f written once as a template:
//   struct MyDelayEquations {
//     std::size_t state_size() const;
//     std::vector<double> delays_s() const;
//     template <class S> void rhs(std::span<const S> x, std::span<const std::span<const S>> delayed,
//                                 std::span<S> out) const;
//   };
// with optional Eigen::MatrixXd mass_matrix() const and std::vector<Eigen::MatrixXd>
// neutral_matrices() const (one per delay, empty entries: none).
template <class E>
concept DelayEquations = requires(const E& e, std::span<const double> x, std::span<const std::span<const double>> xd,
                                  std::span<double> out, std::span<const Dual> dx,
                                  std::span<const std::span<const Dual>> dxd, std::span<Dual> dout) {
  { e.state_size() } -> std::convertible_to<std::size_t>;
  { e.delays_s() } -> std::convertible_to<std::vector<double>>;
  e.rhs(x, xd, out);
  e.rhs(dx, dxd, dout);
};

// The linearisation at the steady state x* (f(x*, ..., x*) = 0 is the caller's; see the test for
// Newton on it): A_0 = df/dx(t), A_k = df/dx(t - tau_k) by forward-mode differentiation.
template <DelayEquations E>
LinearDelaySystem linearise(const E& eqs, std::span<const double> steady_state) {
  const std::size_t n = eqs.state_size();
  const std::vector<double> delays = eqs.delays_s();
  const std::size_t k_count = delays.size();
  LinearDelaySystem system;
  system.a0 = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (double tau : delays) system.delayed.push_back({tau, system.a0, {}});
  std::vector<std::vector<Dual>> values(k_count + 1, std::vector<Dual>(n));
  std::vector<std::span<const Dual>> delayed_views;
  for (std::size_t k = 1; k <= k_count; ++k) delayed_views.emplace_back(values[k]);
  std::vector<Dual> out(n);
  for (std::size_t block = 0; block <= k_count; ++block) {
    for (std::size_t j = 0; j < n; ++j) {
      for (std::size_t b = 0; b <= k_count; ++b)
        for (std::size_t i = 0; i < n; ++i) values[b][i] = Dual(steady_state[i], b == block && i == j ? 1.0 : 0.0);
      std::fill(out.begin(), out.end(), Dual(0.0));
      eqs.rhs(std::span<const Dual>(values[0]), std::span<const std::span<const Dual>>(delayed_views), std::span<Dual>(out));
      Eigen::MatrixXd& target = block == 0 ? system.a0 : system.delayed[block - 1].matrix;
      for (std::size_t i = 0; i < n; ++i)
        target(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = out[i].derivative;
    }
  }
  if constexpr (requires { eqs.mass_matrix(); }) system.mass = eqs.mass_matrix();
  if constexpr (requires { eqs.neutral_matrices(); }) {
    const std::vector<Eigen::MatrixXd> b = eqs.neutral_matrices();
    for (std::size_t k = 0; k < b.size() && k < k_count; ++k) system.delayed[k].neutral_matrix = b[k];
  }
  return system;
}

}  // namespace chatterlab
