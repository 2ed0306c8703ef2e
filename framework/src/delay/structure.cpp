#include "delay/structure.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "chatterlab/errors.hpp"

namespace chatterlab::delay_detail {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string shape(const MatrixXd& m) { return fmt::format("{}x{}", m.rows(), m.cols()); }

void check_finite(const MatrixXd& m, const std::string& name) {
  if (!m.allFinite()) throw InputError(fmt::format("delay system: {} has a non-finite entry", name));
}

// A square n x n matrix, or empty (then `empty_as` of that size).
MatrixXd square_or(const MatrixXd& m, Index n, const std::string& name, bool empty_is_zero) {
  if (m.size() == 0) return empty_is_zero ? MatrixXd(MatrixXd::Zero(n, n)) : MatrixXd(MatrixXd::Identity(n, n));
  if (m.rows() != n || m.cols() != n)
    throw InputError(fmt::format("delay system: {} is {} but A_0 is {}x{}: every matrix must be n x n",
                                 name, shape(m), n, n));
  check_finite(m, name);
  return m;
}

// Upper bound of the spectral norm: ||X||_2 <= sqrt(||X||_1 ||X||_inf) (cheap, always valid).
double norm_bound(const MatrixXd& x) {
  if (x.size() == 0) return 0.0;
  const double one = x.cwiseAbs().colwise().sum().maxCoeff();
  const double inf = x.cwiseAbs().rowwise().sum().maxCoeff();
  return std::sqrt(one * inf);
}

// Logarithmic 2-norm: the largest eigenvalue of the symmetric part.
double log_norm(const MatrixXd& x) {
  if (x.size() == 0) return -kInfinity;
  const MatrixXd h = 0.5 * (x + x.transpose());
  Eigen::SelfAdjointEigenSolver<MatrixXd> solver(h, Eigen::EigenvaluesOnly);
  const double largest = solver.eigenvalues().maxCoeff();
  // Rounding of the eigensolver: a relative margin of the matrix size.
  return largest + 1e-13 * static_cast<double>(x.rows()) * h.cwiseAbs().maxCoeff();
}

bool is_zero(const MatrixXd& m, double tolerance) { return m.size() == 0 || m.cwiseAbs().maxCoeff() <= tolerance; }

double power_of_two(double x) { return std::ldexp(1.0, static_cast<int>(std::lround(std::log2(x)))); }

}  // namespace

