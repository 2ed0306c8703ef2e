// Floquet growth rates by semi-discretisation (chatterlab/floquet.hpp; Insperger & Stepan 2002,
// 2004, 2011). docs/derived_stability.md derives the step map.
#include "chatterlab/floquet.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>
#include <unsupported/Eigen/MatrixFunctions>

#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Cubic Lagrange basis on the nodes 0, 1, 2, 3.
std::array<double, 4> lagrange_at(double theta) {
  const double t0 = theta, t1 = theta - 1.0, t2 = theta - 2.0, t3 = theta - 3.0;
  return {-t1 * t2 * t3 / 6.0, t0 * t2 * t3 / 2.0, -t0 * t1 * t3 / 2.0, t0 * t1 * t2 / 6.0};
}

// The same basis along theta = a + b xi, as polynomials in xi: out[l][q] multiplies xi^q.
std::array<std::array<double, 4>, 4> lagrange_along(double a, double b) {
  std::array<std::array<double, 4>, 4> out{};
  for (int l = 0; l < 4; ++l) {
    std::array<double, 4> poly{1.0, 0.0, 0.0, 0.0};
    double denominator = 1.0;
    int degree = 0;
    for (int m = 0; m < 4; ++m) {
      if (m == l) continue;
      // poly *= (a - m) + b xi
      const double c0 = a - m;
      for (int q = degree + 1; q >= 0; --q) {
        double v = c0 * poly[static_cast<std::size_t>(q)];
        if (q > 0) v += b * poly[static_cast<std::size_t>(q - 1)];
        poly[static_cast<std::size_t>(q)] = v;
      }
      ++degree;
      denominator *= l - m;
    }
    for (int q = 0; q < 4; ++q) out[static_cast<std::size_t>(l)][static_cast<std::size_t>(q)] = poly[static_cast<std::size_t>(q)] / denominator;
  }
  return out;
}

