#pragma once
// Internal to DelayCharacteristic: two ways to evaluate det Delta(s) and its derivative for a
// reduced system (delay/structure.hpp), equal up to a constant nonzero factor.
//
// DenseEvaluator: Delta(s) = s N(z) - A(z) filled entry by entry (sparse lists of the delayed
// matrices), rows and columns equilibrated by powers of two, LU with Jacobi's formula. General.
//
// ModalEvaluator: the Schur complement onto the delayed variables. The variables no delay acts on
// (I: G1's structural modes) enter Delta only through the delay-free pencil s E11 - A11; with its
// eigen-decomposition computed once,
//     det Delta = det(E11) prod_i (s - lambda_i) det R(s),
//     R(s) = sum_k z_k [ s F_k - G_k - sum_i N_ik / (s - lambda_i) ]      (z_0 = 1),
// a matrix of the size of the delayed variables (G1: the two surfaces), whose entries are sums of
// simple fractions over the modes (conjugate pairs evaluated together with real coefficients).
// The cost per evaluation is linear in the number of modes, like a hand-written modal form.
#include <optional>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "delay/structure.hpp"

namespace chatterlab::delay_detail {

class DenseEvaluator {
 public:
  explicit DenseEvaluator(const ReducedSystem& system);
  CharacteristicValue operator()(Complex s) const;
  std::size_t size() const { return n_; }
  // Delta(s) (row-major) of the equilibrated system, and (if dm) Delta'(s); with skip < number
  // of delays, delay `skip`'s term is left out (M0 of the chain polynomial det(M0 - C_k x)).
  void fill(Complex s, Complex* m, Complex* dm, std::size_t skip = static_cast<std::size_t>(-1)) const;
  // C_k(s) = A_k + s B_k of the equilibrated system (row-major): Delta = M0 - C_k e^{-tau_k s}.
  void delayed_coefficient(std::size_t k, Complex s, Complex* out) const;

 private:
  struct Entry {
    std::size_t index;  // row-major position
    double value;
  };
  struct Term {
    double delay_s;
    std::vector<Entry> a, b;  // nonzero entries of A_k and B_k
  };
  std::size_t n_;
  std::vector<double> mass_, a0_;
  std::vector<Term> terms_;
};

class ModalEvaluator {
 public:
  // nullopt when the Schur complement does not pay (few undelayed variables) or is not safe (a
  // singular E11, an ill-conditioned eigenvector basis).
  static std::optional<ModalEvaluator> make(const ReducedSystem& system);
  CharacteristicValue operator()(Complex s) const;
  std::size_t modes() const { return real_modes_.size() + pairs_.size() * 2; }
  std::size_t delayed_variables() const { return d_; }

 private:
  struct Fraction {
    std::size_t k;                      // z power (0: undelayed)
    std::vector<double> real, imag;     // N_ik (d x d, row-major): real and imaginary parts
  };
  struct RealMode {
    double lambda, scale;               // (s - lambda) / scale in the product
    std::vector<Fraction> fractions;    // imag parts zero
  };
  struct Pair {                         // lambda and its conjugate: Im lambda > 0
    double re, im, inverse_modulus_squared;
    std::vector<Fraction> fractions;    // of the member with Im > 0
  };
  std::size_t d_ = 0;
  std::vector<double> delays_;              // tau_k, k = 1..K (index k - 1)
  std::vector<std::vector<double>> f_, g_;  // F_k, G_k (k = 0..K), d x d row-major
  std::vector<RealMode> real_modes_;
  std::vector<Pair> pairs_;
};

}  // namespace chatterlab::delay_detail
