#include "delay/evaluation.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "delay/determinant.hpp"

namespace chatterlab::delay_detail {

namespace {

using Eigen::Index;
using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// e^{-tau s} without cexp's special-value handling.
inline Complex delay_factor(double tau, Complex s) {
  const double magnitude = std::exp(-tau * s.real());
  const double phase = tau * s.imag();
  return {magnitude * std::cos(phase), -magnitude * std::sin(phase)};
}

std::vector<double> row_major(const MatrixXd& m) {
  std::vector<double> out(static_cast<std::size_t>(m.size()));
  for (Index i = 0; i < m.rows(); ++i)
    for (Index j = 0; j < m.cols(); ++j) out[static_cast<std::size_t>(i * m.cols() + j)] = m(i, j);
  return out;
}

}  // namespace

// ------------------------------------------------------------------ dense

DenseEvaluator::DenseEvaluator(const ReducedSystem& s) : n_(s.size()) {
  // Powers-of-two row and column scaling from the magnitudes of all coefficients, so that LU with
  // partial pivoting sees O(1) entries whatever the physical units (det changes by a constant).
  MatrixXd magnitude = s.mass.cwiseAbs() + s.a0.cwiseAbs();
  for (std::size_t k = 0; k < s.delays.size(); ++k) {
    magnitude += s.matrices[k].cwiseAbs();
    if (s.neutral[k].size()) magnitude += s.neutral[k].cwiseAbs();
  }
  VectorXd r, c;
  equilibrate(magnitude, r, c);
  auto scaled = [&](const MatrixXd& m) { return MatrixXd(r.asDiagonal() * m * c.asDiagonal()); };
  mass_ = row_major(scaled(s.mass));
  a0_ = row_major(scaled(s.a0));
  for (std::size_t k = 0; k < s.delays.size(); ++k) {
    Term term{s.delays[k], {}, {}};
    const std::vector<double> a = row_major(scaled(s.matrices[k]));
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a[i] != 0.0) term.a.push_back({i, a[i]});
    if (s.neutral[k].size()) {
      const std::vector<double> b = row_major(scaled(s.neutral[k]));
      for (std::size_t i = 0; i < b.size(); ++i)
        if (b[i] != 0.0) term.b.push_back({i, b[i]});
    }
    terms_.push_back(std::move(term));
  }
}

void DenseEvaluator::fill(Complex s, Complex* m, Complex* dm, std::size_t skip) const {
  // Delta = s N(z) - A(z), N = E - sum B_k z_k; Delta' = N(z) + sum_k tau_k z_k (A_k + s B_k).
  const std::size_t nn = n_ * n_;
  for (std::size_t i = 0; i < nn; ++i) {
    m[i] = s * mass_[i] - a0_[i];
    if (dm) dm[i] = mass_[i];
  }
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    if (k == skip) continue;
    const Term& t = terms_[k];
    const Complex z = delay_factor(t.delay_s, s);
    const Complex tau_z = t.delay_s * z;
    for (const Entry& e : t.a) {
      m[e.index] -= e.value * z;
      if (dm) dm[e.index] += e.value * tau_z;
    }
    for (const Entry& e : t.b) {
      m[e.index] -= s * e.value * z;
      if (dm) dm[e.index] += e.value * (tau_z * s - z);
    }
  }
}

void DenseEvaluator::delayed_coefficient(std::size_t k, Complex s, Complex* out) const {
  std::fill(out, out + n_ * n_, Complex(0.0));
  for (const Entry& e : terms_[k].a) out[e.index] += e.value;
  for (const Entry& e : terms_[k].b) out[e.index] += s * e.value;
}

CharacteristicValue DenseEvaluator::operator()(Complex s) const {
  const std::size_t nn = n_ * n_;
  ComplexScratch<2 * 64> storage(2 * nn);
  Complex* m = storage.data();
  Complex* dm = m + nn;
  fill(s, m, dm);
  return determinant_and_derivative(m, dm, n_);
}

// ------------------------------------------------------------------ modal Schur complement