MatrixXd take(const MatrixXd& m, const std::vector<Index>& rows, const std::vector<Index>& cols) {
  MatrixXd out(static_cast<Index>(rows.size()), static_cast<Index>(cols.size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < cols.size(); ++j) out(static_cast<Index>(i), static_cast<Index>(j)) = m(rows[i], cols[j]);
  return out;
}

// One level of the semi-discretisation: N steps per period. The step maps (the delays' revolution
// solves, the eliminations, the exponentials and the interpolation weights) are built once; the
// monodromy is then applied to blocks of vectors: all unit vectors for the dense matrix, one
// vector at a time for the Krylov solve, which needs a few dozen products instead of dim.
class Discretisation {
 public:
  // `coarser_delays`: the half-step delays of the level with steps / 2 (its grid is every other
  // point of this one), or null.
  Discretisation(const PeriodicDelaySystem& system, int steps, const std::vector<Index>& delayed_columns,
                 const std::vector<std::vector<double>>* coarser_delays = nullptr);
  Index dimension() const { return d_ + ring_ * nh_; }
  // tau_k(j h / 2), j = 0 .. 2 N, per delay k.
  const std::vector<std::vector<double>>& half_step_delays() const { return tau_; }
  // A vector of the level with twice the step (its samples every other one of this level's; the
  // ones between interpolated linearly) in this level's layout: a start vector for Arnoldi.
  Eigen::VectorXd refine(const Eigen::VectorXd& coarse) const;
  // out = M^power x for the columns of x (dimension x k).
  void apply(const MatrixXd& x, MatrixXd& out, int power = 1) const;
  MatrixXd monodromy() const {
    MatrixXd m;
    apply(MatrixXd::Identity(dimension(), dimension()), m);
    return m;
  }

 private:
  // The undelayed elimination at time t: S = A_dd - A_da A_aa^{-1} A_ad and the delayed inputs
  // C_k = A_k,dH - A_da A_aa^{-1} A_k,aH of the differential part; L, M_k of the algebraic part.
  struct Blocks {
    MatrixXd s, l;
    std::vector<MatrixXd> c, m;
  };
  // What a step applies, shared by the steps whose coefficients are the same (G1 under a speed
  // modulation: only the delays vary, so one set serves the whole period). One matrix per step
  // half, so that a step is two small products:
  //   x_next = [e^{S h}, Gamma_0 C_0, .., Gamma_3 C_0, Gamma_0 C_1, ..] [x; u_00; ..; u_30; u_01; ..]
  //   y_end  = [L, M_0, M_1, ..] [x_next; v_0; v_1; ..]
  // with Gamma_q = int_0^h e^{S (h - u)} (u/h)^q du, u_qk the history combined with the
  // stencil's weights of power q along delay k, v_k the history at the step end's delayed argument.
  struct MidOperators {
    MatrixXd step;  // d x (d + 4 nh K)
  };
  struct EndOperators {
    MatrixXd step;  // na x (d + nh K)
  };
  // Per step and delay: the stencil's first sample and the cubic weights along the delayed
  // argument (mid: polynomial in the step's fraction, by power; end: at the step end).
  struct DelayStep {
    Index first_mid = 0, first_end = 0;
    std::array<std::array<double, 4>, 4> mid{};  // mid[power q][stencil l]
    std::array<double, 4> end{};
  };
  // The blocks at t, reused while the coefficients stay the same (compared with the previous
  // call of the same cache).
  struct BlockCache {
    MatrixXd a0, next_a0;
    std::vector<MatrixXd> ak, next_ak;
    Blocks blocks;
    bool valid = false;
  };
  bool update_blocks(double t, BlockCache& cache) const;  // true when the blocks changed
  template <bool kOneColumn>
  void apply_columns(const MatrixXd& x, MatrixXd& out, int power) const;
  MidOperators mid_operators(const Blocks& b) const;

  const PeriodicDelaySystem& system_;
  int steps_;
  double h_;
  Index d_ = 0, na_ = 0, nh_ = 0, ring_ = 0;
  std::size_t delay_count_ = 0;
  std::vector<Index> diff_, alg_, delayed_;  // variable indices
  std::vector<Index> delayed_rows_in_d_, delayed_rows_in_a_;  // position of each delayed variable (-1: not there)
  std::vector<MidOperators> mids_;
  std::vector<EndOperators> ends_;
  std::vector<std::uint32_t> mid_of_step_, end_of_step_;
  std::vector<DelayStep> delay_steps_;  // [step * delay_count + k]
  std::vector<std::vector<double>> tau_;
};

// c (rows(a) x k, row-major) = (or +=) a * b (b: cols(a) x k, row-major). The blocks are tiny (a
// few states) and k runs from 1 (a Krylov vector) to the dimension (the dense monodromy): plain
// loops with the long, contiguous index inside, and no loop at all for one column.
template <bool kOneColumn>
inline void multiply_rows(const MatrixXd& a, const double* b, double* c, Index k, bool accumulate) {
  if constexpr (kOneColumn) k = 1;
  const Index rows = a.rows(), cols = a.cols();
  const double* a_data = a.data();  // column-major
  for (Index i = 0; i < rows; ++i) {
    double* ci = c + i * k;
    if constexpr (kOneColumn) {
      double sum = accumulate ? *ci : 0.0;
      for (Index m = 0; m < cols; ++m) sum += a_data[m * rows + i] * b[m];
      *ci = sum;
    } else {
      if (!accumulate) std::fill(ci, ci + k, 0.0);
      for (Index m = 0; m < cols; ++m) {
        const double aim = a_data[m * rows + i];
        const double* bm = b + m * k;
        for (Index j = 0; j < k; ++j) ci[j] += aim * bm[j];
      }
    }
  }
}

Discretisation::Discretisation(const PeriodicDelaySystem& system, int steps, const std::vector<Index>& delayed_columns,
                               const std::vector<std::vector<double>>* coarser_delays)
    : system_(system), steps_(steps), h_(system.period_s() / steps), delayed_(delayed_columns) {
  const std::vector<bool> differential = system.differential();
  for (std::size_t i = 0; i < differential.size(); ++i) (differential[i] ? diff_ : alg_).push_back(static_cast<Index>(i));
  d_ = static_cast<Index>(diff_.size());
  na_ = static_cast<Index>(alg_.size());
  nh_ = static_cast<Index>(delayed_.size());
  delay_count_ = system.delay_count();
  for (Index v : delayed_) {
    const auto in_d = std::find(diff_.begin(), diff_.end(), v), in_a = std::find(alg_.begin(), alg_.end(), v);
    delayed_rows_in_d_.push_back(in_d != diff_.end() ? static_cast<Index>(in_d - diff_.begin()) : -1);
    delayed_rows_in_a_.push_back(in_a != alg_.end() ? static_cast<Index>(in_a - alg_.begin()) : -1);
  }
  // Samples back to the oldest a step can reach: tau_max / h plus the stencil and one spare.
  ring_ = static_cast<Index>(std::ceil(system.max_delay_s() / h_)) + 4;

  // The step maps of one period. Sample index j holds the delayed variables at t = j h.
  BlockCache mid_cache, end_cache;
  // tau_k at every half step, t = j h / 2 (j = 0 .. 2 N); the even j from the coarser level.
  const std::size_t points = static_cast<std::size_t>(2 * steps_ + 1);
  const bool halves = coarser_delays && coarser_delays->size() == delay_count_ && steps_ % 2 == 0 &&
                      std::all_of(coarser_delays->begin(), coarser_delays->end(),
                                  [&](const std::vector<double>& c) { return 2 * c.size() - 1 == points; });
  std::vector<double> times;
  for (std::size_t j = halves ? 1 : 0; j < points; j += halves ? 2 : 1) times.push_back(0.5 * h_ * static_cast<double>(j));
  tau_.resize(delay_count_);
  std::vector<double> solved;
  for (std::size_t k = 0; k < delay_count_; ++k) {
    system_.delays_s(k, times, solved);
    if (!halves) {
      tau_[k] = solved;
      continue;
    }
    tau_[k].resize(points);
    for (std::size_t j = 0; j < points; ++j) tau_[k][j] = j % 2 == 0 ? (*coarser_delays)[k][j / 2] : solved[j / 2];
  }
  const std::vector<std::vector<double>>& tau = tau_;
  delay_steps_.resize(static_cast<std::size_t>(steps_) * delay_count_);
  for (int i = 0; i < steps_; ++i) {
    const double t_mid = (i + 0.5) * h_, t_end = (i + 1) * h_;
    if (update_blocks(t_mid, mid_cache)) mids_.push_back(mid_operators(mid_cache.blocks));
    mid_of_step_.push_back(static_cast<std::uint32_t>(mids_.size() - 1));
    for (std::size_t k = 0; k < delay_count_; ++k) {
      DelayStep& step = delay_steps_[static_cast<std::size_t>(i) * delay_count_ + k];
      const std::size_t at = 2 * static_cast<std::size_t>(i);
      const double tau_start = tau[k][at], tau_mid = tau[k][at + 1], tau_end = tau[k][at + 2];
      // Delayed argument t - tau(t) in samples, linear over the step: b(xi) = b_mid + (xi - 1/2) rho.
      const double rho = 1.0 - (tau_end - tau_start) / h_;
      const double b_mid = i + 0.5 - tau_mid / h_;
      const Index c = static_cast<Index>(std::floor(b_mid));
      const auto basis = lagrange_along(b_mid - static_cast<double>(c) + 1.0 - 0.5 * rho, rho);
      step.first_mid = c - 1;
      for (std::size_t l = 0; l < 4; ++l)
        for (std::size_t q = 0; q < 4; ++q) step.mid[q][l] = basis[l][q];
      // Algebraic variables at the step end read the history at t_end - tau(t_end).
      const double b = (i + 1) - tau_end / h_;
      const Index c_end = static_cast<Index>(std::floor(b));
      step.first_end = c_end - 1;
      step.end = lagrange_at(b - static_cast<double>(c_end) + 1.0);
    }
    if (na_ > 0) {
      if (update_blocks(t_end, end_cache)) {
        const Blocks& b = end_cache.blocks;
        EndOperators end{MatrixXd(na_, d_ + nh_ * static_cast<Index>(delay_count_))};
        end.step.leftCols(d_) = b.l;
        for (std::size_t k = 0; k < delay_count_; ++k) end.step.middleCols(d_ + nh_ * static_cast<Index>(k), nh_) = b.m[k];
        ends_.push_back(std::move(end));
      }
      end_of_step_.push_back(static_cast<std::uint32_t>(ends_.size() - 1));
    }
  }
}

bool Discretisation::update_blocks(double t, BlockCache& cache) const {
  system_.coefficients(t, cache.next_a0, cache.next_ak);
  if (cache.valid && cache.next_a0 == cache.a0 && cache.next_ak == cache.ak) return false;
  cache.valid = false;  // until the new blocks are complete (an exception leaves none)
  cache.a0.swap(cache.next_a0);
  cache.ak.swap(cache.next_ak);
  const MatrixXd& a0 = cache.a0;
  const std::vector<MatrixXd>& ak = cache.ak;
  Blocks& b = cache.blocks;
  b = Blocks{};
  const MatrixXd a_dd = take(a0, diff_, diff_), a_da = take(a0, diff_, alg_), a_ad = take(a0, alg_, diff_);
  MatrixXd solve_ad, elimination;  // A_aa^{-1} A_ad and A_da A_aa^{-1}
  Eigen::PartialPivLU<MatrixXd> lu;
  if (!alg_.empty()) {
    lu.compute(take(a0, alg_, alg_));
    if (!(lu.rcond() > 1e-14))
      throw PointFailure(fmt::format("Floquet: the algebraic equations are singular at t = {:.6g} s", t));
    solve_ad = lu.solve(a_ad);
    elimination = lu.solve(MatrixXd::Identity(na_, na_));
    elimination = a_da * elimination;
    b.s = a_dd - a_da * solve_ad;
    b.l = -solve_ad;
  } else {
    b.s = a_dd;
  }
  for (std::size_t k = 0; k < ak.size(); ++k) {
    // Columns outside the delayed set must stay zero (the set is fixed per level).
    for (Index j = 0; j < ak[k].cols(); ++j)
      if (std::find(delayed_.begin(), delayed_.end(), j) == delayed_.end() && !ak[k].col(j).isZero(0.0))
        throw PointFailure(fmt::format("Floquet: variable {} becomes delayed at t = {:.6g} s only", j, t));
    const MatrixXd dh = take(ak[k], diff_, delayed_);
    if (alg_.empty()) {
      b.c.push_back(dh);
    } else {
      const MatrixXd ah = take(ak[k], alg_, delayed_);
      b.c.push_back(dh - elimination * ah);
      b.m.push_back(-lu.solve(ah));
    }
  }
  cache.valid = true;
  return true;
}

// e^{Z} and the phi functions phi_j(Z) = sum_k Z^k/(k+j)! from one exponential of the augmented
// block matrix [[Z, I, 0, 0, 0], [0, 0, I, 0, 0], ..., [0, ...]]: its first block row is
// [e^Z, phi_1, phi_2, phi_3, phi_4]; int_0^h e^{S(h-u)} (u/h)^q du = h q! phi_{q+1}(S h).
Discretisation::MidOperators Discretisation::mid_operators(const Blocks& b) const {
  const Index n = d_;
  MatrixXd augmented = MatrixXd::Zero(5 * n, 5 * n);
  augmented.topLeftCorner(n, n) = b.s * h_;
  for (Index j = 0; j < 4; ++j) augmented.block(j * n, (j + 1) * n, n, n).setIdentity();
  const MatrixXd e = augmented.exp();
  MidOperators out{MatrixXd(n, n + 4 * nh_ * static_cast<Index>(b.c.size()))};
  out.step.leftCols(n) = e.topLeftCorner(n, n);
  double factorial = 1.0;
  for (Index q = 0; q < 4; ++q) {
    if (q > 0) factorial *= static_cast<double>(q);
    const MatrixXd gamma = h_ * factorial * e.block(0, (q + 1) * n, n, n);
    for (std::size_t k = 0; k < b.c.size(); ++k)
      out.step.middleCols(n + (4 * static_cast<Index>(k) + q) * nh_, nh_) = gamma * b.c[k];
  }
  return out;
}

Eigen::VectorXd Discretisation::refine(const Eigen::VectorXd& coarse) const {
  const Index coarse_ring = (coarse.size() - d_) / nh_;
  Eigen::VectorXd out(dimension());
  out.head(d_) = coarse.head(d_);
  auto coarse_sample = [&](Index s) { return coarse.segment(d_ + std::min(s, coarse_ring - 1) * nh_, nh_); };
  for (Index s = 0; s < ring_; ++s)  // this level's sample s is the coarse one at s / 2
    out.segment(d_ + s * nh_, nh_) =
        s % 2 == 0 ? Eigen::VectorXd(coarse_sample(s / 2)) : Eigen::VectorXd(0.5 * (coarse_sample(s / 2) + coarse_sample(s / 2 + 1)));
  return out;
}

void Discretisation::apply(const MatrixXd& x, MatrixXd& out, int power) const {
  if (x.cols() == 1) apply_columns<true>(x, out, power);
  else apply_columns<false>(x, out, power);
}

template <bool kOneColumn>
void Discretisation::apply_columns(const MatrixXd& x, MatrixXd& out, int power) const {
  const Index k = kOneColumn ? 1 : x.cols(), dim = dimension();
  const Index block = nh_ * k, delays = static_cast<Index>(delay_count_);
  // mid_in = [x; u_qk ...] and end_in = [x_next; v_k ...] (row-major, k columns); the state x is
  // the first d rows of mid_in.
  std::vector<double> mid_in(static_cast<std::size_t>((d_ + 4 * nh_ * delays) * k));
  std::vector<double> end_in(static_cast<std::size_t>((d_ + nh_ * delays) * k));
  std::vector<double> history(static_cast<std::size_t>(ring_ * block)), algebraic(static_cast<std::size_t>(na_ * k));
  double* state = mid_in.data();
  double* next = end_in.data();
  // Sample index `now + offset` (-ring < offset <= 1) in the ring, `now_position` = now mod ring.
  auto sample_at = [&](Index now_position, Index offset) {
    Index position = now_position + offset;
    if (position < 0) position += ring_;
    else if (position >= ring_) position -= ring_;
    return history.data() + position * block;
  };
  for (Index r = 0; r < d_; ++r)
    for (Index j = 0; j < k; ++j) state[r * k + j] = x(r, j);
  for (Index s = 0; s < ring_; ++s)  // entry d + s nh + r: sample index -s
    for (Index r = 0; r < nh_; ++r)
      for (Index j = 0; j < k; ++j) sample_at(0, -s)[r * k + j] = x(d_ + s * nh_ + r, j);
  Index now_position = 0;  // the current step's sample index mod ring
  for (int p = 0; p < power; ++p) {
    for (int i = 0; i < steps_; ++i) {
      const DelayStep* steps = &delay_steps_[static_cast<std::size_t>(i) * delay_count_];
      for (Index kk = 0; kk < delays; ++kk) {
        // u_qk = sum_l w[q][l] s_l (written once per entry: no accumulation through memory)
        double* u = state + (d_ + 4 * kk * nh_) * k;
        const Index first = steps[kk].first_mid - i;
        const double *s0 = sample_at(now_position, first), *s1 = sample_at(now_position, first + 1),
                     *s2 = sample_at(now_position, first + 2), *s3 = sample_at(now_position, first + 3);
        const auto& w = steps[kk].mid;
        for (Index e = 0; e < block; ++e) {
          const double a = s0[e], b = s1[e], c = s2[e], f = s3[e];
          for (std::size_t q = 0; q < 4; ++q)
            u[static_cast<Index>(q) * block + e] = w[q][0] * a + w[q][1] * b + w[q][2] * c + w[q][3] * f;
        }
      }
      multiply_rows<kOneColumn>(mids_[mid_of_step_[static_cast<std::size_t>(i)]].step, state, next, k, false);
      // Algebraic variables at the step end, from the new differential state and the history.
      if (na_ > 0) {
        for (Index kk = 0; kk < delays; ++kk) {
          double* v = next + (d_ + kk * nh_) * k;
          const Index first = steps[kk].first_end - i;
          const double *s0 = sample_at(now_position, first), *s1 = sample_at(now_position, first + 1),
                       *s2 = sample_at(now_position, first + 2), *s3 = sample_at(now_position, first + 3);
          const auto& w = steps[kk].end;
          for (Index e = 0; e < block; ++e) v[e] = w[0] * s0[e] + w[1] * s1[e] + w[2] * s2[e] + w[3] * s3[e];
        }
        multiply_rows<kOneColumn>(ends_[end_of_step_[static_cast<std::size_t>(i)]].step, next, algebraic.data(), k, false);
      }
      std::copy(next, next + d_ * k, state);
      double* fresh = sample_at(now_position, 1);
      for (Index r = 0; r < nh_; ++r) {
        const std::size_t ri = static_cast<std::size_t>(r);
        const double* from = delayed_rows_in_d_[ri] >= 0 ? state + delayed_rows_in_d_[ri] * k
                                                         : algebraic.data() + delayed_rows_in_a_[ri] * k;
        std::copy(from, from + k, fresh + r * k);
      }
      if (++now_position == ring_) now_position = 0;
    }
  }
  out.resize(dim, k);
  for (Index r = 0; r < d_; ++r)
    for (Index j = 0; j < k; ++j) out(r, j) = state[static_cast<std::size_t>(r * k + j)];
  for (Index s = 0; s < ring_; ++s)
    for (Index r = 0; r < nh_; ++r)
      for (Index j = 0; j < k; ++j) out(d_ + s * nh_ + r, j) = sample_at(now_position, -s)[r * k + j];
}

struct Level {
  int steps = 0;
  std::size_t dimension = 0;
  Complex multiplier;
  double growth = 0.0;
  double eigen_error = 0.0;  // residual bound of the Krylov solve on the growth rate [1/s]
  int excluded = 0;
  std::string eigen_route;
  Eigen::VectorXd dominant_vector;  // a real vector of the dominant multiplier's invariant subspace (Krylov only)
  std::vector<std::vector<double>> delays;  // the half-step delays, for the next level
};

// A multiplier of a family of steady states: within 1e-6 of 1.
constexpr double kFamilyDistance = 1e-6;
// The Krylov solve works on M^p over at least this many seconds, so that the dominant multiplier
// stands out from the rest by e^{(sigma_1 - sigma_2) p T} per product even for short periods.
constexpr double kKrylovHorizon_s = 0.5;
constexpr Index kKrylovMaxVectors = 80;
constexpr double kKrylovResidual = 1e-12;  // relative residual of the accepted Ritz pair

// The dominant multiplier from the full spectrum of the dense monodromy (the reference the Krylov
// solve is tested against, and its fallback).
void dense_dominant(const Discretisation& discretisation, const PeriodicDelaySystem& system, Level& level) {
  const MatrixXd m = discretisation.monodromy();
  Eigen::EigenSolver<MatrixXd> solver(m, false);
  if (solver.info() != Eigen::Success) throw PointFailure("Floquet: the eigenvalue solver of the monodromy failed");
  std::vector<Complex> mu(solver.eigenvalues().data(), solver.eigenvalues().data() + solver.eigenvalues().size());
  // A family of steady states is an exact multiplier 1 (a constant history): excluded.
  for (int f = 0; f < system.family_multipliers() && !mu.empty(); ++f) {
    auto nearest = std::min_element(mu.begin(), mu.end(), [](Complex a, Complex b) { return std::abs(a - 1.0) < std::abs(b - 1.0); });
    if (std::abs(*nearest - 1.0) > kFamilyDistance) break;
    mu.erase(nearest);
    ++level.excluded;
  }
  if (mu.empty()) throw PointFailure("Floquet: no multiplier left");
  Complex best = 0.0;
  for (Complex z : mu)
    if (std::abs(z) > std::abs(best) * (1.0 + 1e-12) || (std::abs(z) >= std::abs(best) * (1.0 - 1e-12) && z.imag() > best.imag()))
      best = z;
  level.multiplier = Complex(best.real(), std::abs(best.imag()));
  level.growth = std::log(std::abs(best)) / system.period_s();
  level.eigen_error = 0.0;
  level.eigen_route = fmt::format("dense eigenvalues of the {}-dimensional monodromy", m.rows());
}

// The dominant multiplier by Arnoldi's method on P = M^p (matrix-free: each product runs the
// step maps over p periods, O(steps) instead of the O(dim^3) dense solve). Ritz values of P are
// checked every few vectors; the accepted one is the largest in modulus after the family
// multipliers (|theta - 1| small, themselves converged), with residual |h_{m+1,m} y_m| <=
// kKrylovResidual |theta|. Its multiplier is the Rayleigh quotient of the Ritz vector under M.
// False when the Krylov space reaches its limit unconverged (the caller solves densely).
// `start`: a start vector (the coarser level's dominant vector refined), else a fixed random one.
bool krylov_dominant(const Discretisation& discretisation, const PeriodicDelaySystem& system, const Eigen::VectorXd& start,
                     Level& level) {
  const Index n = discretisation.dimension();
  const double period = system.period_s();
  const int power = std::max(1, static_cast<int>(std::ceil(kKrylovHorizon_s / period)));
  const Index max_vectors = std::min<Index>(kKrylovMaxVectors, n - 1);
  if (max_vectors < 3) return false;
  MatrixXd v(n, max_vectors + 1), h = MatrixXd::Zero(max_vectors + 1, max_vectors);
  std::mt19937_64 random(20261127);  // a fixed start: reproducible results
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (Index i = 0; i < n; ++i) v(i, 0) = uniform(random);
  if (start.size() == n && start.norm() > 0.0) v.col(0) = start;
  v.col(0).normalize();
  MatrixXd w;
  Eigen::VectorXcd last_ritz;  // the Ritz values at the previous check
  for (Index j = 0; j < max_vectors; ++j) {
    discretisation.apply(v.col(j), w, power);
    // Classical Gram-Schmidt, twice (orthogonal to working precision).
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::VectorXd coefficients = v.leftCols(j + 1).transpose() * w;
      w.noalias() -= v.leftCols(j + 1) * coefficients;
      h.col(j).head(j + 1) += coefficients;
    }
    const double beta = w.norm();
    h(j + 1, j) = beta;
    const Index m = j + 1;
    const bool invariant = !(beta > 1e-14 * h.topLeftCorner(m + 1, m).norm());
    if (!invariant) v.col(j + 1) = w / beta;
    if (!invariant && (m < 3 || (m > 12 && m % 2 != 0)) && m != max_vectors) continue;
    Eigen::EigenSolver<MatrixXd> ritz(h.topLeftCorner(m, m), true);
    if (ritz.info() != Eigen::Success) return false;
    std::vector<Index> order(static_cast<std::size_t>(m));
    for (Index i = 0; i < m; ++i) order[static_cast<std::size_t>(i)] = i;
    std::sort(order.begin(), order.end(), [&](Index a, Index b) {
      return std::abs(ritz.eigenvalues()(a)) > std::abs(ritz.eigenvalues()(b));
    });
    auto residual = [&](Index i) { return invariant ? 0.0 : beta * std::abs(ritz.eigenvectors()(m - 1, i)); };
    int excluded = 0;
    Index accepted = -1;
    bool converged = true;
    for (Index i : order) {
      const Complex theta = ritz.eigenvalues()(i);
      converged = residual(i) <= kKrylovResidual * std::abs(theta);
      if (!converged) break;
      if (excluded < system.family_multipliers() && std::abs(theta - 1.0) <= kFamilyDistance * power) {
        ++excluded;
        continue;
      }
      accepted = i;
      break;
    }
    const Complex theta = accepted >= 0 ? ritz.eigenvalues()(accepted) : Complex(0.0);
    // The same multiplier at the previous check: its nearest Ritz value then (with two multipliers
    // of nearly equal modulus the dominant one may have been the other).
    Complex before = 0.0;
    for (Index i = 0; i < last_ritz.size(); ++i)
      if (before == Complex(0.0) || std::abs(last_ritz(i) - theta) < std::abs(before - theta)) before = last_ritz(i);
    last_ritz = ritz.eigenvalues();
    // (The change needs a previous check: the first converged one waits for the next vector.)
    if (!converged || accepted < 0 || (before == Complex(0.0) && !invariant)) {
      if (invariant) return false;
      continue;
    }
    Complex mu = theta;
    const Eigen::VectorXcd x = v.leftCols(m).cast<Complex>() * ritz.eigenvectors().col(accepted);
    if (x.real().norm() >= x.imag().norm()) level.dominant_vector = x.real();
    else level.dominant_vector = x.imag();
    if (power > 1) {
      // mu from the Ritz vector x: mu = x^H M x / x^H x (M applied to Re x and Im x).
      MatrixXd parts(n, 2), images;
      parts.col(0) = x.real();
      parts.col(1) = x.imag();
      discretisation.apply(parts, images, 1);
      const Eigen::VectorXcd mx = images.col(0).cast<Complex>() + Complex(0.0, 1.0) * images.col(1).cast<Complex>();
      mu = x.dot(mx) / x.squaredNorm();
    }
    level.multiplier = Complex(mu.real(), std::abs(mu.imag()));
    level.growth = std::log(std::abs(theta)) / (power * period);
    // The residual bounds the error of a well-conditioned multiplier; the change since the
    // previous check also sees the conditioning (the step maps are far from normal).
    const double relative_error = std::max(residual(accepted) / std::abs(theta), std::abs(theta - before) / std::abs(theta));
    level.eigen_error = relative_error / (power * period);
    level.excluded = excluded;
    level.eigen_route = fmt::format("Arnoldi on M^{} ({} vectors, relative residual {:.1e}, change {:.1e})", power, m,
                                    residual(accepted) / std::abs(theta), std::abs(theta - before) / std::abs(theta));
    return true;
  }
  return false;
}

