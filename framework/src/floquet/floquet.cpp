// Floquet growth rates by semi-discretisation (chatterlab/floquet.hpp; Insperger & Stepan 2002,
// 2004, 2011). docs/derived_stability.md derives the step map.
#include "chatterlab/floquet.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
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

// One level of the semi-discretisation: N steps per period.
class Discretisation {
 public:
  Discretisation(const PeriodicDelaySystem& system, int steps, const std::vector<Index>& delayed_columns);
  std::size_t dimension() const { return static_cast<std::size_t>(d_ + ring_ * nh_); }
  MatrixXd monodromy();

 private:
  // The undelayed elimination at time t: S = A_dd - A_da A_aa^{-1} A_ad and the delayed inputs
  // C_k = A_k,dH - A_da A_aa^{-1} A_k,aH of the differential part; L, M_k of the algebraic part.
  struct Blocks {
    MatrixXd s, l;
    std::vector<MatrixXd> c, m;
  };
  // The blocks at t, reused while the coefficients stay the same (G1 under a speed modulation:
  // only the delays vary), so a step does not redo the elimination. Valid until the next call.
  const Blocks& blocks(double t);
  void exponentials(const MatrixXd& s);
  auto sample(Index index) {
    const Index position = ((index % ring_) + ring_) % ring_;
    return history_.middleRows(position * nh_, nh_);
  }

  const PeriodicDelaySystem& system_;
  int steps_;
  double h_;
  Index d_ = 0, nh_ = 0, ring_ = 0;
  std::vector<Index> diff_, alg_, delayed_;  // variable indices
  std::vector<Index> delayed_rows_in_d_, delayed_rows_in_a_;  // position of each delayed variable (-1: not there)
  MatrixXd cached_s_;
  MatrixXd a0_, last_a0_;
  std::vector<MatrixXd> ak_, last_ak_;
  Blocks last_blocks_;
  bool has_blocks_ = false;
  MatrixXd phi_;                    // e^{S h}
  std::array<MatrixXd, 4> gamma_;   // int_0^h e^{S (h - u)} (u/h)^q du
  RowMatrix state_, history_;
};

Discretisation::Discretisation(const PeriodicDelaySystem& system, int steps, const std::vector<Index>& delayed_columns)
    : system_(system), steps_(steps), h_(system.period_s() / steps), delayed_(delayed_columns) {
  const std::vector<bool> differential = system.differential();
  for (std::size_t i = 0; i < differential.size(); ++i) (differential[i] ? diff_ : alg_).push_back(static_cast<Index>(i));
  d_ = static_cast<Index>(diff_.size());
  nh_ = static_cast<Index>(delayed_.size());
  for (Index v : delayed_) {
    const auto in_d = std::find(diff_.begin(), diff_.end(), v), in_a = std::find(alg_.begin(), alg_.end(), v);
    delayed_rows_in_d_.push_back(in_d != diff_.end() ? static_cast<Index>(in_d - diff_.begin()) : -1);
    delayed_rows_in_a_.push_back(in_a != alg_.end() ? static_cast<Index>(in_a - alg_.begin()) : -1);
  }
  // Samples back to the oldest a step can reach: tau_max / h plus the stencil and one spare.
  ring_ = static_cast<Index>(std::ceil(system.max_delay_s() / h_)) + 4;
}