std::optional<ModalEvaluator> ModalEvaluator::make(const ReducedSystem& s) {
  const Index m = static_cast<Index>(s.size());
  const std::size_t delay_count = s.delays.size();
  std::vector<Index> delayed, undelayed;
  for (Index j = 0; j < m; ++j) {
    bool any = false;
    for (std::size_t k = 0; k < delay_count; ++k)
      any = any || !s.matrices[k].col(j).isZero(0.0) || (s.neutral[k].size() && !s.neutral[k].col(j).isZero(0.0));
    (any ? delayed : undelayed).push_back(j);
  }
  const Index d = static_cast<Index>(delayed.size()), u = static_cast<Index>(undelayed.size());
  // Worth it when the undelayed part is larger than the delayed one (G1: 2 modes per structural
  // mode against 2 surfaces); a dense LU is as fast for small systems.
  if (u < 2 || u <= d || d == 0) return std::nullopt;
  auto cols = [&](const MatrixXd& x, const std::vector<Index>& c) {
    MatrixXd out(x.rows(), static_cast<Index>(c.size()));
    for (std::size_t j = 0; j < c.size(); ++j) out.col(static_cast<Index>(j)) = x.col(c[j]);
    return out;
  };
  // Rows R_I: the u rows of E[:, I] with a regular block (full-pivoting LU picks them).
  const MatrixXd e_undelayed = cols(s.mass, undelayed);
  Eigen::FullPivLU<MatrixXd> pick(e_undelayed);
  if (pick.rank() < u) return std::nullopt;
  std::vector<Index> rows_i, rows_d;
  std::vector<bool> used(static_cast<std::size_t>(m), false);
  // P E Q = L U moves row j to position P(j): the pivot rows are those placed first.
  for (Index j = 0; j < m; ++j)
    if (pick.permutationP().indices()(j) < u) {
      rows_i.push_back(j);
      used[static_cast<std::size_t>(j)] = true;
    }
  for (Index i = 0; i < m; ++i)
    if (!used[static_cast<std::size_t>(i)]) rows_d.push_back(i);
  auto block = [&](const MatrixXd& x, const std::vector<Index>& r, const std::vector<Index>& c) {
    MatrixXd out(static_cast<Index>(r.size()), static_cast<Index>(c.size()));
    for (std::size_t i = 0; i < r.size(); ++i)
      for (std::size_t j = 0; j < c.size(); ++j) out(static_cast<Index>(i), static_cast<Index>(j)) = x(r[i], c[j]);
    return out;
  };
  const MatrixXd e11 = block(s.mass, rows_i, undelayed), a11 = block(s.a0, rows_i, undelayed);
  Eigen::PartialPivLU<MatrixXd> e11_lu(e11);
  if (!(e11_lu.rcond() > 1e-10)) return std::nullopt;
  // M = E11^{-1} A11, balanced first (physical units put w^2 next to 1 in a modal block; the
  // eigenvectors of the balanced matrix are well conditioned): Mb = D M D^{-1}, V = D^{-1} Vb.
  const MatrixXd state = e11_lu.solve(a11);
  const VectorXd balance = osborne(state);
  const MatrixXd balanced = balance.asDiagonal() * state * balance.cwiseInverse().asDiagonal();
  Eigen::EigenSolver<MatrixXd> eig(balanced, true);
  if (eig.info() != Eigen::Success) return std::nullopt;
  // Modes: real eigenvalues and one member (Im > 0) of each conjugate pair; V built with the
  // partner's vector as the exact conjugate, so that the pair's fractions are exact conjugates.
  std::vector<std::size_t> real_index, pair_index;
  for (Index i = 0; i < u; ++i) {
    const double im = eig.eigenvalues()(i).imag();
    if (im == 0.0) real_index.push_back(static_cast<std::size_t>(i));
    else if (im > 0.0) pair_index.push_back(static_cast<std::size_t>(i));
  }
  if (real_index.size() + 2 * pair_index.size() != static_cast<std::size_t>(u)) return std::nullopt;
  MatrixXcd v(u, u);
  Index col = 0;
  for (std::size_t i : real_index) v.col(col++) = eig.eigenvectors().col(static_cast<Index>(i)).real().cast<Complex>();
  for (std::size_t i : pair_index) {
    v.col(col++) = eig.eigenvectors().col(static_cast<Index>(i));
    v.col(col++) = eig.eigenvectors().col(static_cast<Index>(i)).conjugate();
  }
  Eigen::PartialPivLU<MatrixXcd> v_lu(v);
  // The fractions' accuracy follows the conditioning of the eigenvector basis (defective or nearly
  // defective pencils go to the dense route).
  if (!(v_lu.rcond() > 1e-8)) return std::nullopt;
  // V^{-1} E11^{-1} with V = D Vb: Vb^{-1} D^{-1} E11^{-1}.
  const MatrixXd inverse_e11 = e11_lu.solve(MatrixXd::Identity(u, u));
  const MatrixXcd w = v_lu.solve((balance.asDiagonal() * inverse_e11).cast<Complex>());
  v = balance.cwiseInverse().asDiagonal() * v;

  const MatrixXd e12 = block(s.mass, rows_i, delayed), a12 = block(s.a0, rows_i, delayed);
  const MatrixXd e21 = block(s.mass, rows_d, undelayed), a21 = block(s.a0, rows_d, undelayed);
  const MatrixXd e22 = block(s.mass, rows_d, delayed), a22 = block(s.a0, rows_d, delayed);
  std::vector<MatrixXd> a12k, b12k, a22k, b22k;
  for (std::size_t k = 0; k < delay_count; ++k) {
    a12k.push_back(block(s.matrices[k], rows_i, delayed));
    a22k.push_back(block(s.matrices[k], rows_d, delayed));
    const MatrixXd b = s.neutral[k].size() ? s.neutral[k] : MatrixXd::Zero(m, m);
    b12k.push_back(block(b, rows_i, delayed));
    b22k.push_back(block(b, rows_d, delayed));
  }

  ModalEvaluator out;
  out.d_ = static_cast<std::size_t>(d);
  out.delays_ = s.delays;
  // Per mode and z power: the numerator s^2 C2 + s C1 + C0 of (Delta21 v)(w Delta12) / (s - lambda)
  // (z^0: (s p - q)(s e - a); z_k: -(s p - q)(g_k + s h_k)), split into its polynomial part
  // s C2 + (lambda C2 + C1), summed over the modes into F_k, G_k, and N = lambda^2 C2 + lambda C1 + C0.
  std::vector<MatrixXcd> poly2(delay_count + 1, MatrixXcd::Zero(d, d)), poly1(delay_count + 1, MatrixXcd::Zero(d, d));
  auto fractions_of = [&](Index mode, Complex lambda) {
    const Eigen::VectorXcd p = e21.cast<Complex>() * v.col(mode), q = a21.cast<Complex>() * v.col(mode);
    const Eigen::RowVectorXcd wi = w.row(mode);
    std::vector<std::pair<std::size_t, MatrixXcd>> numerators;
    for (std::size_t k = 0; k <= delay_count; ++k) {
      MatrixXcd c2, c1, c0;
      if (k == 0) {
        const Eigen::RowVectorXcd e = wi * e12.cast<Complex>(), a = wi * a12.cast<Complex>();
        c2 = p * e;
        c1 = -(p * a + q * e);
        c0 = q * a;
      } else {
        const Eigen::RowVectorXcd g = wi * a12k[k - 1].cast<Complex>(), h = wi * b12k[k - 1].cast<Complex>();
        c2 = -(p * h);
        c1 = -(p * g - q * h);
        c0 = q * g;
      }
      poly2[k] += c2;
      poly1[k] += lambda * c2 + c1;
      const MatrixXcd n = lambda * lambda * c2 + lambda * c1 + c0;
      numerators.emplace_back(k, n);
    }
    return numerators;
  };
  auto as_fraction = [&](std::size_t k, const MatrixXcd& n) {
    Fraction f{k, {}, {}};
    for (Index i = 0; i < d; ++i)
      for (Index j = 0; j < d; ++j) {
        f.real.push_back(n(i, j).real());
        f.imag.push_back(n(i, j).imag());
      }
    return f;
  };
  auto significant = [](const MatrixXcd& n) { return n.cwiseAbs().maxCoeff() > 0.0; };
  col = 0;
  for (std::size_t i : real_index) {
    const double lambda = eig.eigenvalues()(static_cast<Index>(i)).real();
    RealMode mode{lambda, std::abs(lambda) > 0.0 ? std::abs(lambda) : 1.0, {}};
    for (const auto& [k, n] : fractions_of(col, lambda))
      if (significant(n)) mode.fractions.push_back(as_fraction(k, n));
    out.real_modes_.push_back(std::move(mode));
    ++col;
  }
  for (std::size_t i : pair_index) {
    const Complex lambda = eig.eigenvalues()(static_cast<Index>(i));
    Pair pair{lambda.real(), lambda.imag(), 1.0 / std::norm(lambda), {}};
    // The partner's numerators are the conjugates: its polynomial parts are added here too.
    for (const auto& [k, n] : fractions_of(col, lambda)) {
      if (significant(n)) pair.fractions.push_back(as_fraction(k, n));
    }
    fractions_of(col + 1, std::conj(lambda));  // adds the partner's polynomial parts
    out.pairs_.push_back(std::move(pair));
    col += 2;
  }
  // F_k, G_k: the delayed block minus the polynomial parts (real up to rounding).
  for (std::size_t k = 0; k <= delay_count; ++k) {
    MatrixXd f, g;
    if (k == 0) {
      f = e22 - poly2[0].real();
      g = a22 + poly1[0].real();
    } else {
      f = -(b22k[k - 1] + poly2[k].real());
      g = a22k[k - 1] + poly1[k].real();
    }
    out.f_.push_back(row_major(f));
    out.g_.push_back(row_major(g));
  }
  return out;
}