// `coarser`: the level with steps / 2, whose delays and dominant vector this one starts from.
Level solve_level(const PeriodicDelaySystem& system, int steps, const std::vector<Index>& delayed,
                  const FloquetSettings& settings, const Level* coarser = nullptr) {
  const Discretisation discretisation(system, steps, delayed, coarser ? &coarser->delays : nullptr);
  Level level;
  level.steps = steps;
  level.dimension = static_cast<std::size_t>(discretisation.dimension());
  const Eigen::VectorXd start = coarser && coarser->dominant_vector.size() > 0
                                    ? discretisation.refine(coarser->dominant_vector) : Eigen::VectorXd();
  if (settings.dense_spectrum || !krylov_dominant(discretisation, system, start, level)) {
    const std::string unconverged = settings.dense_spectrum ? "" : "Arnoldi unconverged, ";
    level.excluded = 0;
    dense_dominant(discretisation, system, level);
    level.eigen_route = unconverged + level.eigen_route;
  }
  level.delays = discretisation.half_step_delays();
  return level;
}

// Variables that appear delayed: nonzero columns of any A_k at sampled times.
std::vector<Index> delayed_variables(const PeriodicDelaySystem& system) {
  std::vector<bool> used(system.size(), false);
  MatrixXd a0;
  std::vector<MatrixXd> ak;
  for (int j = 0; j < 64; ++j) {
    system.coefficients(system.period_s() * j / 64.0, a0, ak);
    for (const MatrixXd& a : ak)
      for (Index c = 0; c < a.cols(); ++c)
        if (!a.col(c).isZero(0.0)) used[static_cast<std::size_t>(c)] = true;
  }
  std::vector<Index> out;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (used[i]) out.push_back(static_cast<Index>(i));
  return out;
}

