// Modal parameters from a measured FRF: LSCF poles over increasing orders, the stabilisation
// diagram and its automatic reading, LSFD compliances, a Levenberg-Marquardt refinement of every
// parameter and its covariance (chatterlab/modal_fit.hpp has the method in words).
#include "chatterlab/modal_fit.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The measured lines of the fit band, the response scaled to an RMS of 1 (the normal equations mix
// sums of |H|^2 and of 1: with H ~ 1e-8 m/N they would span 1e16), and the line weights.
struct Band {
  std::vector<double> f_hz;
  std::vector<Complex> h;  // scaled
  std::vector<double> weight;
  double scale = 1.0;  // receptance = h x scale
};

Band band_of(const MeasuredFrf& frf, const ModalFitSettings& s) {
  const double lo = s.min_frequency_hz.value_or(frf.frequency_hz.front());
  const double hi = s.max_frequency_hz.value_or(frf.frequency_hz.back());
  if (!(hi > lo))
    throw InputError(fmt::format("{}: modal fit band {}-{} Hz is empty", frf.source, lo, hi));
  Band b;
  double sum_squares = 0.0;
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i) {
    if (frf.frequency_hz[i] < lo || frf.frequency_hz[i] > hi) continue;
    b.f_hz.push_back(frf.frequency_hz[i]);
    b.h.push_back(frf.receptance_m_per_n[i]);
    sum_squares += std::norm(frf.receptance_m_per_n[i]);
  }
  constexpr std::size_t min_lines = 16;
  if (b.f_hz.size() < min_lines)
    throw InputError(fmt::format("{}: the modal fit band {}-{} Hz holds {} measured lines; at least {} are needed",
                                 frf.source, lo, hi, b.f_hz.size(), min_lines));
  b.scale = std::sqrt(sum_squares / static_cast<double>(b.h.size()));
  if (!(b.scale > 0.0)) throw InputError(fmt::format("{}: the FRF is zero in the fit band", frf.source));
  double peak = 0.0;
  for (Complex& v : b.h) {
    v /= b.scale;
    peak = std::max(peak, std::abs(v));
  }
  // Relative weights 1/|H|, floored at 1e-3 of the peak so that a near-zero line (an
  // anti-resonance, a noise dip) does not take over the fit.
  for (const Complex& v : b.h)
    b.weight.push_back(s.weighting == FitWeighting::relative ? 1.0 / std::max(std::abs(v), 1e-3 * peak) : 1.0);
  return b;
}

// ---------------------------------------------------------------- LSCF

// Sums over the lines of Omega^d, H Omega^d and |H|^2 Omega^d, Omega = e^{-j w dt}: the normal
// matrices R, S, T of the common-denominator fit are Toeplitz in these lags. The pole fit is
// unweighted whatever the refinement's weighting: with 1/|H| weights the linearised equation error
// H A - B is dominated by the off-resonance lines, and with 2 % noise the poles of two modes 2 %
// apart wandered by 0.5 % from order to order instead of stabilising (weights do matter, and are
// used, in the compliances and the refinement).
struct Lags {
  int max_lag = 0;
  std::vector<Complex> rho, tau;  // d = 0..max_lag
  std::vector<Complex> sigma;     // d = -max_lag..max_lag (index d + max_lag)
};

Lags lags_of(const Band& b, int max_lag, double dt) {
  Lags l;
  l.max_lag = max_lag;
  l.rho.assign(static_cast<std::size_t>(max_lag) + 1, 0.0);
  l.tau.assign(static_cast<std::size_t>(max_lag) + 1, 0.0);
  l.sigma.assign(2 * static_cast<std::size_t>(max_lag) + 1, 0.0);
  for (std::size_t k = 0; k < b.f_hz.size(); ++k) {
    const Complex omega = std::polar(1.0, -kTwoPi * b.f_hz[k] * dt);
    Complex power = 1.0;
    for (int d = 0; d <= max_lag; ++d) {
      const auto u = static_cast<std::size_t>(d);
      l.rho[u] += power;
      l.tau[u] += std::norm(b.h[k]) * power;
      l.sigma[static_cast<std::size_t>(max_lag + d)] += b.h[k] * power;
      if (d > 0) l.sigma[static_cast<std::size_t>(max_lag - d)] += b.h[k] * std::conj(power);
      power *= omega;
    }
  }
  return l;
}

struct Pole {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
};

