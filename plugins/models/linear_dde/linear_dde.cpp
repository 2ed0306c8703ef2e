#include "models/linear_dde/linear_dde.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "chatterlab/complex_determinant.hpp"
#include "chatterlab/delay_chains.hpp"
#include "chatterlab/delay_system.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/param_table.hpp"

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Guesses along the imaginary axis, spaced by this fraction of 2 pi / tau_max: a retarded chain
// has one root per 2 pi / tau of frequency, so each root has a guess within a quarter spacing.
constexpr double kSweepFraction = 0.5;
// Fixed-point steps on the chain equation s = (2 pi j m - Log z(s)) / tau before Newton.
constexpr int kChainFixedPointSteps = 1;

double induced_norm(const std::vector<double>& a, std::size_t n, bool by_rows) {
  double worst = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    double sum = 0.0;
    for (std::size_t j = 0; j < n; ++j) sum += std::abs(by_rows ? a[i * n + j] : a[j * n + i]);
    worst = std::max(worst, sum);
  }
  return worst;
}

std::vector<double> row_major(const std::vector<std::vector<double>>& rows) {
  std::vector<double> out;
  for (const auto& row : rows) out.insert(out.end(), row.begin(), row.end());
  return out;
}

void append_eigenvalues(const std::vector<double>& a, std::size_t n, std::vector<Complex>& out) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = a[i * n + j];
  Eigen::EigenSolver<Eigen::MatrixXd> solver(m, false);
  if (solver.info() != Eigen::Success) return;
  for (const auto& lambda : solver.eigenvalues())
    if (lambda.imag() >= 0.0) out.push_back(lambda);
}

}  // namespace

// ------------------------------------------------------------------ characteristic function

LinearDdeCharacteristic::LinearDdeCharacteristic(const LinearDdeParameters& p)
    : n_(p.a0.size()), a0_(row_major(p.a0)) {
  std::vector<double> sum = a0_;
  double norm_rows = induced_norm(a0_, n_, true), norm_cols = induced_norm(a0_, n_, false);
  // Terms with the same delay share e^{-tau s}: one matrix each delay (the DDE-BIFTOOL neuron's
  // tau1 = tau2 = 0.2 make three terms two exponentials per evaluation).
  for (const DelayedTerm& term : p.delayed) {
    const std::vector<double> a = row_major(term.matrix);
    auto same = std::find(delays_.begin(), delays_.end(), term.delay_s);
    if (same == delays_.end()) {
      delays_.push_back(term.delay_s);
      matrices_.push_back(a);
    } else {
      std::vector<double>& merged = matrices_[static_cast<std::size_t>(same - delays_.begin())];
      for (std::size_t i = 0; i < merged.size(); ++i) merged[i] += a[i];
    }
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += a[i];
  }
  for (const std::vector<double>& a : matrices_) {
    norm_rows += induced_norm(a, n_, true);
    norm_cols += induced_norm(a, n_, false);
  }
  norm_bound_ = std::min(norm_rows, norm_cols);
  unit_roots_ = unit_roots(n_ + 1);
  if (!delays_.empty())
    longest_ = static_cast<std::size_t>(std::max_element(delays_.begin(), delays_.end()) - delays_.begin());
  // s = eigenvalue of A0 is exact for vanishing delayed terms; of A0 + sum A_k for vanishing
  // delays: the two ends between which the low-frequency roots move.
  append_eigenvalues(a0_, n_, eigenvalues_);
  if (!delays_.empty()) append_eigenvalues(sum, n_, eigenvalues_);
}

void LinearDdeCharacteristic::fill(Complex s, Complex* m, Complex* dm, std::size_t skip) const {
  const std::size_t nn = n_ * n_;
  for (std::size_t i = 0; i < nn; ++i) {
    m[i] = -a0_[i];
    if (dm) dm[i] = 0.0;
  }
  for (std::size_t i = 0; i < n_; ++i) {
    m[i * n_ + i] += s;
    if (dm) dm[i * n_ + i] = 1.0;
  }
  for (std::size_t k = 0; k < delays_.size(); ++k) {
    if (k == skip) continue;
    const double tau = delays_[k];
    const double magnitude = std::exp(-tau * s.real());
    const Complex z(magnitude * std::cos(tau * s.imag()), -magnitude * std::sin(tau * s.imag()));
    const Complex tau_z = tau * z;
    const std::vector<double>& a = matrices_[k];
    for (std::size_t i = 0; i < nn; ++i) {
      if (a[i] == 0.0) continue;
      m[i] -= a[i] * z;
      if (dm) dm[i] += a[i] * tau_z;
    }
  }
}