// The level plan shared by first_floquet_level and floquet_growth_rate.
struct Plan {
  std::vector<Index> delayed;
  std::size_t differential_count = 0;
  int first_steps = 0;
  std::size_t dimension_at(const PeriodicDelaySystem& system, int steps) const {
    const double step = system.period_s() / steps;
    return differential_count + static_cast<std::size_t>(std::ceil(system.max_delay_s() / step) + 4) * delayed.size();
  }
};

Plan plan(const PeriodicDelaySystem& system, const FloquetSettings& settings) {
  const double period = system.period_s();
  if (!(period > 0.0) || !std::isfinite(period)) throw PointFailure(fmt::format("Floquet: period {} s must be > 0", period));
  const double tau_min = system.min_delay_s();
  if (!(tau_min > 0.0)) throw PointFailure("Floquet: delays must be > 0");
  Plan p;
  p.delayed = delayed_variables(system);
  // First level: the frequency scale resolved by steps_per_wave steps, and at least 4 steps per
  // shortest delay (the cubic stencil stays behind the step).
  const double h = std::min(1.0 / (settings.steps_per_wave * system.frequency_scale_hz()), tau_min / 4.0);
  p.first_steps = std::max(8, static_cast<int>(std::ceil(period / h)));
  const std::vector<bool> differential = system.differential();
  p.differential_count = static_cast<std::size_t>(std::count(differential.begin(), differential.end(), true));
  return p;
}

}  // namespace

