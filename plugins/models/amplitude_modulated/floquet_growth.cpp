#include "models/amplitude_modulated/floquet_growth.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
using Mat2 = std::array<double, 4>;  // row-major 2 x 2

Mat2 multiply(const Mat2& a, const Mat2& b) {
  return {a[0] * b[0] + a[1] * b[2], a[0] * b[1] + a[1] * b[3], a[2] * b[0] + a[3] * b[2],
          a[2] * b[1] + a[3] * b[3]};
}

// exp(A h) of the oscillator's first-order matrix by scaling and squaring with a Taylor series
// (exact to rounding for the small norms met here).
Mat2 exponential(const Mat2& a, double h) {
  double norm = 0.0;
  for (double v : a) norm = std::max(norm, std::abs(v) * h);
  int squarings = 0;
  while (norm > 0.125) {
    norm *= 0.5;
    ++squarings;
  }
  const double scale = h / std::ldexp(1.0, squarings);
  const Mat2 x{a[0] * scale, a[1] * scale, a[2] * scale, a[3] * scale};
  Mat2 result{1.0, 0.0, 0.0, 1.0}, term{1.0, 0.0, 0.0, 1.0};
  for (int order = 1; order <= 14; ++order) {
    term = multiply(term, x);
    for (double& v : term) v /= order;
    for (int i = 0; i < 4; ++i) result[static_cast<std::size_t>(i)] += term[static_cast<std::size_t>(i)];
  }
  for (int i = 0; i < squarings; ++i) result = multiply(result, result);
  return result;
}

// Cubic Lagrange basis through u = -1, 0, 1, 2 (u = tau/h), coefficients of u^0..u^3.
constexpr double kLagrange[4][4] = {
    {0.0, -1.0 / 3.0, 0.5, -1.0 / 6.0},
    {1.0, -0.5, -1.0, 0.5},
    {0.0, 1.0, 0.5, -0.5},
    {0.0, -1.0 / 6.0, 0.0, 1.0 / 6.0},
};

struct Model {
  double m, c, k, grinding, ratio, overlap, depth, period, omega0;
  double modulation(double t) const { return 1.0 + depth * std::sin(omega0 * t); }
  // kappa(t) = kg b g/(1 + (kg/kc) g): the force per unit of x1 - mu x(t - T).
  double kappa(double t) const {
    const double g = modulation(t);
    return grinding * g / (1.0 + ratio * g);
  }
};

// One step of length h from t: x1, v1 at t + h as linear functions of x1, v1 at t and of the four
// delayed samples x(t - T - h), x(t - T), x(t - T + h), x(t - T + 2h).
struct Step {
  Mat2 phi;
  std::array<double, 4> to_x, to_v;
};

Step step_map(const Model& md, double t, double h) {
  const double kappa = md.kappa(t + 0.5 * h);  // frozen at the midpoint
  const double stiffness = md.k + kappa;
  Step s;
  s.phi = exponential({0.0, 1.0, -stiffness / md.m, -md.c / md.m}, h);
  for (std::size_t j = 0; j < 4; ++j) {
    // Forcing kappa mu P_j(tau) as a polynomial in tau; particular solution of
    // m x'' + c x' + K x = f0 + f1 tau + f2 tau^2 + f3 tau^3.
    double f[4];
    for (std::size_t d = 0; d < 4; ++d)
      f[d] = kappa * md.overlap * kLagrange[j][d] / std::pow(h, static_cast<double>(d));
    const double p3 = f[3] / stiffness;
    const double p2 = (f[2] - 3.0 * md.c * p3) / stiffness;
    const double p1 = (f[1] - 2.0 * md.c * p2 - 6.0 * md.m * p3) / stiffness;
    const double p0 = (f[0] - md.c * p1 - 2.0 * md.m * p2) / stiffness;
    s.to_x[j] = -s.phi[0] * p0 - s.phi[1] * p1 + p0 + h * (p1 + h * (p2 + h * p3));
    s.to_v[j] = -s.phi[2] * p0 - s.phi[3] * p1 + p1 + h * (2.0 * p2 + 3.0 * h * p3);
  }
  return s;
}

