#pragma once
// A general linear delay-differential system given in the study (no C++ needed):
//
//   x'(t) = A0 x(t) + sum_k A_k x(t - tau_k),     E(s) = det(s I - A0 - sum_k A_k e^{-tau_k s}),
//
// or, with a mass matrix M (`mass`, may be singular: its zero rows are algebraic equations, as
// G1's surfaces) and neutral terms B_k (`delayed.neutral_matrix`, DDE-BIFTOOL's conventions),
//
//   M x'(t) - sum_k B_k x'(t - tau_k) = A0 x(t) + sum_k A_k x(t - tau_k),
//
// whose certified characteristic function is the general DelayCharacteristic (delay_system.hpp:
// real-part bound from the matrices, essential spectrum of neutral systems). Retarded systems
// without them keep the fast path below (LinearDdeCharacteristic).
//
// Used for systems that are not (yet) a model plugin and as the solver's known-answer testbed
// (DDE-BIFTOOL-style oscillator with delayed feedback). Docs: docs/models/linear_dde.md.
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

struct DelayedTerm {
  double delay_s = 0.0;
  std::vector<std::vector<double>> matrix;
  std::vector<std::vector<double>> neutral_matrix;  // B_k; empty: none
};

struct LinearDdeParameters {
  std::vector<std::vector<double>> a0;
  std::vector<DelayedTerm> delayed;
  std::vector<std::vector<double>> mass;  // M; empty: the identity
  // A mass matrix or a neutral term: the general (delay-differential-algebraic) route.
  bool general() const;
};

class LinearDdeCharacteristic final : public CharacteristicFunction {
 public:
  // Sizes must already be consistent (LinearDde's constructor checks them).
  explicit LinearDdeCharacteristic(const LinearDdeParameters& parameters);

  // det(M) and, by Jacobi's formula, det(M) tr(M^{-1} M'), M' = I + sum tau_k A_k e^{-tau_k s}.
  CharacteristicValue evaluate(Complex s) const override;
  void initial_guesses(double max_angular_frequency_rad_s,
                       std::vector<Complex>& guesses) const override;
  double real_part_bound() const override;
  double natural_frequency_scale_hz() const override;

 private:
  // M = sI - A0 - sum_{k != skip} A_k e^{-tau_k s} and (if dm) M' (row-major n x n).
  void fill(Complex s, Complex* m, Complex* dm, std::size_t skip) const;
  // Roots z of det(M0(s) - A z), A the longest delay's matrix: the chains' e^{-tau s} values.
  void chain_factors(Complex s, std::vector<Complex>& roots) const;

  std::size_t n_;
  std::vector<double> a0_;                 // row-major n x n
  std::vector<double> delays_;             // tau_k [s]
  std::vector<std::vector<double>> matrices_;  // A_k row-major
  std::vector<Complex> eigenvalues_;       // of A0 and of A0 + sum A_k (Im >= 0)
  double norm_bound_ = 0.0;                // ||A0|| + sum ||A_k|| (induced 1- or inf-norm)
  std::size_t longest_ = 0;                // index of the longest delay
  std::vector<Complex> unit_roots_;        // e^{2 pi j k/(n+1)}, k = 0..n
};

class LinearDde final : public Model {
 public:
  // Throws InputError when a0 is not square or a delayed matrix does not match its size.
  explicit LinearDde(const ParamValues& values);
  explicit LinearDde(LinearDdeParameters parameters);

  static PluginInfo info();

  std::unique_ptr<CharacteristicFunction> characteristic() const override;

 private:
  LinearDdeParameters parameters_;
};

}  // namespace chatterlab
