// DelayCharacteristic (chatterlab/delay_system.hpp): the certified characteristic function of a
// linear delay-differential(-algebraic) system. The numerics live in delay/structure.* (checks,
// condensation, proven bound, difference operator, family roots) and delay/evaluation.* (det
// Delta by dense LU or by the modal Schur complement); this file assembles them and derives the
// initial guesses. docs/derived_stability.md.
#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "chatterlab/delay_chains.hpp"
#include "chatterlab/delay_system.hpp"
#include "chatterlab/errors.hpp"
#include "delay/determinant.hpp"
#include "delay/evaluation.hpp"
#include "delay/structure.hpp"

namespace chatterlab {

using delay_detail::DenseEvaluator;
using delay_detail::ModalEvaluator;
using delay_detail::ReducedSystem;
using delay_detail::SplitSystem;
using Eigen::Index;
using Eigen::MatrixXd;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Two lattice points of different neutral delays closer than this many radians times the longer
// delay share a neighbourhood: a local quadratic separates their two roots (as MODELS.md G1's
// wheel and work chains near a common frequency).
constexpr double kPairDistance = 0.5;
constexpr double kCommensurateTolerance = 1e-9;

Complex logarithm(Complex z) { return {0.5 * std::log(std::norm(z)), std::arg(z)}; }

void append_eigenvalues(const MatrixXd& m, std::vector<Complex>& out) {
  if (m.size() == 0) return;
  Eigen::EigenSolver<MatrixXd> solver(m, false);
  if (solver.info() != Eigen::Success) return;
  for (const auto& lambda : solver.eigenvalues())
    if (lambda.imag() >= 0.0 && std::isfinite(lambda.real())) out.push_back(lambda);
}

// The zero-delay system (z_k = 1): (I - B(1))^{-1} (A_dd(1) - A_da(1) A_aa(1)^{-1} A_ad(1)), when
// regular. Empty otherwise (G1: the cumulative-removal family makes A_aa(1) singular).
MatrixXd zero_delay_system(const SplitSystem& s) {
  const Index r = static_cast<Index>(s.differential), a = static_cast<Index>(s.algebraic);
  MatrixXd dd = s.a0_dd, da = s.a0_da, ad = s.a0_ad, aa = a > 0 ? MatrixXd(s.g0.inverse()) : MatrixXd(0, 0);
  MatrixXd n = MatrixXd::Identity(r, r);
  for (std::size_t k = 0; k < s.delays.size(); ++k) {
    dd += s.a_dd[k];
    da += s.a_da[k];
    ad += s.a_ad[k];
    if (a > 0) aa += s.a_aa[k];
    n -= s.b_dd[k];
  }
  Eigen::FullPivLU<MatrixXd> n_lu(n);
  if (!n_lu.isInvertible()) return {};
  if (a == 0) return n_lu.solve(dd);
  Eigen::FullPivLU<MatrixXd> aa_lu(aa);
  if (!aa_lu.isInvertible() || aa_lu.rcond() < 1e-12) return {};
  return n_lu.solve(MatrixXd(dd - da * aa_lu.solve(ad)));
}

std::string show(double x) { return fmt::format("{:.6g}", x); }

}  // namespace

struct DelayCharacteristic::Impl {
  LinearDelaySystem original;
  ReducedSystem reduced;
  SplitSystem split;
  delay_detail::RealPartBound bound;
  DenseEvaluator dense;
  std::optional<ModalEvaluator> modal;
  DelaySystemSummary summary;
  delay_detail::FamilyRoots family;
  double natural_frequency_hz = 0.0;
  std::vector<Complex> base_guesses;         // eigenvalues of the undelayed / zero-delay systems
  std::vector<std::size_t> neutral_delays;   // indices into reduced.delays
  std::vector<double> chain_offsets;         // single neutral delay: -Log z_j (chain real parts)
  std::vector<double> chain_phases;          // and their phases
  std::optional<std::size_t> retarded_longest;
  std::size_t retarded_degree = 0;