const Discretisation::Blocks& Discretisation::blocks(double t) {
  system_.coefficients(t, a0_, ak_);
  if (has_blocks_ && a0_ == last_a0_ && ak_ == last_ak_) return last_blocks_;
  last_a0_ = a0_;
  last_ak_ = ak_;
  has_blocks_ = false;  // until the new blocks are complete (an exception leaves none)
  const MatrixXd& a0 = a0_;
  const std::vector<MatrixXd>& ak = ak_;
  Blocks& b = last_blocks_;
  b = Blocks{};
  const MatrixXd a_dd = take(a0, diff_, diff_), a_da = take(a0, diff_, alg_), a_ad = take(a0, alg_, diff_);
  MatrixXd solve_ad, elimination;  // A_aa^{-1} A_ad and A_da A_aa^{-1}
  Eigen::PartialPivLU<MatrixXd> lu;
  if (!alg_.empty()) {
    lu.compute(take(a0, alg_, alg_));
    if (!(lu.rcond() > 1e-14))
      throw PointFailure(fmt::format("Floquet: the algebraic equations are singular at t = {:.6g} s", t));
    solve_ad = lu.solve(a_ad);
    elimination = lu.solve(MatrixXd::Identity(static_cast<Index>(alg_.size()), static_cast<Index>(alg_.size())));
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
  has_blocks_ = true;
  return b;
}

// e^{Z} and the phi functions phi_j(Z) = sum_k Z^k/(k+j)! from one exponential of the augmented
// block matrix [[Z, I, 0, 0, 0], [0, 0, I, 0, 0], ..., [0, ...]]: its first block row is
// [e^Z, phi_1, phi_2, phi_3, phi_4]; int_0^h e^{S(h-u)} (u/h)^q du = h q! phi_{q+1}(S h).
void Discretisation::exponentials(const MatrixXd& s) {
  if (cached_s_.size() == s.size() && cached_s_ == s) return;
  cached_s_ = s;
  const Index n = d_;
  MatrixXd augmented = MatrixXd::Zero(5 * n, 5 * n);
  augmented.topLeftCorner(n, n) = s * h_;
  for (Index j = 0; j < 4; ++j) augmented.block(j * n, (j + 1) * n, n, n).setIdentity();
  const MatrixXd e = augmented.exp();
  phi_ = e.topLeftCorner(n, n);
  double factorial = 1.0;
  for (Index q = 0; q < 4; ++q) {
    if (q > 0) factorial *= static_cast<double>(q);
    gamma_[static_cast<std::size_t>(q)] = h_ * factorial * e.block(0, (q + 1) * n, n, n);
  }
}

MatrixXd Discretisation::monodromy() {
  const Index dim = static_cast<Index>(dimension());
  state_ = RowMatrix::Zero(d_, dim);
  history_ = RowMatrix::Zero(ring_ * nh_, dim);
  for (Index i = 0; i < d_; ++i) state_(i, i) = 1.0;
  for (Index j = 0; j < ring_; ++j)  // initial sample index -j: identity columns d + j nh + r
    for (Index r = 0; r < nh_; ++r) sample(-j)(r, d_ + j * nh_ + r) = 1.0;
  const std::size_t k_count = system_.delay_count();
  std::vector<double> tau_start(k_count);
  for (std::size_t k = 0; k < k_count; ++k) tau_start[k] = system_.delay_s(k, 0.0);
  RowMatrix next_state(d_, dim), algebraic(static_cast<Index>(alg_.size()), dim);
  for (int i = 0; i < steps_; ++i) {
    const double t = i * h_, t_mid = t + 0.5 * h_, t_end = t + h_;
    const Blocks& mid = blocks(t_mid);
    exponentials(mid.s);
    next_state.noalias() = phi_ * state_;
    std::vector<double> tau_end(k_count);
    for (std::size_t k = 0; k < k_count; ++k) {
      const double tau_mid = system_.delay_s(k, t_mid);
      tau_end[k] = system_.delay_s(k, t_end);
      // Delayed argument t - tau(t) in samples, linear over the step: b(xi) = b_mid + (xi - 1/2) rho.
      const double rho = 1.0 - (tau_end[k] - tau_start[k]) / h_;
      const double b_mid = i + 0.5 - tau_mid / h_;
      const Index c = static_cast<Index>(std::floor(b_mid));
      const auto basis = lagrange_along(b_mid - static_cast<double>(c) + 1.0 - 0.5 * rho, rho);
      for (Index l = 0; l < 4; ++l) {
        MatrixXd weight = MatrixXd::Zero(d_, d_);
        for (std::size_t q = 0; q < 4; ++q) weight += basis[static_cast<std::size_t>(l)][q] * gamma_[q];
        next_state.noalias() += (weight * mid.c[k]) * sample(c - 1 + l);
      }
    }
    state_.swap(next_state);
    // Algebraic variables at the step end, from the new differential state and the history.
    if (!alg_.empty()) {
      const Blocks& end = blocks(t_end);  // mid is not used after this
      algebraic.noalias() = end.l * state_;
      for (std::size_t k = 0; k < k_count; ++k) {
        const double b = (i + 1) - tau_end[k] / h_;
        const Index c = static_cast<Index>(std::floor(b));
        const auto basis = lagrange_at(b - static_cast<double>(c) + 1.0);
        for (Index l = 0; l < 4; ++l)
          algebraic.noalias() += (basis[static_cast<std::size_t>(l)] * end.m[k]) * sample(c - 1 + l);
      }
    }
    auto fresh = sample(i + 1);
    for (Index r = 0; r < nh_; ++r) {
      const std::size_t ri = static_cast<std::size_t>(r);
      if (delayed_rows_in_d_[ri] >= 0) fresh.row(r) = state_.row(delayed_rows_in_d_[ri]);
      else fresh.row(r) = algebraic.row(delayed_rows_in_a_[ri]);
    }
    tau_start = tau_end;
  }
  MatrixXd m(dim, dim);
  m.topRows(d_) = state_;
  for (Index j = 0; j < ring_; ++j) m.middleRows(d_ + j * nh_, nh_) = sample(steps_ - j);
  return m;
}

struct Level {
  int steps = 0;
  std::size_t dimension = 0;
  Complex multiplier;
  double growth = 0.0;
  int excluded = 0;
};

Level solve_level(const PeriodicDelaySystem& system, int steps, const std::vector<Index>& delayed) {
  Discretisation discretisation(system, steps, delayed);
  const MatrixXd m = discretisation.monodromy();
  Eigen::EigenSolver<MatrixXd> solver(m, false);
  if (solver.info() != Eigen::Success) throw PointFailure("Floquet: the eigenvalue solver of the monodromy failed");
  std::vector<Complex> mu(solver.eigenvalues().data(), solver.eigenvalues().data() + solver.eigenvalues().size());
  Level level;
  level.steps = steps;
  level.dimension = discretisation.dimension();
  // A family of steady states is an exact multiplier 1 (a constant history): excluded.
  for (int f = 0; f < system.family_multipliers() && !mu.empty(); ++f) {
    auto nearest = std::min_element(mu.begin(), mu.end(), [](Complex a, Complex b) { return std::abs(a - 1.0) < std::abs(b - 1.0); });
    if (std::abs(*nearest - 1.0) > 1e-6) break;
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
  Level previous = solve_level(system, steps, delayed), current = previous;
  result.growth_rate_error_per_s = std::numeric_limits<double>::infinity();
  while (dimension_at(2 * steps) <= settings.max_dimension) {
    steps *= 2;
    current = solve_level(system, steps, delayed);
    // Order >= 2: the error of the finer level is at most a third of the change between levels.
    result.growth_rate_error_per_s = std::abs(current.growth - previous.growth) / 3.0;
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
                              "monodromy dimension {}, error estimate {:.3g} 1/s",
                              current.steps, period, current.dimension, result.growth_rate_error_per_s);
  return result;
}

}  // namespace chatterlab