VectorXd osborne(const MatrixXd& x) {
  const Index n = x.rows();
  VectorXd d = VectorXd::Ones(n);
  for (int sweep = 0; sweep < 20; ++sweep) {
    bool changed = false;
    for (Index i = 0; i < n; ++i) {
      double row = 0.0, col = 0.0;
      for (Index j = 0; j < n; ++j) {
        if (j == i) continue;
        row += std::abs(x(i, j)) * d(i) / d(j);
        col += std::abs(x(j, i)) * d(j) / d(i);
      }
      if (row == 0.0 || col == 0.0) continue;
      // d_i -> f d_i scales row i by f and column i by 1/f: balanced at f = sqrt(col/row).
      const double f = power_of_two(std::sqrt(col / row));
      if (f != 1.0 && row * f + col / f < 0.95 * (row + col)) {
        d(i) *= f;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return d;
}

void equilibrate(const MatrixXd& magnitude, VectorXd& rows, VectorXd& columns) {
  const Index n = magnitude.rows(), m = magnitude.cols();
  rows = VectorXd::Ones(n);
  columns = VectorXd::Ones(m);
  for (int sweep = 0; sweep < 8; ++sweep) {
    for (Index i = 0; i < n; ++i) {
      double largest = 0.0;
      for (Index j = 0; j < m; ++j) largest = std::max(largest, magnitude(i, j) * rows(i) * columns(j));
      if (largest > 0.0) rows(i) /= power_of_two(std::sqrt(largest));
    }
    for (Index j = 0; j < m; ++j) {
      double largest = 0.0;
      for (Index i = 0; i < n; ++i) largest = std::max(largest, magnitude(i, j) * rows(i) * columns(j));
      if (largest > 0.0) columns(j) /= power_of_two(std::sqrt(largest));
    }
  }
}

namespace {

// Reciprocal condition number (1-norm estimate) of a square matrix after equilibration; 0 when
// exactly singular.
double scaled_rcond(const MatrixXd& m) {
  if (m.size() == 0) return 1.0;
  VectorXd r, c;
  equilibrate(m.cwiseAbs(), r, c);
  const MatrixXd scaled = r.asDiagonal() * m * c.asDiagonal();
  Eigen::PartialPivLU<MatrixXd> lu(scaled);
  if (lu.matrixLU().diagonal().cwiseAbs().minCoeff() == 0.0) return 0.0;
  return lu.rcond();
}

std::vector<Index> where(const std::vector<bool>& flags, bool value) {
  std::vector<Index> out;
  for (std::size_t i = 0; i < flags.size(); ++i)
    if (flags[i] == value) out.push_back(static_cast<Index>(i));
  return out;
}

MatrixXd take(const MatrixXd& m, const std::vector<Index>& rows, const std::vector<Index>& cols) {
  MatrixXd out(static_cast<Index>(rows.size()), static_cast<Index>(cols.size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < cols.size(); ++j)
      out(static_cast<Index>(i), static_cast<Index>(j)) = m(rows[i], cols[j]);
  return out;
}

// Eliminates the undelayed algebraic variables U that the delay-free algebraic equations R
// determine (|U| = |R|, A0[R, U] regular): Delta[R, :] = -A0[R, :] is constant and Delta[:, U] =
// -A0[:, U] too, so det Delta = det(-A0[R, U]) det(reduced) with A0 replaced by its Schur
// complement.
void condense(ReducedSystem& s) {
  const Index n = s.a0.rows();
  std::vector<bool> undelayed_algebraic_col(static_cast<std::size_t>(n)), delay_free_algebraic_row(static_cast<std::size_t>(n));
  for (Index j = 0; j < n; ++j) {
    bool algebraic = s.mass.col(j).isZero(0.0), delayed = false;
    for (std::size_t k = 0; k < s.delays.size(); ++k) {
      delayed = delayed || !s.matrices[k].col(j).isZero(0.0);
      if (s.neutral[k].size()) {
        algebraic = algebraic && s.neutral[k].col(j).isZero(0.0);
        delayed = delayed || !s.neutral[k].col(j).isZero(0.0);
      }
    }
    undelayed_algebraic_col[static_cast<std::size_t>(j)] = algebraic && !delayed;
  }
  for (Index i = 0; i < n; ++i) {
    bool algebraic = s.mass.row(i).isZero(0.0), delayed = false;
    for (std::size_t k = 0; k < s.delays.size(); ++k) {
      delayed = delayed || !s.matrices[k].row(i).isZero(0.0);
      if (s.neutral[k].size()) {
        algebraic = algebraic && s.neutral[k].row(i).isZero(0.0);
        delayed = delayed || !s.neutral[k].row(i).isZero(0.0);
      }
    }
    delay_free_algebraic_row[static_cast<std::size_t>(i)] = algebraic && !delayed;
  }
  const std::vector<Index> u = where(undelayed_algebraic_col, true), r = where(delay_free_algebraic_row, true);
  if (u.empty() || u.size() != r.size() || u.size() == static_cast<std::size_t>(n)) return;
  const MatrixXd block = take(s.a0, r, u);
  if (scaled_rcond(block) < 1e-12) return;
  const std::vector<Index> keep_cols = where(undelayed_algebraic_col, false);
  const std::vector<Index> keep_rows = where(delay_free_algebraic_row, false);
  const MatrixXd solved = block.fullPivLu().solve(take(s.a0, r, keep_cols));
  s.a0 = take(s.a0, keep_rows, keep_cols) - take(s.a0, keep_rows, u) * solved;
  s.mass = take(s.mass, keep_rows, keep_cols);
  for (std::size_t k = 0; k < s.delays.size(); ++k) {
    s.matrices[k] = take(s.matrices[k], keep_rows, keep_cols);
    if (s.neutral[k].size()) s.neutral[k] = take(s.neutral[k], keep_rows, keep_cols);
  }
  s.condensed = u.size();
}

}  // namespace

ReducedSystem check_and_reduce(const LinearDelaySystem& system) {
  const Index n = system.a0.rows();
  if (n == 0 || system.a0.cols() != n)
    throw InputError(fmt::format("delay system: A_0 is {}: must be square and non-empty", shape(system.a0)));
  ReducedSystem s;
  s.a0 = system.a0;
  check_finite(s.a0, "A_0");
  s.mass = square_or(system.mass, n, "the mass matrix E", false);
  for (std::size_t k = 0; k < system.delayed.size(); ++k) {
    const DelayTerm& term = system.delayed[k];
    if (!(term.delay_s > 0.0) || !std::isfinite(term.delay_s))
      throw InputError(fmt::format("delay system: delayed term {}: tau = {} must be finite and > 0", k, term.delay_s));
    s.delays.push_back(term.delay_s);
    s.matrices.push_back(square_or(term.matrix, n, fmt::format("delayed term {}: A_k", k), true));
    MatrixXd b = term.neutral_matrix.size() ? square_or(term.neutral_matrix, n, fmt::format("delayed term {}: B_k", k), true)
                                            : MatrixXd();
    if (b.size() && b.isZero(0.0)) b.resize(0, 0);
    s.neutral.push_back(std::move(b));
  }
  condense(s);
  return s;
}

bool SplitSystem::neutral() const {
  return std::any_of(neutral_delay.begin(), neutral_delay.end(), [](bool b) { return b; });
}

SplitSystem split(const ReducedSystem& s) {
  const Index n = static_cast<Index>(s.size());
  // Row and column transformations P, Q with P E Q = diag(I_r, 0). A (permuted) diagonal E is
  // transformed exactly; otherwise by its singular value decomposition E = U S V^T.
  MatrixXd p = MatrixXd::Zero(n, n), q = MatrixXd::Zero(n, n);
  Index r = 0;
  const bool diagonal = (s.mass - MatrixXd(s.mass.diagonal().asDiagonal())).isZero(0.0);
  if (diagonal) {
    std::vector<Index> order;
    for (Index i = 0; i < n; ++i)
      if (s.mass(i, i) != 0.0) order.push_back(i);
    r = static_cast<Index>(order.size());
    for (Index i = 0; i < n; ++i)
      if (s.mass(i, i) == 0.0) order.push_back(i);
    for (Index j = 0; j < n; ++j) {
      const Index i = order[static_cast<std::size_t>(j)];
      q(i, j) = 1.0;
      p(j, i) = j < r ? 1.0 / s.mass(i, i) : 1.0;
    }
  } else {
    Eigen::JacobiSVD<MatrixXd> svd(s.mass, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const VectorXd& sv = svd.singularValues();
    const double tolerance = 1e-12 * static_cast<double>(n) * sv(0);
    while (r < n && sv(r) > tolerance) ++r;
    VectorXd scale = VectorXd::Ones(n);
    for (Index i = 0; i < r; ++i) scale(i) = 1.0 / sv(i);
    p = scale.asDiagonal() * svd.matrixU().transpose();
    q = svd.matrixV();
  }
  SplitSystem out;
  out.differential = static_cast<std::size_t>(r);
  out.algebraic = static_cast<std::size_t>(n - r);
  out.delays = s.delays;
  const Index a = n - r;
  auto transform = [&](const MatrixXd& x) -> MatrixXd { return p * x * q; };
  const MatrixXd a0 = transform(s.a0);
  out.a0_dd = a0.topLeftCorner(r, r);
  out.a0_da = a0.topRightCorner(r, a);
  out.a0_ad = a0.bottomLeftCorner(a, r);
  const MatrixXd a0_aa = a0.bottomRightCorner(a, a);
  if (a > 0) {
    if (scaled_rcond(a0_aa) < 1e-13)
      throw InputError("delay system: the algebraic equations do not determine the algebraic variables "
                       "(their matrix without delays is singular: a differential-algebraic system of index "
                       "> 1 or a singular pencil)");
    out.g0 = a0_aa.fullPivLu().inverse();
  } else {
    out.g0.resize(0, 0);
  }
  for (std::size_t k = 0; k < s.delays.size(); ++k) {
    const MatrixXd ak = transform(s.matrices[k]);
    const double tolerance = 1e-13 * std::max(ak.cwiseAbs().maxCoeff(), 1e-300);
    out.a_dd.push_back(ak.topLeftCorner(r, r));
    out.a_da.push_back(ak.topRightCorner(r, a));
    out.a_ad.push_back(ak.bottomLeftCorner(a, r));
    MatrixXd aa = ak.bottomRightCorner(a, a);
    bool neutral = !is_zero(aa, diagonal ? 0.0 : tolerance);
    if (!neutral) aa.setZero();
    out.a_aa.push_back(aa);
    if (s.neutral[k].size()) {
      const MatrixXd bk = transform(s.neutral[k]);
      const double b_tol = (diagonal ? 0.0 : 1e-12) * bk.cwiseAbs().maxCoeff();
      if (!is_zero(bk.bottomRows(a), b_tol) || !is_zero(bk.rightCols(a), b_tol))
        throw InputError(fmt::format(
            "delay system: delayed term {}: the neutral term B_k acts on algebraic variables or equations "
            "(B_k must vanish on the null space of E and map into its range: only derivatives of "
            "differential variables may be delayed)", k));
      out.b_dd.push_back(bk.topLeftCorner(r, r));
      neutral = true;
    } else {
      out.b_dd.push_back(MatrixXd::Zero(r, r));
    }
    out.neutral_delay.push_back(neutral);
  }
  out.undelayed = a > 0 ? MatrixXd(out.a0_dd - out.a0_da * out.g0 * out.a0_ad) : out.a0_dd;
  return out;
}

// ------------------------------------------------------------------ real-part bound

RealPartBound::RealPartBound(const SplitSystem& s) : delays_(s.delays), has_differential_(s.differential > 0), neutral_(s.neutral()) {
  const Index r = static_cast<Index>(s.differential), a = static_cast<Index>(s.algebraic);
  // Inner products on the differential space (T) and the algebraic space (W): each gives a valid
  // bound, the least is taken. T: identity, Osborne balancing of S0, the real modal form of S0.
  std::vector<std::pair<MatrixXd, MatrixXd>> ts;  // (T, T^{-1})
  ts.emplace_back(MatrixXd::Identity(r, r), MatrixXd::Identity(r, r));
  if (r > 0) {
    const VectorXd d = osborne(s.undelayed);
    ts.emplace_back(MatrixXd(d.asDiagonal()), MatrixXd(d.cwiseInverse().asDiagonal()));
    // The modal form of the balanced matrix D S0 D^{-1}; T = Tb D.
    const MatrixXd balanced = d.asDiagonal() * s.undelayed * d.cwiseInverse().asDiagonal();
    Eigen::EigenSolver<MatrixXd> eig(balanced, true);
    if (eig.info() == Eigen::Success) {
      // Columns: real eigenvectors, and (Re v, Im v) of each complex pair (Im lambda > 0).
      MatrixXd basis(r, r);
      Index col = 0;
      for (Index i = 0; i < r && col < r; ++i) {
        const auto lambda = eig.eigenvalues()(i);
        const Eigen::VectorXcd v = eig.eigenvectors().col(i);
        if (lambda.imag() == 0.0) {
          basis.col(col++) = v.real().normalized();
        } else if (lambda.imag() > 0.0 && col + 1 < r) {
          const double scale = v.norm();
          basis.col(col++) = v.real() / scale;
          basis.col(col++) = v.imag() / scale;
        }
      }
      if (col == r) {
        Eigen::FullPivLU<MatrixXd> lu(basis);
        if (lu.isInvertible()) {
          const MatrixXd inverse = lu.inverse();
          const double residual = (inverse * basis - MatrixXd::Identity(r, r)).cwiseAbs().maxCoeff();
          if (residual < 1e-10 && (inverse.cwiseAbs().maxCoeff() * basis.cwiseAbs().maxCoeff()) < 1e10)
            ts.emplace_back(MatrixXd(inverse * d.asDiagonal()), MatrixXd(d.cwiseInverse().asDiagonal() * basis));
        }
      }
    }
  }
  std::vector<std::pair<MatrixXd, MatrixXd>> ws;  // (W, W^{-1})
  ws.emplace_back(MatrixXd::Identity(a, a), MatrixXd::Identity(a, a));
  if (a > 1) {
    MatrixXd coupling = MatrixXd::Zero(a, a);
    for (const MatrixXd& aa : s.a_aa) coupling += (s.g0 * aa).cwiseAbs();
    const VectorXd d = osborne(coupling);
    ws.emplace_back(MatrixXd(d.asDiagonal()), MatrixXd(d.cwiseInverse().asDiagonal()));
  }
  const std::size_t k_count = delays_.size();
  for (const auto& [t, t_inv] : ts) {
    for (const auto& [w, w_inv] : ws) {
      Profile p;
      const MatrixXd s0 = t * s.undelayed * t_inv;
      p.mu0 = r > 0 ? log_norm(s0) : -kInfinity;
      p.norm0 = norm_bound(s0);
      p.alpha0 = norm_bound(t * s.a0_da * w_inv);
      p.gamma0 = a > 0 ? norm_bound(w * s.g0 * s.a0_ad * t_inv) : 0.0;
      for (std::size_t k = 0; k < k_count; ++k) {
        p.dd.push_back(norm_bound(t * s.a_dd[k] * t_inv));
        p.b.push_back(norm_bound(t * s.b_dd[k] * t_inv));
        p.alpha.push_back(norm_bound(t * s.a_da[k] * w_inv));
        if (a > 0) {
          p.gamma.push_back(norm_bound(w * s.g0 * s.a_ad[k] * t_inv));
          p.phi.push_back(norm_bound(w * s.g0 * s.a_aa[k] * s.g0 * s.a0_ad * t_inv));
          p.q.push_back(norm_bound(w * s.g0 * s.a_aa[k] * w_inv));
        } else {
          p.gamma.push_back(0.0);
          p.phi.push_back(0.0);
          p.q.push_back(0.0);
        }
      }
      // Rounding of the products and norms above: a relative margin on every coefficient.
      constexpr double margin = 1.0 + 1e-12;
      for (auto* v : {&p.dd, &p.b, &p.alpha, &p.gamma, &p.phi, &p.q})
        for (double& x : *v) x *= margin;
      p.norm0 *= margin;
      p.alpha0 *= margin;
      p.gamma0 *= margin;
      profiles_.push_back(std::move(p));
      if (r == 0) break;  // no differential space: one profile per W is enough
    }
  }
}

RealPartBound::Terms RealPartBound::terms(const Profile& p, double sigma) const {
  Terms t;
  double q = 0.0, beta = 0.0, dd = 0.0, alpha = 0.0, gamma = 0.0, phi = 0.0;
  for (std::size_t k = 0; k < delays_.size(); ++k) {
    const double rho = std::exp(-delays_[k] * sigma);
    if (!std::isfinite(rho)) return t;
    // 0 * inf never occurs: rho is finite here.
    q += p.q[k] * rho;
    beta += p.b[k] * rho;
    dd += p.dd[k] * rho;
    alpha += p.alpha[k] * rho;
    gamma += p.gamma[k] * rho;
    phi += p.phi[k] * rho;
  }
  if (!(q < 1.0) || !(beta < 1.0)) return t;
  t.valid = true;
  if (!has_differential_) {  // det Delta = det(-A_aa(z)): no root where the Neumann condition holds
    t.bound = -kInfinity;
    t.reach = 0.0;
    return t;
  }
  // ||S(z) - S0|| on the polydisc: the delayed differential terms and the change of the algebraic
  // elimination A_da G A_ad, G = (I + G0 dA_aa)^{-1} G0 (Neumann: ||(I + G0 dA_aa)^{-1}|| <= 1/(1-q)).
  const double change = dd + (p.alpha0 * phi + alpha * p.gamma0 + p.alpha0 * gamma + alpha * gamma) / (1.0 - q);
  // s (I - B) v = S v: Re s <= mu(S) + beta |s| and |s| (1 - beta) <= ||S||.
  t.reach = (p.norm0 + change) / (1.0 - beta);
  t.bound = p.mu0 + change + beta * t.reach;
  return t;
}

double RealPartBound::bound(double sigma) const {
  double best = invalid;
  for (const Profile& p : profiles_)
    if (Terms t = terms(p, sigma); t.valid) best = std::min(best, t.bound);
  return best;
}

double RealPartBound::reach(double sigma) const {
  double best = invalid;
  for (const Profile& p : profiles_)
    if (Terms t = terms(p, sigma); t.valid) best = std::min(best, t.reach);
  return best;
}

// inf { sigma : holds(sigma) } for a condition that, once true, stays true as sigma grows.
double RealPartBound::smallest(const std::function<bool(double)>& holds) const {
  double hi = 1.0;
  for (int i = 0; i < 1100 && !holds(hi); ++i) hi = 2.0 * hi + 1.0;
  if (!holds(hi)) return kInfinity;
  double lo = hi - 1.0;
  for (int i = 0; i < 1100 && holds(lo); ++i) lo -= 2.0 * (hi - lo);
  if (holds(lo)) return -kInfinity;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * (1.0 + std::abs(hi)); ++i) {
    const double mid = 0.5 * (lo + hi);
    (holds(mid) ? hi : lo) = mid;
  }
  return hi;
}

double RealPartBound::proven_bound() const {
  const double sigma = smallest([&](double x) { return bound(x) <= x; });
  if (!std::isfinite(sigma)) return sigma;
  return sigma + 1e-9 * (1.0 + std::abs(sigma));  // rounding of the bisection's last comparison
}

double RealPartBound::difference_operator_bound() const {
  if (!neutral_) return -kInfinity;
  return smallest([&](double x) {
    for (const Profile& p : profiles_) {
      double q = 0.0, beta = 0.0;
      for (std::size_t k = 0; k < delays_.size(); ++k) {
        const double rho = std::exp(-delays_[k] * x);
        if (!std::isfinite(rho)) return false;
        q += p.q[k] * rho;
        beta += p.b[k] * rho;
      }
      if (q < 1.0 && beta < 1.0) return true;
    }
    return false;
  });
}

// ------------------------------------------------------------------ difference operator

DifferenceSpectrum difference_spectrum(const SplitSystem& s, const RealPartBound& bound) {
  DifferenceSpectrum out;
  if (!s.neutral()) return out;
  out.upper = bound.difference_operator_bound();
  std::vector<std::size_t> neutral;
  for (std::size_t k = 0; k < s.delays.size(); ++k)
    if (s.neutral_delay[k]) neutral.push_back(k);
  if (neutral.size() == 1) {
    // det(A0_aa + A_aa z) = det A0_aa det(I + G0 A_aa z) and det(I - B z): the chain values
    // z_j = e^{-tau s} are reciprocals of eigenvalues, Re s = ln|eigenvalue| / tau (exact).
    const std::size_t k = neutral.front();
    double largest = -kInfinity;
    auto add = [&](const MatrixXd& m) {
      if (m.size() == 0) return;
      Eigen::EigenSolver<MatrixXd> eig(m, false);
      if (eig.info() != Eigen::Success) return;
      for (Index i = 0; i < eig.eigenvalues().size(); ++i) {
        const double modulus = std::abs(eig.eigenvalues()(i));
        if (modulus > 1e-300) largest = std::max(largest, std::log(modulus) / s.delays[k]);
      }
    };
    if (s.algebraic > 0) add(-(s.g0 * s.a_aa[k]));
    add(s.b_dd[k]);
    // Exact (to the eigensolver's rounding): the chains' real parts are these values.
    if (std::isfinite(largest)) out.lower = out.upper = largest;
    return out;
  }
  // Several neutral delays: the largest real root of the real function det D(e^{-tau sigma}) on
  // the ray z_k = e^{-tau_k sigma} (where e.g. G1's cumulative-removal point z = 1 lies).
  auto det_on_ray = [&](double sigma) {
    double value = 1.0;
    if (s.algebraic > 0) {
      MatrixXd d = MatrixXd::Identity(static_cast<Index>(s.algebraic), static_cast<Index>(s.algebraic));
      for (std::size_t k : neutral) d += std::exp(-s.delays[k] * sigma) * (s.g0 * s.a_aa[k]);
      value *= d.determinant();
    }
    if (s.differential > 0) {
      MatrixXd d = MatrixXd::Identity(static_cast<Index>(s.differential), static_cast<Index>(s.differential));
      for (std::size_t k : neutral) d -= std::exp(-s.delays[k] * sigma) * s.b_dd[k];
      value *= d.determinant();
    }
    return value;
  };
  double tau_min = kInfinity;
  for (std::size_t k : neutral) tau_min = std::min(tau_min, s.delays[k]);
  const double top = std::isfinite(out.upper) ? out.upper : 0.0;
  const double span = 20.0 / tau_min;
  constexpr int samples = 4000;
  double previous_sigma = top, previous = det_on_ray(top);
  for (int i = 1; i <= samples; ++i) {
    const double sigma = top - span * i / samples;
    const double value = det_on_ray(sigma);
    if (!std::isfinite(value)) break;
    if (value == 0.0) {
      out.lower = sigma;
      break;
    }
    if ((value < 0.0) != (previous < 0.0)) {
      double lo = sigma, hi = previous_sigma;
      for (int j = 0; j < 100; ++j) {
        const double mid = 0.5 * (lo + hi);
        const double v = det_on_ray(mid);
        if ((v < 0.0) == (value < 0.0)) lo = mid;
        else hi = mid;
      }
      out.lower = 0.5 * (lo + hi);
      break;
    }
    previous_sigma = sigma;
    previous = value;
  }
  // A zero found within rounding of sigma = 0 is the point z = 1 itself (G1's cumulative removal).
  if (std::abs(out.lower) < 1e-12 / tau_min) out.lower = 0.0;
  // The ray's zero may sit exactly at a point the scan steps over (sigma = 0 for G1): check it.
  if (!(out.lower >= 0.0) && top >= 0.0 && std::abs(det_on_ray(0.0)) <= 1e-12) out.lower = std::max(out.lower, 0.0);
  return out;
}

// ------------------------------------------------------------------ family of steady states

FamilyRoots family_roots(const ReducedSystem& s) {
  FamilyRoots out;
  const Index n = static_cast<Index>(s.size());
  MatrixXd zero_delay = s.a0;  // Delta(0) = -(A0 + sum A_k)
  for (const MatrixXd& a : s.matrices) zero_delay += a;
  VectorXd r, c;
  equilibrate(zero_delay.cwiseAbs() + s.mass.cwiseAbs(), r, c);
  const MatrixXd scaled = r.asDiagonal() * zero_delay * c.asDiagonal();
  Eigen::JacobiSVD<MatrixXd> svd(scaled, Eigen::ComputeFullV);
  const VectorXd& sv = svd.singularValues();
  const double tolerance = 1e-11 * std::max(sv(0), 1e-300);
  Index rank = 0;
  while (rank < n && sv(rank) > tolerance) ++rank;
  const Index kernel_dim = n - rank;
  if (kernel_dim == 0) return out;
  // Kernel vectors in the original variables.
  const MatrixXd kernel = c.asDiagonal() * svd.matrixV().rightCols(kernel_dim);
  // Semisimple (no Jordan chain): Delta'(0) v must not fall into the range of Delta(0) for any
  // kernel vector, i.e. rank [Delta(0), Delta'(0) K] = rank Delta(0) + dim K.
  MatrixXd derivative = s.mass;  // Delta'(0) = E - sum B_k + sum tau_k A_k
  for (std::size_t k = 0; k < s.delays.size(); ++k) {
    derivative += s.delays[k] * s.matrices[k];
    if (s.neutral[k].size()) derivative -= s.neutral[k];
  }
  MatrixXd augmented(n, n + kernel_dim);
  augmented << zero_delay, derivative * kernel;
  VectorXd r2, c2;
  equilibrate(augmented.cwiseAbs(), r2, c2);
  Eigen::JacobiSVD<MatrixXd> svd2(r2.asDiagonal() * augmented * c2.asDiagonal());
  const VectorXd& sv2 = svd2.singularValues();
  Index rank2 = 0;
  while (rank2 < sv2.size() && sv2(rank2) > 1e-11 * std::max(sv2(0), 1e-300)) ++rank2;
  if (rank2 != rank + kernel_dim) return out;  // a Jordan chain: not declared (reported as a root)
  out.multiplicity_at_zero = static_cast<int>(kernel_dim);
  if (kernel_dim != 1) return out;
  const VectorXd v = kernel.col(0);
  const double scale = v.cwiseAbs().maxCoeff();
  auto vanishes = [&](const MatrixXd& m) { return m.size() == 0 || (m * v).cwiseAbs().maxCoeff() <= 1e-12 * scale * std::max(m.cwiseAbs().maxCoeff(), 1e-300); };
  bool algebraic = vanishes(s.mass);
  for (const MatrixXd& b : s.neutral) algebraic = algebraic && vanishes(b);
  if (!algebraic) return out;
  for (std::size_t k = 0; k < s.delays.size(); ++k)
    if (!vanishes(s.matrices[k])) out.lattice_delays_s.push_back(s.delays[k]);
  return out;
}

}  // namespace chatterlab::delay_detail