CharacteristicValue LinearDdeCharacteristic::evaluate(Complex s) const {
  // M = sI - A0 - sum A_k z_k and M' = I + sum tau_k A_k z_k with z_k = e^{-tau_k s}; small
  // systems live on the stack (no allocation per evaluation).
  if (n_ == 2) {
    // Two states (the common small DDE): M and M' in registers, det and its derivative directly.
    Complex m[4] = {s - a0_[0], -a0_[1], -a0_[2], s - a0_[3]}, dm[4] = {1.0, 0.0, 0.0, 1.0};
    for (std::size_t k = 0; k < delays_.size(); ++k) {
      const double tau = delays_[k], magnitude = std::exp(-tau * s.real());
      const Complex z(magnitude * std::cos(tau * s.imag()), -magnitude * std::sin(tau * s.imag()));
      const Complex tau_z = tau * z;
      const double* a = matrices_[k].data();
      for (int i = 0; i < 4; ++i) {
        if (a[i] == 0.0) continue;  // (as fill(): an overflowing z must not make 0 * inf)
        m[i] -= a[i] * z;
        dm[i] += a[i] * tau_z;
      }
    }
    return {m[0] * m[3] - m[1] * m[2], dm[0] * m[3] + m[0] * dm[3] - dm[1] * m[2] - m[1] * dm[2]};
  }
  const std::size_t nn = n_ * n_;
  ComplexScratch<2 * 36> storage(2 * nn);  // M and M'; no allocation up to 6 x 6
  Complex* m = storage.data();
  Complex* dm = m + nn;
  fill(s, m, dm, delays_.size());
  switch (n_) {
    case 1: return {m[0], dm[0]};
    case 2: return {m[0] * m[3] - m[1] * m[2], dm[0] * m[3] + m[0] * dm[3] - dm[1] * m[2] - m[1] * dm[2]};
    default: return complex_determinant_and_derivative(m, dm, n_);
  }
}

void LinearDdeCharacteristic::chain_factors(Complex s, std::vector<Complex>& roots) const {
  // det(M0 - A z), M0 = sI - A0 - (the other delayed terms at s), A = the longest delay's matrix,
  // is a polynomial of degree <= n in z; its roots are the chains' values of z = e^{-tau s}.
  const std::size_t nn = n_ * n_, points = n_ + 1;
  ComplexScratch<36 + 8> storage(nn + points);
  Complex* base = storage.data();
  Complex* coefficients = base + nn;
  fill(s, base, nullptr, longest_);
  const std::vector<double>& a = matrices_[longest_];
  if (n_ == 1) {
    coefficients[0] = base[0];
    coefficients[1] = -a[0];
  } else if (n_ == 2) {
    // (m00 - a00 z)(m11 - a11 z) - (m01 - a01 z)(m10 - a10 z), expanded.
    coefficients[0] = base[0] * base[3] - base[1] * base[2];
    coefficients[1] = -(base[0] * a[3] + a[0] * base[3]) + (base[1] * a[2] + a[1] * base[2]);
    coefficients[2] = a[0] * a[3] - a[1] * a[2];
  } else {
    // Values at the n + 1 roots of unity, then the inverse discrete Fourier transform (exact for a
    // polynomial of degree <= n).
    std::vector<Complex> work(nn), values(points);
    for (std::size_t j = 0; j < points; ++j) {
      for (std::size_t i = 0; i < nn; ++i) work[i] = base[i] - a[i] * unit_roots_[j];
      values[j] = complex_determinant(work.data(), n_);
    }
    coefficients_from_unit_root_values({values.data(), points}, unit_roots_, {coefficients, points});
  }
  // Degree = how far the delayed coupling reaches (rank of A for generic M0); rounding leaves
  // tiny top coefficients, which nonzero_polynomial_roots does not count.
  nonzero_polynomial_roots({coefficients, points}, roots);
}