// The poles of the order-n common-denominator fit that can be modes: Im s > 0, damped, in band.
std::vector<Pole> lscf_poles(const Lags& l, int n, double dt, double lo_hz, double hi_hz, double max_damping) {
  const Eigen::Index m = n + 1;
  Eigen::MatrixXd r(m, m), s(m, m), t(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j) {
      const auto d = static_cast<std::size_t>(std::abs(j - i));
      r(i, j) = l.rho[d].real();
      t(i, j) = l.tau[d].real();
      s(i, j) = -l.sigma[static_cast<std::size_t>(l.max_lag + (j - i))].real();
    }
  // Reduced normal equations M a = 0 for the denominator a (numerator eliminated), a_n = 1.
  const Eigen::MatrixXd reduced = t - s.transpose().lazyProduct(r.ldlt().solve(s));
  const Eigen::VectorXd a_head = reduced.topLeftCorner(n, n).ldlt().solve(-reduced.topRightCorner(n, 1));
  // Companion matrix of the monic polynomial sum a_r Omega^r.
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  for (Eigen::Index i = 0; i < n; ++i) companion(i, n - 1) = -a_head(i);
  const Eigen::VectorXcd roots = companion.eigenvalues();
  std::vector<Pole> poles;
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    const Complex z = roots(i);
    if (std::abs(z) == 0.0) continue;
    const Complex pole = -std::log(z) / dt;  // Omega = e^{-s dt}
    if (!(pole.imag() > 0.0) || !(pole.real() < 0.0)) continue;
    const double wn = std::abs(pole), zeta = -pole.real() / wn, f = wn / kTwoPi;
    if (f < lo_hz || f > hi_hz || zeta > max_damping) continue;
    poles.push_back({f, zeta});
  }
  std::sort(poles.begin(), poles.end(), [](const Pole& a, const Pole& b) { return a.frequency_hz < b.frequency_hz; });
  return poles;
}

// Stabilisation diagram: each order's poles, labelled against the next lower order's.
void label_against(std::vector<StabilisationPole>& current, const std::vector<StabilisationPole>& previous,
                   const ModalFitSettings& s) {
  for (StabilisationPole& p : current) {
    const StabilisationPole* nearest = nullptr;
    for (const StabilisationPole& q : previous)
      if (!nearest || std::abs(q.frequency_hz - p.frequency_hz) < std::abs(nearest->frequency_hz - p.frequency_hz))
        nearest = &q;
    if (!nearest || std::abs(nearest->frequency_hz - p.frequency_hz) > s.frequency_tolerance * p.frequency_hz) continue;
    p.status = std::abs(nearest->damping_ratio - p.damping_ratio) <= s.damping_tolerance * p.damping_ratio
                   ? StabilisationPole::Status::stable
                   : StabilisationPole::Status::frequency_stable;
  }
}

struct Cluster {
  double frequency_hz = 0.0, damping_ratio = 0.0;
  int orders = 0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Automatic reading of the diagram: the poles stable at least in frequency, sorted by frequency and
// split where neighbours are more than half the frequency tolerance apart; a cluster present in
// enough distinct orders is a mode, at the median frequency and damping of its poles. Damping is
// not required to be stable here: LSCF damping wanders with noise from order to order (a 2 %
// noise FRF moves it by more than 5 %), and the refinement that follows fixes it.
std::vector<Cluster> select_modes(const std::vector<StabilisationPole>& poles, std::size_t order_count,
                                  const ModalFitSettings& s) {
  std::vector<const StabilisationPole*> stable;
  for (const StabilisationPole& p : poles)
    if (p.status != StabilisationPole::Status::new_pole) stable.push_back(&p);
  std::sort(stable.begin(), stable.end(),
            [](const auto* a, const auto* b) { return a->frequency_hz < b->frequency_hz; });
  std::vector<Cluster> clusters;
  const int needed = std::max(2, static_cast<int>(std::ceil(s.min_stable_fraction * static_cast<double>(order_count))));
  for (std::size_t i = 0; i < stable.size();) {
    std::size_t j = i + 1;
    while (j < stable.size() &&
           stable[j]->frequency_hz - stable[j - 1]->frequency_hz <= 0.5 * s.frequency_tolerance * stable[j]->frequency_hz)
      ++j;
    std::vector<double> f, zeta;
    std::vector<int> orders;
    for (std::size_t k = i; k < j; ++k) {
      f.push_back(stable[k]->frequency_hz);
      zeta.push_back(stable[k]->damping_ratio);
      orders.push_back(stable[k]->order);
    }
    std::sort(orders.begin(), orders.end());
    const int distinct = static_cast<int>(std::unique(orders.begin(), orders.end()) - orders.begin());
    if (distinct >= needed) clusters.push_back({median(f), median(zeta), distinct});
    i = j;
  }
  if (s.modes && static_cast<int>(clusters.size()) > *s.modes) {
    std::stable_sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) { return a.orders > b.orders; });
    clusters.resize(static_cast<std::size_t>(*s.modes));
    std::sort(clusters.begin(), clusters.end(),
              [](const Cluster& a, const Cluster& b) { return a.frequency_hz < b.frequency_hz; });
  }
  return clusters;
}