  explicit Impl(const LinearDelaySystem& system, const DelayCharacteristicOptions& options)
      : original(system),
        reduced(delay_detail::check_and_reduce(system)),
        split(delay_detail::split(reduced)),
        bound(split),
        dense(reduced),
        modal(ModalEvaluator::make(reduced)) {
    summary.states = static_cast<std::size_t>(system.a0.rows());
    summary.differential = split.differential;
    summary.algebraic = split.algebraic + reduced.condensed;
    summary.condensed = reduced.condensed;
    summary.neutral = split.neutral();
    summary.real_part_bound = bound.proven_bound();
    if (!std::isfinite(summary.real_part_bound))
      throw InputError("delay system: no finite bound on the real parts of the roots could be proven (the "
                       "difference operator is not stable for any real part)");
    const delay_detail::DifferenceSpectrum spectrum = delay_detail::difference_spectrum(split, bound);
    summary.difference_spectrum_lower = spectrum.lower;
    summary.difference_spectrum_upper = spectrum.upper;
    family = delay_detail::family_roots(reduced);
    summary.family_roots_at_zero = family.multiplicity_at_zero;
    summary.family_lattice_delays_s = family.lattice_delays_s;
    summary.evaluation = modal ? fmt::format("modal Schur complement ({} modes, {} delayed variables)",
                                             modal->modes(), modal->delayed_variables())
                               : fmt::format("dense LU (n = {})", dense.size());

    append_eigenvalues(split.undelayed, base_guesses);
    append_eigenvalues(zero_delay_system(split), base_guesses);
    if (split.algebraic > 0) append_eigenvalues(split.a0_dd, base_guesses);
    double scale = 0.0;
    for (Complex lambda : base_guesses) scale = std::max(scale, std::abs(lambda));
    if (scale == 0.0) scale = bound.reach(summary.real_part_bound);
    if (!(scale > 0.0) || !std::isfinite(scale))
      scale = 1.0 / *std::max_element(reduced.delays.begin(), reduced.delays.end());
    natural_frequency_hz = options.natural_frequency_hz > 0.0 ? options.natural_frequency_hz : scale / kTwoPi;

    for (std::size_t k = 0; k < reduced.delays.size(); ++k) {
      if (split.neutral_delay[k]) {
        neutral_delays.push_back(k);
      } else if (!reduced.matrices[k].isZero(0.0) &&
                 (!retarded_longest || reduced.delays[k] > reduced.delays[*retarded_longest])) {
        retarded_longest = k;
      }
    }
    if (retarded_longest) {
      Eigen::FullPivLU<MatrixXd> lu(reduced.matrices[*retarded_longest]);
      retarded_degree = static_cast<std::size_t>(lu.rank());
    }
    if (neutral_delays.size() == 1) single_chain_offsets();
  }

  // One neutral delay: the difference operator's chain values z_j (its roots in z); the root
  // chains sit at s = (2 pi j m - Log z_j) / tau.
  void single_chain_offsets() {
    const std::size_t k = neutral_delays.front();
    auto add = [&](const MatrixXd& m, double sign) {
      if (m.size() == 0) return;
      Eigen::EigenSolver<MatrixXd> eig(m, false);
      if (eig.info() != Eigen::Success) return;
      for (const auto& mu : eig.eigenvalues())
        if (std::abs(mu) > 1e-300) {
          const Complex z = 1.0 / (sign * mu);  // z = -1/eig(G0 A_aa) or 1/eig(B)
          const Complex log_z = logarithm(z);
          chain_offsets.push_back(-log_z.real());
          chain_phases.push_back(-log_z.imag());
        }
    };
    if (split.algebraic > 0) add(split.g0 * split.a_aa[k], -1.0);
    add(split.b_dd[k], 1.0);
  }

  CharacteristicValue evaluate(Complex s) const { return modal ? (*modal)(s) : dense(s); }

  void neutral_lattice_guesses(double omega, std::vector<Complex>& guesses) const;
  void retarded_chain_guesses(double omega, std::vector<Complex>& guesses) const;
  bool is_family_root(Complex s, double omega) const;
};

bool DelayCharacteristic::Impl::is_family_root(Complex s, double omega) const {
  if (family.multiplicity_at_zero == 0) return false;
  const double tolerance = 1e-9 * std::max(std::abs(s), 1e-3 * omega);
  if (std::abs(s) <= tolerance) return true;
  return false;
}