void LinearDdeCharacteristic::initial_guesses(double max_angular_frequency,
                                              std::vector<Complex>& guesses) const {
  guesses.insert(guesses.end(), eigenvalues_.begin(), eigenvalues_.end());
  if (delays_.empty()) return;  // an ODE: the eigenvalues are the roots
  // Retarded chains of the longest delay tau (chatterlab/delay_chains.hpp): the chain factors are
  // the roots z of det(M0(s) - A z). One guess per root of the band.
  const double tau = delays_[longest_];
  const bool any_chain = append_chain_guesses(
      tau, max_angular_frequency, kChainFixedPointSteps,
      [this](Complex s, std::vector<Complex>& factors) { chain_factors(s, factors); }, guesses);
  if (any_chain) return;
  // No delayed coupling in the longest delay's matrix (all zero): sweep the axis instead.
  const double spacing = kSweepFraction * kTwoPi / tau;
  for (double y = 0.0; y <= max_angular_frequency + spacing; y += spacing) guesses.emplace_back(0.0, y);
}

double LinearDdeCharacteristic::real_part_bound() const {
  // A zero with Re s >= 0 has s x = (A0 + sum A_k e^{-tau_k s}) x for some x != 0 and
  // |e^{-tau_k s}| <= 1, so |s| <= ||A0|| + sum ||A_k|| in any induced norm.
  return 1.01 * norm_bound_ + 1e-9;
}

double LinearDdeCharacteristic::natural_frequency_scale_hz() const {
  double scale = 0.0;
  for (Complex lambda : eigenvalues_) scale = std::max(scale, std::abs(lambda));
  if (scale == 0.0) scale = norm_bound_;
  if (scale == 0.0) scale = delays_.empty() ? 1.0 : 1.0 / *std::max_element(delays_.begin(), delays_.end());
  return scale / kTwoPi;
}

// ------------------------------------------------------------------ model plugin

namespace {

std::string shape(const std::vector<std::vector<double>>& m) {
  if (m.empty()) return "empty";
  return fmt::format("{}x{}", m.size(), m.front().size());
}

bool is_square_of(const std::vector<std::vector<double>>& m, std::size_t n) {
  if (m.size() != n) return false;
  return std::all_of(m.begin(), m.end(), [n](const std::vector<double>& row) { return row.size() == n; });
}

// The parameter validator checks types, limits and that each matrix is rectangular; sizes that
// must agree across keys are this model's to check. Paths are as a study writes them ([model]).
void check_sizes(const LinearDdeParameters& p) {
  const std::size_t n = p.a0.size();
  if (n == 0 || !is_square_of(p.a0, n))
    throw InputError(fmt::format("model.a0 is {}: the state matrix A0 must be square (n x n)",
                                 shape(p.a0)));
  if (!p.mass.empty() && !is_square_of(p.mass, n))
    throw InputError(fmt::format("model.mass is {} but model.a0 is {}x{}: the mass matrix must be "
                                 "square with the size of a0", shape(p.mass), n, n));
  for (std::size_t k = 0; k < p.delayed.size(); ++k) {
    const DelayedTerm& term = p.delayed[k];
    if (!is_square_of(term.matrix, n))
      throw InputError(fmt::format(
          "model.delayed.{}.matrix is {} but model.a0 is {}x{}: every delayed matrix must be "
          "square with the size of a0", k, shape(term.matrix), n, n));
    if (!term.neutral_matrix.empty() && !is_square_of(term.neutral_matrix, n))
      throw InputError(fmt::format(
          "model.delayed.{}.neutral_matrix is {} but model.a0 is {}x{}: every neutral matrix must be "
          "square with the size of a0", k, shape(term.neutral_matrix), n, n));
    if (!(term.delay_s > 0.0) || !std::isfinite(term.delay_s))
      throw InputError(fmt::format("model.delayed.{}.delay_s = {}: must be finite and > 0", k,
                                   term.delay_s));
  }
}

const ParamTable<LinearDdeParameters>& parameters_table() {
  static const ParamTable<LinearDdeParameters> table = [] {
    ParamTable<DelayedTerm> term;
    term.add(&DelayedTerm::delay_s, "delay_s", "s", "delay tau_k").positive().required();
    term.add(&DelayedTerm::matrix, "matrix", "1/s", "delayed matrix A_k (n x n, the size of a0)")
        .min_items(1)
        .required();
    term.add(&DelayedTerm::neutral_matrix, "neutral_matrix", "1",
             "neutral matrix B_k of x'(t - tau_k) on the left (n x n); omitted: none");
    ParamTable<LinearDdeParameters> t;
    t.add(&LinearDdeParameters::a0, "a0", "1/s", "state matrix A0 (n x n) of x' = A0 x + sum_k A_k x(t - tau_k)")
        .min_items(1)
        .required();
    t.add(&LinearDdeParameters::mass, "mass", "1",
          "mass matrix M of M x' (n x n; may be singular: zero rows are algebraic equations); "
          "omitted: the identity");
    t.add_tables(&LinearDdeParameters::delayed, "delayed", "delayed terms A_k x(t - tau_k); empty: an ODE", term);
    return t;
  }();
  return table;
}

Eigen::MatrixXd to_eigen(const std::vector<std::vector<double>>& m) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(m.size()), static_cast<Eigen::Index>(m.size()));
  for (std::size_t i = 0; i < m.size(); ++i)
    for (std::size_t j = 0; j < m.size(); ++j) out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = m[i][j];
  return out;
}