FloquetLevel first_floquet_level(const PeriodicDelaySystem& system, const FloquetSettings& settings) {
  const Plan p = plan(system, settings);
  return {p.first_steps, p.dimension_at(system, p.first_steps)};
}

FloquetResult floquet_growth_rate(const PeriodicDelaySystem& system, const FloquetSettings& settings) {
  const Plan p = plan(system, settings);
  const double period = system.period_s();
  const std::vector<Index>& delayed = p.delayed;
  int steps = p.first_steps;
  auto dimension_at = [&](int n) { return p.dimension_at(system, n); };
  if (dimension_at(steps) > settings.max_dimension)
    throw PointFailure(fmt::format("Floquet: {} steps per period give a monodromy of dimension {} > {} (max_dimension)",
                                   steps, dimension_at(steps), settings.max_dimension));
  FloquetResult result;
  Level previous = solve_level(system, steps, delayed, settings), current = previous;
  result.growth_rate_error_per_s = std::numeric_limits<double>::infinity();
  while (dimension_at(2 * steps) <= settings.max_dimension) {
    steps *= 2;
    current = solve_level(system, steps, delayed, settings, &previous);
    // Order >= 2: the error of the finer level is at most a third of the change between levels;
    // plus the eigenvalue solve's own residual bound (Krylov; 0 for the dense spectrum).
    result.growth_rate_error_per_s = std::abs(current.growth - previous.growth) / 3.0 + current.eigen_error;
    previous = current;
    if (result.growth_rate_error_per_s <= settings.tolerance_per_s + settings.relative_tolerance * std::abs(current.growth)) {
      result.converged = true;
      break;
    }
  }
  result.multiplier = current.multiplier;
  result.growth_rate_per_s = current.growth;
  result.steps_per_period = current.steps;
  result.dimension = current.dimension;
  result.family_multipliers_excluded = current.excluded;
  result.method = fmt::format("semi-discretisation (exact exponential, cubic history), {} steps per period of {:.6g} s, "
                              "monodromy dimension {}, dominant multiplier by {}, error estimate {:.3g} 1/s",
                              current.steps, period, current.dimension, current.eigen_route, result.growth_rate_error_per_s);
  return result;
}

}  // namespace chatterlab
