#pragma once
// Linear delay-differential(-algebraic) systems with constant delays and their certified
// characteristic function, in DDE-BIFTOOL's conventions (lhs_matrix M, sys_tau, the linearisation
// A_0 = df/dx(t), A_k = df/dx(t - tau_k)):
//
//   E x'(t) - sum_k B_k x'(t - tau_k) = A_0 x(t) + sum_k A_k x(t - tau_k),
//   Delta(s) = s (E - sum_k B_k e^{-s tau_k}) - A_0 - sum_k A_k e^{-s tau_k},   E(s) = det Delta(s).
//
// E (the mass matrix) may be singular: its zero rows are algebraic equations, and an algebraic
// equation with a delay (MODELS.md G1's surfaces, W(t) = W(t - T) + F/k) makes the system of
// neutral type: infinitely many roots in a vertical strip, one chain per difference-operator root.
// B_k are neutral terms (derivatives at delayed times). Docs: docs/derived_stability.md.
//
// DelayCharacteristic is the CharacteristicFunction of such a system, with everything the root
// search needs derived from the matrices:
//   - a real-part bound PROVEN from the matrices (Schur complement onto the differential part,
//     logarithmic norm of the undelayed system, Neumann bounds of the delayed terms on the
//     polydisc |e^{-s tau_k}| <= e^{-tau_k sigma}; see real_part_bound in the docs);
//   - the neutral roots of a family of steady states (s = 0 when A_0 + sum A_k is singular, and
//     the common lattice points of the delays acting on a purely algebraic family direction);
//   - initial guesses (eigenvalues of the undelayed and zero-delay systems, the lattice points of
//     every neutral delay with a local quadratic where two lattices nearly coincide, the retarded
//     chains of the longest delay);
//   - a certificate note: where the certificate is global (every root right of the contour lies
//     inside the band), and for neutral systems where the root chains beyond the band accumulate
//     (the spectrum of the difference operator, sup Re s bracketed).
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "chatterlab/characteristic.hpp"

namespace chatterlab {

struct DelayTerm {
  double delay_s = 0.0;
  Eigen::MatrixXd matrix;          // A_k: coefficient of x(t - tau_k); empty: zero
  Eigen::MatrixXd neutral_matrix;  // B_k: coefficient of x'(t - tau_k) on the left; empty: none
};

struct LinearDelaySystem {
  Eigen::MatrixXd mass;  // E; empty: the identity (an ordinary retarded or neutral DDE)
  Eigen::MatrixXd a0;    // A_0 (n x n)
  std::vector<DelayTerm> delayed;
};

struct DelayCharacteristicOptions {
  // Characteristic frequency [Hz] for the default search band; 0: from the matrices (the largest
  // eigenvalue modulus of the undelayed system and, where regular, of the zero-delay system).
  double natural_frequency_hz = 0.0;
};

// What the construction found out about the system (for the certificate, docs and tests).
struct DelaySystemSummary {
  std::size_t states = 0;        // n
  std::size_t differential = 0;  // rank of E
  std::size_t algebraic = 0;     // n - rank E
  std::size_t condensed = 0;     // undelayed algebraic variables eliminated before evaluation
  bool neutral = false;          // an algebraic equation with a delay, or a neutral term B_k
  double real_part_bound = 0.0;  // proven: no root has Re s above it
  // Neutral systems: the spectrum of the difference operator (root chains beyond the band
  // accumulate there) has its largest real part in [lower, upper]; upper is proven, lower is
  // attained (-inf: not located). Retarded systems: both -inf.
  double difference_spectrum_lower = 0.0, difference_spectrum_upper = 0.0;
  int family_roots_at_zero = 0;  // multiplicity of s = 0 excluded as a family of steady states
  std::vector<double> family_lattice_delays_s;  // delays whose common lattice repeats it
  std::string evaluation;        // how E(s) is evaluated, e.g. "modal Schur complement ..."
};

class DelayCharacteristic final : public CharacteristicFunction {
 public:
  // Throws InputError for inconsistent sizes, non-finite entries, a delay <= 0, a singular
  // algebraic part (index > 1: the algebraic equations do not determine the algebraic variables)
  // or neutral terms outside the differential part. Messages name the offending matrix.
  explicit DelayCharacteristic(const LinearDelaySystem& system,
                               const DelayCharacteristicOptions& options = {});
  ~DelayCharacteristic() override;
  DelayCharacteristic(const DelayCharacteristic&) = delete;
  DelayCharacteristic& operator=(const DelayCharacteristic&) = delete;

  CharacteristicValue evaluate(Complex s) const override;
  std::vector<Complex> neutral_roots(double max_angular_frequency_rad_s) const override;
  void initial_guesses(double max_angular_frequency_rad_s,
                       std::vector<Complex>& guesses) const override;
  double real_part_bound() const override;
  double natural_frequency_scale_hz() const override;
  std::string certificate_note(double certified_real_part, double band_rad_s) const override;

  const DelaySystemSummary& summary() const;
  // Delta(s) of the system as given (n x n), for tests and eigenvectors.
  Eigen::MatrixXcd matrix(Complex s) const;
  // The same determinant by dense LU of the reduced system (the reference route the fast modal
  // evaluation is tested against); equal to evaluate() up to a constant nonzero factor.
  CharacteristicValue evaluate_dense(Complex s) const;

  struct Impl;

 private:
  std::unique_ptr<const Impl> impl_;
};

}  // namespace chatterlab