LinearDelaySystem delay_system(const LinearDdeParameters& p) {
  LinearDelaySystem system;
  if (!p.mass.empty()) system.mass = to_eigen(p.mass);
  system.a0 = to_eigen(p.a0);
  for (const DelayedTerm& term : p.delayed)
    system.delayed.push_back(
        {term.delay_s, to_eigen(term.matrix), term.neutral_matrix.empty() ? Eigen::MatrixXd() : to_eigen(term.neutral_matrix)});
  return system;
}

}  // namespace

bool LinearDdeParameters::general() const {
  return !mass.empty() ||
         std::any_of(delayed.begin(), delayed.end(), [](const DelayedTerm& t) { return !t.neutral_matrix.empty(); });
}

namespace {

// A study's table is validated (defaults filled in) before a model is built; a table given
// directly (tests, the SDK's conformance run of example_params) may omit the optional matrices.
Json with_optional_matrices(Json table) {
  if (!table.contains("mass")) table["mass"] = Json::array();
  if (table.contains("delayed") && table["delayed"].is_array())
    for (Json& term : table["delayed"])
      if (term.is_object() && !term.contains("neutral_matrix")) term["neutral_matrix"] = Json::array();
  return table;
}

}  // namespace

LinearDde::LinearDde(const ParamValues& values)
    : LinearDde(parameters_table().read(with_optional_matrices(values.json()))) {}

LinearDde::LinearDde(LinearDdeParameters parameters) : parameters_(std::move(parameters)) {
  check_sizes(parameters_);
  // The general route checks the system at load (index > 1, neutral terms on algebraic rows):
  // its message names the matrix; the study's load adds the file.
  if (parameters_.general()) {
    try {
      DelayCharacteristic check(delay_system(parameters_));
    } catch (const InputError& e) {
      throw InputError(fmt::format("model (mass / neutral_matrix): {}", e.what()));
    }
  }
}

PluginInfo LinearDde::info() {
  return PluginInfo{
      .name = "linear_dde",
      .description = "Any linear delay system x' = A0 x + sum_k A_k x(t - tau_k), given as matrices",
      .params = parameters_table().specs(),
      .thread_safety = ThreadSafety::shareable,  // immutable after construction
      .models_md_ids = "general linear DDE (solver testbed for G1)",
      // x'' + 2 zeta x' + x = -K (x - x(t - tau)), zeta = 0.05, K = 0.3, tau = 10: the tests'
      // known-answer case (rightmost root near 0.03856 + 1.1222i).
      .example_params = Json::parse(R"({
          "a0": [[0.0, 1.0], [-1.3, -0.1]],
          "delayed": [ { "delay_s": 10.0, "matrix": [[0.0, 0.0], [0.3, 0.0]] } ] })"),
  };
}

std::unique_ptr<CharacteristicFunction> LinearDde::characteristic() const {
  if (parameters_.general()) return std::make_unique<DelayCharacteristic>(delay_system(parameters_));
  return std::make_unique<LinearDdeCharacteristic>(parameters_);
}

CHATTERLAB_REGISTER_MODEL(LinearDde);

}  // namespace chatterlab