void DelayCharacteristic::Impl::neutral_lattice_guesses(double omega, std::vector<Complex>& guesses) const {
  if (neutral_delays.empty()) return;
  // Lattice points of each neutral delay. Where two delays' points nearly coincide, the local
  // model of E is a product of two linear factors: a quadratic through three values of E
  // separates the two roots (the raw points would both lead Newton to one of them).
  struct Point {
    double omega;
    std::size_t delay;
    bool paired = false;
  };
  std::vector<std::vector<Point>> lattices;
  for (std::size_t k : neutral_delays) {
    const double tau = reduced.delays[k];
    std::vector<Point> points;
    const long count = static_cast<long>(omega * tau / kTwoPi) + 2;
    for (long m = 0; m < count; ++m) points.push_back({kTwoPi * static_cast<double>(m) / tau, k});
    lattices.push_back(std::move(points));
  }
  for (std::size_t a = 0; a < lattices.size(); ++a) {
    for (std::size_t b = 0; b < lattices.size(); ++b) {
      const double tau_a = reduced.delays[neutral_delays[a]], tau_b = reduced.delays[neutral_delays[b]];
      if (b == a || tau_a >= tau_b) continue;  // a: the shorter delay (sparser lattice)
      const double spacing_b = kTwoPi / tau_b;
      for (Point& p : lattices[a]) {
        const auto nearest = static_cast<std::size_t>(std::lround(p.omega / spacing_b));
        if (nearest >= lattices[b].size()) continue;
        Point& q = lattices[b][nearest];
        const double delta = q.omega - p.omega;
        if (std::abs(delta) * tau_b > kPairDistance) continue;
        p.paired = q.paired = true;
        // E at three points across the pair: Newton-form quadratic, both roots.
        const double spread = std::max(0.5 * std::abs(delta), 0.05 / tau_b);
        const Complex centre(0.0, 0.5 * (p.omega + q.omega));
        const Complex u0 = centre - Complex(0.0, spread), u1 = centre, u2 = centre + Complex(0.0, spread);
        const Complex e0 = evaluate(u0).value, e1 = evaluate(u1).value, e2 = evaluate(u2).value;
        const Complex d01 = (e1 - e0) / (u1 - u0), d12 = (e2 - e1) / (u2 - u1);
        const Complex c2 = (d12 - d01) / (u2 - u0);
        // E ~ e1 + d (u - u1) + c2 (u - u1)^2 with d = d01 + c2 (u1 - u0).
        const Complex d = d01 + c2 * (u1 - u0);
        if (!(std::norm(c2) > 0.0) || !std::isfinite(std::norm(c2))) {
          guesses.emplace_back(0.0, p.omega);
          guesses.emplace_back(0.0, q.omega);
          continue;
        }
        Complex root_disc = std::sqrt(d * d - 4.0 * c2 * e1);
        if ((std::conj(d) * root_disc).real() < 0.0) root_disc = -root_disc;
        const Complex big = -0.5 * (d + root_disc);
        guesses.push_back(u1 + big / c2);
        if (std::norm(big) > 0.0) guesses.push_back(u1 + e1 / big);
      }
    }
  }
  for (const std::vector<Point>& lattice : lattices)
    for (const Point& p : lattice) {
      if (p.paired) continue;
      const Complex point(0.0, p.omega);
      if (is_family_root(point, omega)) continue;
      const double tau = reduced.delays[p.delay];
      if (chain_offsets.empty()) {
        guesses.push_back(point);
      } else {
        for (std::size_t j = 0; j < chain_offsets.size(); ++j)
          guesses.emplace_back(chain_offsets[j] / tau, p.omega + chain_phases[j] / tau);
      }
    }
}

void DelayCharacteristic::Impl::retarded_chain_guesses(double omega, std::vector<Complex>& guesses) const {
  if (!retarded_longest || retarded_degree == 0) return;
  // Retarded chains of the longest retarded delay tau (the method linear_dde introduced;
  // chatterlab/delay_chains.hpp): the chain factors are the roots z of det(M0(s) - C z), a
  // polynomial of degree <= rank C (M0: Delta without that delay's term). One guess per root of
  // the band, from one fixed-point step.
  const std::size_t k = *retarded_longest, n = dense.size(), nn = n * n;
  const double tau = reduced.delays[k];
  const std::size_t points = retarded_degree + 1;
  const std::vector<Complex> unit = unit_roots(points);
  std::vector<Complex> base(nn), coefficient(nn), work(nn), values(points), poly(points);
  const ChainFactors chain_factors = [&](Complex s, std::vector<Complex>& roots) {
    dense.fill(s, base.data(), nullptr, k);
    dense.delayed_coefficient(k, s, coefficient.data());
    // Values at the roots of unity, then the coefficients (exact for a polynomial of degree <
    // points).
    for (std::size_t j = 0; j < points; ++j) {
      for (std::size_t i = 0; i < nn; ++i) work[i] = base[i] - coefficient[i] * unit[j];
      values[j] = delay_detail::determinant(work.data(), n);
    }
    coefficients_from_unit_root_values(values, unit, poly);
    nonzero_polynomial_roots(poly, roots);
  };
  append_chain_guesses(tau, omega, 1, chain_factors, guesses);
}