// The monodromy matrix over one period with N steps. State: [x1, v1, x_0, x_{-1}, ..., x_{-N-1}]
// (x_j = x(j h), the relative displacement the wheel surface remembers).
Eigen::MatrixXd monodromy(const Model& md, int n_steps) {
  const auto N = static_cast<Eigen::Index>(n_steps);
  const Eigen::Index n = N + 4;
  const double h = md.period / static_cast<double>(n_steps);
  Eigen::MatrixXd history = Eigen::MatrixXd::Zero(2 * N + 2, n);  // row j + N + 1 holds x_j
  auto row = [&](Eigen::Index j) { return history.row(j + N + 1); };
  for (Eigen::Index j = 0; j >= -N - 1; --j) row(j)(2 - j) = 1.0;
  Eigen::RowVectorXd x = Eigen::RowVectorXd::Unit(n, 0), v = Eigen::RowVectorXd::Unit(n, 1);
  for (Eigen::Index i = 0; i < N; ++i) {
    const double t = static_cast<double>(i) * h;
    const Step s = step_map(md, t, h);
    Eigen::RowVectorXd new_x = s.phi[0] * x + s.phi[1] * v;
    Eigen::RowVectorXd new_v = s.phi[2] * x + s.phi[3] * v;
    for (Eigen::Index j = 0; j < 4; ++j) {
      new_x += s.to_x[static_cast<std::size_t>(j)] * row(i - N - 1 + j);
      new_v += s.to_v[static_cast<std::size_t>(j)] * row(i - N - 1 + j);
    }
    x = new_x;
    v = new_v;
    const double qg = md.ratio * md.modulation(t + h);
    row(i + 1) = (x + qg * md.overlap * row(i + 1 - N)) / (1.0 + qg);
  }
  Eigen::MatrixXd m(n, n);
  m.row(0) = x;
  m.row(1) = v;
  for (Eigen::Index l = 0; l < N + 2; ++l) m.row(2 + l) = row(N - l);
  return m;
}

std::complex<double> dominant_eigenvalue(const Eigen::MatrixXd& m) {
  Eigen::EigenSolver<Eigen::MatrixXd> solver(m, false);
  if (solver.info() != Eigen::Success) throw std::runtime_error("floquet_growth: eigenvalue solver failed");
  std::complex<double> best = 0.0;
  for (Eigen::Index i = 0; i < solver.eigenvalues().size(); ++i) {
    const std::complex<double> e = solver.eigenvalues()(i);
    // Of a conjugate pair take Im >= 0 (ties in modulus resolved towards it).
    if (std::abs(e) > std::abs(best) * (1.0 + 1e-12) ||
        (std::abs(e) >= std::abs(best) * (1.0 - 1e-12) && e.imag() > best.imag()))
      best = e;
  }
  return best;
}

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("floquet_growth: " + what);
}

void add_sidebands(const Model& md, const Eigen::MatrixXd& m, std::complex<double> multiplier,
                   int n_steps, int orders, G7FloquetResult& out) {
  // Eigenvector by inverse iteration (shift a hair off the eigenvalue).
  const Eigen::Index n = m.rows();
  Eigen::MatrixXcd shifted = m.cast<std::complex<double>>();
  shifted.diagonal().array() -= multiplier * (1.0 + 1e-10);
  Eigen::PartialPivLU<Eigen::MatrixXcd> lu(shifted);
  Eigen::VectorXcd vec = Eigen::VectorXcd::Ones(n);
  for (int it = 0; it < 3; ++it) vec = lu.solve(vec).normalized();
  // Eigenfunction on one period: x_j (j = -N+1..0), x1_j = (1 + q g) x_j - q g mu x_{j-N} with
  // x_{j-N} = x_j / multiplier (x(t + T) = multiplier x(t)); then the periodic part
  // p(t) = x1(t) e^{-s t}, s = ln(multiplier)/T, and its Fourier coefficients Phi_r (eq 3-17).
  const double h = md.period / n_steps;
  const std::complex<double> s = std::log(multiplier) / md.period;
  std::vector<std::complex<double>> periodic;
  std::vector<double> times;
  for (int j = -n_steps + 1; j <= 0; ++j) {
    const double t = j * h;
    const double qg = md.ratio * md.modulation(t);
    const std::complex<double> xj = vec(2 - j);
    const std::complex<double> x1 = (1.0 + qg) * xj - qg * md.overlap * xj / multiplier;
    periodic.push_back(x1 * std::exp(-s * t));
    times.push_back(t);
  }
  auto coefficient = [&](int r) {
    std::complex<double> sum = 0.0;
    for (std::size_t i = 0; i < periodic.size(); ++i)
      sum += periodic[i] * std::exp(std::complex<double>(0.0, -r * md.omega0 * times[i]));
    return sum / static_cast<double>(periodic.size());
  };
  int carrier = 0;
  double largest = -1.0;
  for (int r = -n_steps / 4; r <= n_steps / 4; ++r) {  // well below the grid's Nyquist
    const double a = std::abs(coefficient(r));
    if (a > largest) largest = a, carrier = r;
  }
  const double base = s.imag();
  const double carrier_rad_s = base + carrier * md.omega0;
  out.carrier_frequency_hz = std::abs(carrier_rad_s) / kTwoPi;
  // A carrier at negative frequency is the conjugate of the physical one at +|w|: order k (at
  // |w_carrier| + k w0) is then harmonic r* - k.
  const int direction = carrier_rad_s >= 0.0 ? 1 : -1;
  for (int k = -orders; k <= orders; ++k) {
    const int r = carrier + direction * k;
    out.sidebands.push_back({k, std::abs(base + r * md.omega0) / kTwoPi, std::abs(coefficient(r)) / largest});
  }
}

}  // namespace