// ---------------------------------------------------------------- LSFD and refinement

// Parameters: per mode (f [Hz], zeta, c = 1/k scaled), then the upper residual (scaled compliance)
// and the lower residual L (scaled, term -L/w^2).
struct Model {
  std::size_t modes = 0;
  Eigen::VectorXd theta;
  Complex value(double f_hz, Eigen::VectorXd* gradient_re = nullptr, Eigen::VectorXd* gradient_im = nullptr) const {
    const double w = kTwoPi * f_hz;
    Complex h = theta(static_cast<Eigen::Index>(3 * modes)) - theta(static_cast<Eigen::Index>(3 * modes + 1)) / (w * w);
    if (gradient_re) {
      gradient_re->setZero(theta.size());
      gradient_im->setZero(theta.size());
      (*gradient_re)(static_cast<Eigen::Index>(3 * modes)) = 1.0;
      (*gradient_re)(static_cast<Eigen::Index>(3 * modes + 1)) = -1.0 / (w * w);
    }
    for (std::size_t i = 0; i < modes; ++i) {
      const auto k = static_cast<Eigen::Index>(3 * i);
      const double wi = kTwoPi * theta(k), zeta = theta(k + 1), c = theta(k + 2);
      const Complex denominator(wi * wi - w * w, 2.0 * zeta * wi * w);
      const Complex phi = wi * wi / denominator;
      h += c * phi;
      if (gradient_re) {
        const Complex d_wi = (2.0 * wi * denominator - wi * wi * Complex(2.0 * wi, 2.0 * zeta * w)) /
                             (denominator * denominator);
        const Complex d_zeta = -wi * wi * Complex(0.0, 2.0 * wi * w) / (denominator * denominator);
        const Complex parts[3] = {c * d_wi * kTwoPi, c * d_zeta, phi};
        for (int p = 0; p < 3; ++p) {
          (*gradient_re)(k + p) = parts[p].real();
          (*gradient_im)(k + p) = parts[p].imag();
        }
      }
    }
    return h;
  }
};

// Weighted residuals (real and imaginary rows) and, optionally, their Jacobian.
double residuals(const Model& m, const Band& b, Eigen::VectorXd& r, Eigen::MatrixXd* jacobian) {
  const auto n = static_cast<Eigen::Index>(b.f_hz.size());
  r.resize(2 * n);
  if (jacobian) jacobian->resize(2 * n, m.theta.size());
  Eigen::VectorXd g_re, g_im;
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto u = static_cast<std::size_t>(k);
    const Complex e = (m.value(b.f_hz[u], jacobian ? &g_re : nullptr, jacobian ? &g_im : nullptr) - b.h[u]) * b.weight[u];
    r(2 * k) = e.real();
    r(2 * k + 1) = e.imag();
    if (jacobian) {
      jacobian->row(2 * k) = b.weight[u] * g_re.transpose();
      jacobian->row(2 * k + 1) = b.weight[u] * g_im.transpose();
    }
  }
  return r.squaredNorm();
}

// J^T J as a coefficient-wise (lazy) product: Eigen's blocked product would start OpenMP threads
// for a 3000 x 25 Jacobian and spend its time spinning them up on a loaded machine.
Eigen::MatrixXd gram(const Eigen::MatrixXd& j) { return j.transpose().lazyProduct(j); }

// Compliances and residual terms by linear least squares with the poles fixed (LSFD).
Model lsfd(const std::vector<Cluster>& clusters, const Band& b) {
  Model m;
  m.modes = clusters.size();
  m.theta.setZero(static_cast<Eigen::Index>(3 * m.modes + 2));
  for (std::size_t i = 0; i < m.modes; ++i) {
    m.theta(static_cast<Eigen::Index>(3 * i)) = clusters[i].frequency_hz;
    m.theta(static_cast<Eigen::Index>(3 * i + 1)) = clusters[i].damping_ratio;
  }
  // The model is linear in c_i and the residuals: their columns are the Jacobian's.
  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  residuals(m, b, r, &j);
  std::vector<Eigen::Index> linear;
  for (std::size_t i = 0; i < m.modes; ++i) linear.push_back(static_cast<Eigen::Index>(3 * i + 2));
  linear.push_back(static_cast<Eigen::Index>(3 * m.modes));
  linear.push_back(static_cast<Eigen::Index>(3 * m.modes + 1));
  Eigen::MatrixXd a(j.rows(), static_cast<Eigen::Index>(linear.size()));
  for (std::size_t c = 0; c < linear.size(); ++c) a.col(static_cast<Eigen::Index>(c)) = j.col(linear[c]);
  // r = A x - w h at x = 0, so the least-squares x solves A x = -r.
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(-r);
  for (std::size_t c = 0; c < linear.size(); ++c) m.theta(linear[c]) = x(static_cast<Eigen::Index>(c));
  return m;
}