// ------------------------------------------------------------------ public class

DelayCharacteristic::DelayCharacteristic(const LinearDelaySystem& system, const DelayCharacteristicOptions& options)
    : impl_(std::make_unique<const Impl>(system, options)) {}

DelayCharacteristic::~DelayCharacteristic() = default;

CharacteristicValue DelayCharacteristic::evaluate(Complex s) const { return impl_->evaluate(s); }

CharacteristicValue DelayCharacteristic::evaluate_dense(Complex s) const { return impl_->dense(s); }

const DelaySystemSummary& DelayCharacteristic::summary() const { return impl_->summary; }

double DelayCharacteristic::real_part_bound() const { return impl_->summary.real_part_bound; }

double DelayCharacteristic::natural_frequency_scale_hz() const { return impl_->natural_frequency_hz; }

std::vector<Complex> DelayCharacteristic::neutral_roots(double omega) const {
  std::vector<Complex> roots;
  const delay_detail::FamilyRoots& family = impl_->family;
  for (int i = 0; i < family.multiplicity_at_zero; ++i) roots.emplace_back(0.0, 0.0);
  if (family.multiplicity_at_zero != 1 || family.lattice_delays_s.empty()) return roots;
  // The family direction sees only the delays acting on it: wherever all of their lattices meet,
  // z_k = 1 for each and Delta(i w) v = Delta(0) v = 0.
  const std::vector<double>& taus = family.lattice_delays_s;
  const double base = *std::min_element(taus.begin(), taus.end());
  for (long n = 1; kTwoPi * static_cast<double>(n) / base <= omega; ++n) {
    double sum = kTwoPi * static_cast<double>(n) / base;
    bool common = true;
    for (double tau : taus) {
      if (tau == base) continue;
      const double m_exact = static_cast<double>(n) * tau / base, m = std::round(m_exact);
      if (m < 1.0 || std::abs(m_exact - m) > kCommensurateTolerance * m_exact) {
        common = false;
        break;
      }
      sum += kTwoPi * m / tau;
    }
    if (common) roots.emplace_back(0.0, sum / static_cast<double>(taus.size()));
  }
  return roots;
}

void DelayCharacteristic::initial_guesses(double omega, std::vector<Complex>& guesses) const {
  guesses.insert(guesses.end(), impl_->base_guesses.begin(), impl_->base_guesses.end());
  impl_->neutral_lattice_guesses(omega, guesses);
  impl_->retarded_chain_guesses(omega, guesses);
}

std::string DelayCharacteristic::certificate_note(double sigma_c, double band) const {
  const DelaySystemSummary& s = impl_->summary;
  std::string note;
  if (s.neutral) {
    const double lo = s.difference_spectrum_lower, hi = s.difference_spectrum_upper;
    std::string where;
    if (lo == hi) where = "= " + show(hi);
    else if (std::isfinite(lo)) where = fmt::format("in [{}, {}]", show(lo), show(hi));
    else where = "<= " + show(hi);
    note = fmt::format("neutral type: beyond the band the root chains approach the difference operator's "
                       "spectrum (sup Re s {})", where);
  }
  const double reach = impl_->bound.reach(sigma_c);
  std::string coverage;
  if (std::isfinite(reach) && reach <= band)
    coverage = fmt::format("global: every root with Re s >= {} has |s| <= {} (proven), inside the band",
                           show(sigma_c), show(reach));
  else if (std::isfinite(reach))
    coverage = fmt::format("roots beyond the band are not covered (proven only |s| <= {} for Re s >= {})",
                           show(reach), show(sigma_c));
  else
    coverage = "roots beyond the band are not covered";
  return note.empty() ? coverage : note + "; " + coverage;
}

Eigen::MatrixXcd DelayCharacteristic::matrix(Complex s) const {
  const LinearDelaySystem& sys = impl_->original;
  const Index n = sys.a0.rows();
  const MatrixXd mass = sys.mass.size() ? sys.mass : MatrixXd::Identity(n, n);
  Eigen::MatrixXcd m = s * mass.cast<Complex>() - sys.a0.cast<Complex>();
  for (const DelayTerm& t : sys.delayed) {
    const Complex z = std::exp(-t.delay_s * s);
    if (t.matrix.size()) m -= z * t.matrix.cast<Complex>();
    if (t.neutral_matrix.size()) m -= s * z * t.neutral_matrix.cast<Complex>();
  }
  return m;
}

}  // namespace chatterlab
