#pragma once
// Internal to DelayCharacteristic (chatterlab/delay_system.hpp): checks, condensation, the split
// into differential and algebraic parts, the proven real-part bound, the difference operator's
// spectrum and the roots of a family of steady states. docs/derived_stability.md derives each.
#include <Eigen/Dense>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "chatterlab/delay_system.hpp"

namespace chatterlab::delay_detail {

// The system after the checks, with the undelayed algebraic variables that delay-free algebraic
// equations determine eliminated (a constant Schur complement: det Delta changes by a constant
// factor only). Square, size m <= n; neutral[k] is empty when delay k has no neutral term.
struct ReducedSystem {
  Eigen::MatrixXd mass, a0;
  std::vector<double> delays;
  std::vector<Eigen::MatrixXd> matrices, neutral;
  std::size_t condensed = 0;
  std::size_t size() const { return static_cast<std::size_t>(a0.rows()); }
};

// Throws InputError (messages name the matrix: "mass matrix E", "A_0", "delayed term 2: A_k").
ReducedSystem check_and_reduce(const LinearDelaySystem& system);

// The reduced system in coordinates where E = diag(I_r, 0): x = Q y, rows multiplied by P.
// Blocks d (differential, r) and a (algebraic, n - r); z-dependence per delay.
struct SplitSystem {
  std::size_t differential = 0, algebraic = 0;
  std::vector<double> delays;
  Eigen::MatrixXd a0_dd, a0_da, a0_ad, g0;  // g0 = A0_aa^{-1}
  std::vector<Eigen::MatrixXd> a_dd, a_da, a_ad, a_aa, b_dd;
  std::vector<bool> neutral_delay;  // A_k,aa != 0 or B_k != 0: the delay enters the difference operator
  Eigen::MatrixXd undelayed;        // S0 = A0_dd - A0_da G0 A0_ad (all delayed terms absent)
  bool neutral() const;
};

SplitSystem split(const ReducedSystem& system);

// Bound(sigma) of docs/derived_stability.md for a set of inner products on the differential and
// algebraic spaces: every root with Re s >= sigma has Re s <= Bound(sigma) and |s| <= Reach(sigma),
// provided the Neumann conditions hold on the polydisc |z_k| <= e^{-tau_k sigma}.
class RealPartBound {
 public:
  explicit RealPartBound(const SplitSystem& system);

  static constexpr double invalid = std::numeric_limits<double>::infinity();
  // min over the inner products; `invalid` where no inner product satisfies the conditions.
  double bound(double sigma) const;
  double reach(double sigma) const;
  // The smallest sigma with bound(sigma) <= sigma: no root has a larger real part (the fixed
  // point exists: bound is non-increasing in sigma and finite for large sigma).
  double proven_bound() const;
  // The smallest sigma where the difference operator is proven invertible on the polydisc (its
  // spectrum lies left of it); -inf when the system is retarded.
  double difference_operator_bound() const;

 private:
  struct Profile {
    double mu0 = 0.0, norm0 = 0.0, alpha0 = 0.0, gamma0 = 0.0;
    std::vector<double> dd, b, alpha, gamma, phi, q;
  };
  struct Terms {
    bool valid = false;
    double bound = 0.0, reach = 0.0;
  };
  Terms terms(const Profile& p, double sigma) const;
  double smallest(const std::function<bool(double)>& holds) const;

  std::vector<double> delays_;
  std::vector<Profile> profiles_;
  bool has_differential_ = true;
  bool neutral_ = false;
};

// Largest real part of the difference operator's spectrum, bracketed: [lower, upper]; upper from
// the Neumann condition (proven), lower attained (exact for a single neutral delay, else the
// largest real root on the ray z_k = e^{-tau_k sigma}; -inf when none was located).
struct DifferenceSpectrum {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = -std::numeric_limits<double>::infinity();
};
DifferenceSpectrum difference_spectrum(const SplitSystem& system, const RealPartBound& bound);

// s = 0 as the neutral root of a family of steady states: (A0 + sum A_k) v = 0. Declared only when
// semisimple (no Jordan chain: its multiplicity is then the kernel dimension). A one-dimensional
// purely algebraic family direction (E v = 0, B_k v = 0) repeats at the common lattice points of
// the delays acting on it (A_k v != 0).
struct FamilyRoots {
  int multiplicity_at_zero = 0;
  std::vector<double> lattice_delays_s;  // empty: s = 0 only
};
FamilyRoots family_roots(const ReducedSystem& system);

// Diagonal similarity d (powers of two) balancing the off-diagonal row and column norms of x
// (Osborne): diag(d) x diag(d)^{-1} is better conditioned for eigenvalue problems in physical units.
Eigen::VectorXd osborne(const Eigen::MatrixXd& x);

// Powers of two r, c with diag(r) |M| diag(c) balanced (Ruiz): exact rescaling of rows and columns.
void equilibrate(const Eigen::MatrixXd& magnitude, Eigen::VectorXd& rows, Eigen::VectorXd& columns);

}  // namespace chatterlab::delay_detail