bool physical(const Model& m, const Band& b) {
  for (std::size_t i = 0; i < m.modes; ++i) {
    const double f = m.theta(static_cast<Eigen::Index>(3 * i)), zeta = m.theta(static_cast<Eigen::Index>(3 * i + 1));
    if (!(f > 0.5 * b.f_hz.front() && f < 1.5 * b.f_hz.back() && zeta > 0.0 && zeta < 1.0)) return false;
  }
  return m.theta.allFinite();
}

// Levenberg-Marquardt (Marquardt's diagonal scaling) on every parameter.
int refine(Model& m, const Band& b) {
  Eigen::VectorXd r, r_trial;
  Eigen::MatrixXd j;
  double cost = residuals(m, b, r, &j);
  double lambda = 1e-3;
  int iterations = 0;
  for (; iterations < 200; ++iterations) {
    const Eigen::MatrixXd jtj = gram(j);
    const Eigen::VectorXd gradient = j.transpose() * r;
    bool improved = false;
    for (int attempt = 0; attempt < 30 && !improved; ++attempt) {
      Eigen::MatrixXd damped = jtj;
      for (Eigen::Index i = 0; i < damped.rows(); ++i) damped(i, i) += lambda * std::max(jtj(i, i), 1e-300);
      const Eigen::VectorXd step = damped.ldlt().solve(-gradient);
      Model trial = m;
      trial.theta += step;
      const double trial_cost = physical(trial, b) ? residuals(trial, b, r_trial, nullptr) : INFINITY;
      if (trial_cost < cost) {
        const double reduction = (cost - trial_cost) / cost;
        m = std::move(trial);
        cost = residuals(m, b, r, &j);
        lambda = std::max(lambda / 10.0, 1e-12);
        improved = true;
        if (reduction < 1e-12) return iterations + 1;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return iterations;
}

}  // namespace

const ParamTable<ModalFitSettings>& modal_fit_settings_table() {
  static const ParamTable<ModalFitSettings> table = [] {
    ParamTable<ModalFitSettings> t;
    t.add(&ModalFitSettings::min_frequency_hz, "min_frequency_hz", "Hz", "lower end of the fit band (default: the lowest measured line)").positive();
    t.add(&ModalFitSettings::max_frequency_hz, "max_frequency_hz", "Hz", "upper end of the fit band (default: the highest measured line)").positive();
    t.add(&ModalFitSettings::max_order, "max_order", "1", "highest LSCF model order (a mode takes two; the diagram shows orders 2, 4, ..., max_order)").at_least(4).at_most(200);
    t.add(&ModalFitSettings::frequency_tolerance, "frequency_tolerance", "1", "stabilisation: largest relative frequency change between consecutive orders of a stable pole").positive().at_most(0.2);
    t.add(&ModalFitSettings::damping_tolerance, "damping_tolerance", "1", "stabilisation: largest relative damping change between consecutive orders of a stable pole").positive().at_most(1.0);
    t.add(&ModalFitSettings::max_damping_ratio, "max_damping_ratio", "1", "poles more damped than this are not taken for modes").positive().below(1.0);
    t.add(&ModalFitSettings::min_stable_fraction, "min_stable_fraction", "1", "a mode must be stable in at least this fraction of the orders").positive().at_most(1.0);
    t.add(&ModalFitSettings::modes, "modes", "1", "keep this many modes, the most persistent ones (default: every mode the diagram selects)").at_least(1).at_most(100);
    t.add_choice(&ModalFitSettings::weighting, "weighting", "line weights of the compliance fit and the refinement: relative (1/|H|) or uniform",
                 {{"relative", FitWeighting::relative}, {"uniform", FitWeighting::uniform}});
    return t;
  }();
  return table;
}

Complex modes_receptance(const std::vector<FittedMode>& modes, double frequency_hz) {
  const double w = kTwoPi * frequency_hz;
  Complex h = 0.0;
  for (const FittedMode& m : modes) {
    const double wi = kTwoPi * m.frequency_hz;
    h += (1.0 / m.stiffness_n_per_m) / Complex(1.0 - w * w / (wi * wi), 2.0 * m.damping_ratio * w / wi);
  }
  return h;
}

Complex ModalFit::modal_receptance(double frequency_hz) const { return modes_receptance(modes, frequency_hz); }

Complex ModalFit::receptance(double frequency_hz) const {
  const double w = kTwoPi * frequency_hz;
  Complex h = modal_receptance(frequency_hz) + upper_residual_m_per_n;
  if (lower_residual_kg != 0.0) h -= 1.0 / (lower_residual_kg * w * w);
  return h;
}

ModalFit fit_modes(const MeasuredFrf& frf, const ModalFitSettings& settings) {
  const Band band = band_of(frf, settings);
  ModalFit fit;
  fit.min_frequency_hz = band.f_hz.front();
  fit.max_frequency_hz = band.f_hz.back();
  fit.lines = static_cast<int>(band.f_hz.size());
  // Orders above half the number of lines would fit the noise line by line.
  const int max_order = std::min(settings.max_order, 2 * (fit.lines / 4));
  const double dt = 1.0 / (2.0 * fit.max_frequency_hz * 1.05);  // the band's top just inside Nyquist
  const Lags lags = lags_of(band, max_order, dt);
  std::vector<StabilisationPole> previous;
  for (int n = 2; n <= max_order; n += 2) {
    std::vector<StabilisationPole> current;
    for (const Pole& p : lscf_poles(lags, n, dt, fit.min_frequency_hz, fit.max_frequency_hz, settings.max_damping_ratio))
      current.push_back({n, p.frequency_hz, p.damping_ratio, StabilisationPole::Status::new_pole});
    label_against(current, previous, settings);
    fit.stabilisation.insert(fit.stabilisation.end(), current.begin(), current.end());
    fit.orders.push_back(n);
    previous = std::move(current);
  }
  const std::vector<Cluster> clusters = select_modes(fit.stabilisation, fit.orders.size(), settings);
  if (clusters.empty())
    throw InputError(fmt::format("{}: no stable mode in {:g}-{:g} Hz: no pole stayed within {:g} % in frequency over "
                                 "{:g} % of the orders 2..{} (raise max_order, widen frequency_tolerance or lower "
                                 "min_stable_fraction)",
                                 frf.source, fit.min_frequency_hz, fit.max_frequency_hz, 100 * settings.frequency_tolerance,
                                 100 * settings.min_stable_fraction, max_order));
  Model model = lsfd(clusters, band);
  Model refined = model;
  fit.refinement_iterations = refine(refined, band);
  if (physical(refined, band)) model = std::move(refined);

  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  const double cost = residuals(model, band, r, &j);
  const double dof = std::max(1.0, static_cast<double>(r.size() - model.theta.size()));
  const Eigen::MatrixXd covariance = (cost / dof) * gram(j).ldlt().solve(
                                                        Eigen::MatrixXd::Identity(model.theta.size(), model.theta.size()));
  for (std::size_t i = 0; i < model.modes; ++i) {
    const auto k = static_cast<Eigen::Index>(3 * i);
    FittedMode m;
    m.frequency_hz = model.theta(k);
    m.damping_ratio = model.theta(k + 1);
    const double c = model.theta(k + 2) * band.scale;  // 1/k [m/N]
    m.stiffness_n_per_m = 1.0 / c;
    m.frequency_sd_hz = std::sqrt(std::max(covariance(k, k), 0.0));
    m.damping_ratio_sd = std::sqrt(std::max(covariance(k + 1, k + 1), 0.0));
    m.stiffness_sd_n_per_m = std::sqrt(std::max(covariance(k + 2, k + 2), 0.0)) * band.scale / (c * c);
    m.stable_orders = clusters[i].orders;
    fit.modes.push_back(m);
  }
  fit.upper_residual_m_per_n = model.theta(static_cast<Eigen::Index>(3 * model.modes)) * band.scale;
  const double lower = model.theta(static_cast<Eigen::Index>(3 * model.modes + 1)) * band.scale;
  fit.lower_residual_kg = lower != 0.0 ? 1.0 / lower : 0.0;
  double misfit = 0.0, total = 0.0;
  for (std::size_t k = 0; k < band.f_hz.size(); ++k) {
    const Complex measured = band.h[k] * band.scale;
    misfit += std::norm(fit.receptance(band.f_hz[k]) - measured);
    total += std::norm(measured);
  }
  fit.relative_misfit = std::sqrt(misfit / total);
  std::sort(fit.modes.begin(), fit.modes.end(), [](const FittedMode& a, const FittedMode& b) { return a.frequency_hz < b.frequency_hz; });
  return fit;
}

}  // namespace chatterlab