G7FloquetResult floquet_growth(const AmplitudeModulatedParameters& p, const FloquetOptions& options) {
  check(p.mass_kg > 0 && p.stiffness_n_per_m > 0 && p.grinding_stiffness_n_per_m > 0 &&
            p.contact_stiffness_n_per_m > 0 && p.wheel_speed_rpm > 0,
        "mass, stiffness, grinding and contact stiffness and wheel speed must be > 0");
  check(p.damping_n_s_per_m >= 0, "damping must be >= 0");
  check(p.overlap_factor >= 0 && p.overlap_factor <= 1, "overlap factor mu must be in [0, 1]");
  check(p.modulation_depth >= 0 && p.modulation_depth < 1, "modulation depth Q must be in [0, 1)");
  check(options.max_steps_per_period >= 8, "max_steps_per_period must be >= 8");
  const double period = 60.0 / p.wheel_speed_rpm;
  const Model md{p.mass_kg, p.damping_n_s_per_m, p.stiffness_n_per_m, p.grinding_stiffness_n_per_m,
                 p.grinding_stiffness_n_per_m / p.contact_stiffness_n_per_m, p.overlap_factor,
                 p.modulation_depth, period, kTwoPi / period};
  int n_steps = options.initial_steps_per_period;
  if (n_steps <= 0) {
    const double stiffest = std::sqrt((p.stiffness_n_per_m + p.grinding_stiffness_n_per_m) / p.mass_kg);
    n_steps = std::max(16, static_cast<int>(std::ceil(1.2 * stiffest * period / 0.5)));
  }
  // At least 8 steps: the cubic reads samples up to two steps ahead of the delayed interval.
  n_steps = std::max(8, std::min(n_steps, options.max_steps_per_period));

  G7FloquetResult out;
  Eigen::MatrixXd m = monodromy(md, n_steps);
  std::complex<double> multiplier = dominant_eigenvalue(m);
  double sigma = std::log(std::abs(multiplier)) / period;
  out.growth_rate_change_per_s = std::numeric_limits<double>::infinity();
  while (2 * n_steps <= options.max_steps_per_period) {
    n_steps *= 2;
    m = monodromy(md, n_steps);
    multiplier = dominant_eigenvalue(m);
    const double refined = std::log(std::abs(multiplier)) / period;
    // The scheme is fourth order (cubic delay interpolation, exact oscillator; the frozen
    // modulation's O(h^2) error carries (w0 h)^2 = (2 pi/N)^2 and stays below it here): Richardson
    // extrapolation of sigma(N/2), sigma(N); the change it applies is the error estimate.
    const double correction = (refined - sigma) / 15.0;
    out.growth_rate_change_per_s = std::abs(correction);
    sigma = refined + correction;
    const double scale = std::abs(std::log(multiplier)) / period;
    if (out.growth_rate_change_per_s <= options.tolerance_per_s + 1e-6 * scale) {
      out.converged = true;
      break;
    }
  }
  out.dominant_multiplier = multiplier;
  out.growth_rate_per_s = sigma;
  out.steps_per_period = n_steps;
  add_sidebands(md, m, multiplier, n_steps, options.sideband_orders, out);
  return out;
}

}  // namespace chatterlab