CharacteristicValue ModalEvaluator::operator()(Complex s) const {
  const std::size_t dd = d_ * d_, powers = delays_.size() + 1;
  // C_k = sum_i N_ik / (s - lambda_i) and D_k = sum_i N_ik / (s - lambda_i)^2 (minus C_k').
  ComplexScratch<4 * 16> storage(4 * dd * powers);
  Complex* c = storage.data();
  Complex* dc = c + dd * powers;
  Complex* r = dc + dd * powers;
  Complex* dr = r + dd * powers;
  std::fill(c, c + 2 * dd * powers, Complex(0.0));
  Complex product = 1.0, log_derivative = 0.0;  // prod (s - lambda_i)/scale_i and its d log
  for (const RealMode& mode : real_modes_) {
    const Complex difference = s - mode.lambda;
    const Complex reciprocal = 1.0 / difference, reciprocal2 = reciprocal * reciprocal;
    product *= difference / mode.scale;
    log_derivative += reciprocal;
    for (const Fraction& f : mode.fractions) {
      Complex* ck = c + f.k * dd;
      Complex* dck = dc + f.k * dd;
      for (std::size_t e = 0; e < dd; ++e) {
        ck[e] += reciprocal * f.real[e];
        dck[e] += reciprocal2 * f.real[e];
      }
    }
  }
  for (const Pair& pair : pairs_) {
    // (s - lambda)(s - conj lambda) = s^2 - 2 Re(lambda) s + |lambda|^2 = Q. With r, r' the two
    // reciprocals: r + r' = 2 (s - Re lambda)/Q, i (r - r') = -2 Im(lambda)/Q, and
    // r N + r' conj(N) = (r + r') Re N + i (r - r') Im N; likewise for r^2, r'^2.
    const Complex q = s * (s - 2.0 * pair.re) + (pair.re * pair.re + pair.im * pair.im);
    const Complex inverse = 1.0 / q;
    const Complex sum = 2.0 * (s - pair.re) * inverse;      // r + r'
    const Complex twist = -2.0 * pair.im * inverse;         // i (r - r')
    const Complex sum2 = sum * sum - 2.0 * inverse;         // r^2 + r'^2
    const Complex twist2 = twist * sum;                     // i (r^2 - r'^2)
    product *= q * pair.inverse_modulus_squared;
    log_derivative += sum;
    for (const Fraction& f : pair.fractions) {
      Complex* ck = c + f.k * dd;
      Complex* dck = dc + f.k * dd;
      for (std::size_t e = 0; e < dd; ++e) {
        ck[e] += sum * f.real[e] + twist * f.imag[e];
        dck[e] += sum2 * f.real[e] + twist2 * f.imag[e];
      }
    }
  }
  // R = sum_k z_k (s F_k - G_k - C_k);  R' = sum_k z_k (F_k + D_k) - tau_k z_k (s F_k - G_k - C_k).
  for (std::size_t e = 0; e < dd; ++e) {
    r[e] = s * f_[0][e] - g_[0][e] - c[e];
    dr[e] = f_[0][e] + dc[e];
  }
  for (std::size_t k = 1; k < powers; ++k) {
    const Complex z = delay_factor(delays_[k - 1], s), tau_z = delays_[k - 1] * z;
    const Complex* ck = c + k * dd;
    const Complex* dck = dc + k * dd;
    for (std::size_t e = 0; e < dd; ++e) {
      const Complex term = s * f_[k][e] - g_[k][e] - ck[e];
      r[e] += z * term;
      dr[e] += z * (f_[k][e] + dck[e]) - tau_z * term;
    }
  }
  const CharacteristicValue reduced = determinant_and_derivative(r, dr, d_);
  return {product * reduced.value, product * (log_derivative * reduced.value + reduced.derivative)};
}

}  // namespace chatterlab::delay_detail
