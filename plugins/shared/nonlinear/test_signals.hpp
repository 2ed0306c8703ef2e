#pragma once
// Known-answer signals for the tests and benchmarks of the nonlinear analyses (MODELS.md N):
// maps (Henon, Ikeda), flows (Lorenz, Roessler), a delay system (Mackey-Glass), a quasi-periodic
// torus, a sine, and stochastic signals (white and power-law noise, AR(2)), plus measurement
// noise; all deterministic (fixed seeds). tests/validation/ compares the analyses' estimates on
// them with the literature.
#include <array>
#include <type_traits>
#include <memory>
#include <string>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <random>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/fft.hpp"
#include "chatterlab/kit/data.hpp"

namespace chatterlab::test_signals {

// Henon map (a = 1.4, b = 0.3) x coordinate after 1000 transient iterations.
// Largest Lyapunov exponent 0.419 per iteration, D2 = 1.21-1.22.
inline std::vector<double> henon(std::size_t n) {
  double x = 0.1, y = 0.1;
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n + 1000; ++i) {
    const double next = 1 - 1.4 * x * x + y;
    y = 0.3 * x;
    x = next;
    if (i >= 1000) out.push_back(x);
  }
  return out;
}

// Lorenz system (sigma 10, rho 28, beta 8/3), x sampled every dt by classical RK4 after 50 time
// units of transient. Exponents 0.906, 0, -14.57 per time unit; D2 = 2.05.
inline std::vector<double> lorenz(std::size_t n, double dt = 0.01) {
  using State = std::array<double, 3>;
  auto f = [](const State& s) {
    return State{10.0 * (s[1] - s[0]), s[0] * (28.0 - s[2]) - s[1],
                 s[0] * s[1] - 8.0 / 3.0 * s[2]};
  };
  State s{1.0, 1.0, 1.0};
  auto step = [&] {
    auto add = [](const State& a, const State& b, double h) {
      return State{a[0] + h * b[0], a[1] + h * b[1], a[2] + h * b[2]};
    };
    const State k1 = f(s), k2 = f(add(s, k1, dt / 2)), k3 = f(add(s, k2, dt / 2)),
                k4 = f(add(s, k3, dt));
    for (int c = 0; c < 3; ++c) s[std::size_t(c)] += dt / 6 * (k1[std::size_t(c)] + 2 * k2[std::size_t(c)] + 2 * k3[std::size_t(c)] + k4[std::size_t(c)]);
  };
  const auto transient = std::size_t(50.0 / dt);
  for (std::size_t i = 0; i < transient; ++i) step();
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(s[0]);
    step();
  }
  return out;
}

// Classical fourth-order Runge-Kutta for an autonomous 3-D flow: `substeps` steps of dt / substeps
// between samples, after `transient` time units. Returns the first coordinate.
template <class Field>
std::vector<double> flow_x(std::size_t n, double dt, int substeps, double transient,
                           std::array<double, 3> s, const Field& f) {
  using State = std::array<double, 3>;
  const double h = dt / substeps;
  auto add = [](const State& a, const State& b, double w) {
    return State{a[0] + w * b[0], a[1] + w * b[1], a[2] + w * b[2]};
  };
  auto step = [&] {
    const State k1 = f(s), k2 = f(add(s, k1, h / 2)), k3 = f(add(s, k2, h / 2)),
                k4 = f(add(s, k3, h));
    for (std::size_t c = 0; c < 3; ++c) s[c] += h / 6 * (k1[c] + 2 * k2[c] + 2 * k3[c] + k4[c]);
  };
  for (std::size_t i = 0; i < std::size_t(transient / h); ++i) step();
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(s[0]);
    for (int k = 0; k < substeps; ++k) step();
  }
  return out;
}

// Roessler system (a = b = 0.2, c = 5.7), x sampled every dt (RK4, 10 steps per sample) after
// 500 time units. Exponents 0.0714, 0, -5.394 per time unit (Sprott 2003); D2 = 1.99 +- 0.07.
inline std::vector<double> roessler(std::size_t n, double dt = 0.1) {
  return flow_x(n, dt, 10, 500.0, {1.0, 1.0, 1.0}, [](const std::array<double, 3>& s) {
    return std::array<double, 3>{-s[1] - s[2], s[0] + 0.2 * s[1], 0.2 + s[2] * (s[0] - 5.7)};
  });
}

// Ikeda map z -> 1 + 0.9 z exp(i (0.4 - 6 / (1 + |z|^2))) (TISEAN `ikeda`'s defaults), Re z
// after 1000 transient iterations. Exponents 0.508, -0.719 per iteration (Sprott 2003).
inline std::vector<double> ikeda(std::size_t n) {
  double x = 0.1, y = 0.1;
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n + 1000; ++i) {
    const double phase = 0.4 - 6.0 / (1 + x * x + y * y);
    const double c = std::cos(phase), s = std::sin(phase);
    const double xn = 1 + 0.9 * (x * c - y * s);
    y = 0.9 * (x * s + y * c);
    x = xn;
    if (i >= 1000) out.push_back(x);
  }
  return out;
}

// Mackey-Glass delay system dx/dt = 0.2 x(t - tau) / (1 + x(t - tau)^10) - 0.1 x(t), integrated
// by RK4 with step 0.1 (the delayed value at half steps by cubic interpolation of the stored
// history). The state is the history over the last tau (+ 3 steps for the interpolation).
class MackeyGlass {
 public:
  static constexpr double h = 0.1;
  explicit MackeyGlass(double tau = 17.0, double initial = 1.2)
      : lag_(std::size_t(std::lround(tau / h))), past_(lag_ + 4, initial) {}
  double x() const { return at(0); }
  void step() {
    const double x0 = at(0), d0 = at(lag_), d1 = at(lag_ - 1);
    // x(t - tau + h/2): cubic through t - tau - h .. t - tau + 2 h
    const double dm = (-at(lag_ + 1) + 9 * d0 + 9 * d1 - at(lag_ - 2)) / 16;
    const double k1 = f(x0, d0), k2 = f(x0 + h / 2 * k1, dm), k3 = f(x0 + h / 2 * k2, dm),
                 k4 = f(x0 + h * k3, d1);
    now_ = (now_ + 1) % past_.size();
    past_[now_] = x0 + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  void advance(double time) {
    for (std::size_t i = 0; i < std::size_t(std::lround(time / h)); ++i) step();
  }
  // The whole state (history) as a vector, for perturbation (reference exponents).
  std::vector<double>& history() { return past_; }

 private:
  static double f(double x, double delayed) {
    return 0.2 * delayed / (1 + std::pow(delayed, 10)) - 0.1 * x;
  }
  double at(std::size_t steps_back) const {
    return past_[(now_ + past_.size() - steps_back) % past_.size()];
  }
  std::size_t lag_;
  std::vector<double> past_;
  std::size_t now_ = 0;
};

// Mackey-Glass x sampled every dt after 2000 time units (tau = 17: D2 = 1.95 +- 0.03,
// Grassberger and Procaccia 1983).
inline std::vector<double> mackey_glass(std::size_t n, double dt = 1.0, double tau = 17.0) {
  MackeyGlass system(tau);
  system.advance(2000.0);
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(system.x());
    system.advance(dt);
  }
  return out;
}

// Quasi-periodic signal on a 2-torus: sin(2 pi i / p) + 0.6 sin(2 pi i / (p golden ratio)),
// incommensurate periods: D2 = 2, every Lyapunov exponent 0.
inline std::vector<double> torus(std::size_t n, double samples_per_period = 50.0) {
  const double golden = (1 + std::sqrt(5.0)) / 2;
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = 2 * std::numbers::pi * double(i) / samples_per_period;
    out[i] = std::sin(t) + 0.6 * std::sin(t / golden);
  }
  return out;
}

inline std::vector<double> sine(std::size_t n, double samples_per_period) {
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = std::sin(2 * std::numbers::pi * double(i) / samples_per_period);
  return out;
}

inline std::vector<double> white_noise(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<double> out(n);
  for (auto& v : out) v = normal(rng);
  return out;
}

// Linear stochastic process AR(2): x_i = a1 x_{i-1} + a2 x_{i-2} + e_i, Gaussian e. The default
// (1.6, -0.9) is a randomly excited, lightly damped oscillation (poles at radius 0.95, 32 degrees:
// a resonance every 11 samples), the linear model of a vibration mode under broadband forcing.
inline std::vector<double> ar2(std::size_t n, unsigned seed, double a1 = 1.6, double a2 = -0.9) {
  const auto e = white_noise(n + 1000, seed);
  std::vector<double> out;
  out.reserve(n);
  double x1 = 0, x2 = 0;
  for (std::size_t i = 0; i < n + 1000; ++i) {
    const double x = a1 * x1 + a2 * x2 + e[i];
    x2 = x1;
    x1 = x;
    if (i >= 1000) out.push_back(x);
  }
  return out;
}

// Coloured (power-law) Gaussian noise with power spectrum ~ 1/f^alpha: Gaussian Fourier
// coefficients scaled by f^(-alpha/2) and transformed back. Osborne and Provenzale (1989): such
// noise shows a finite, spurious correlation dimension (about 2 / (alpha - 1) for 1 < alpha < 3)
// when temporally correlated pairs are not excluded.
inline std::vector<double> power_law_noise(std::size_t n, double alpha, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  RealFft fft(n);
  std::vector<std::complex<double>> spectrum(fft.spectrum_size());
  for (std::size_t k = 1; k < spectrum.size(); ++k)
    spectrum[k] = std::pow(double(k), -alpha / 2) * std::complex<double>(normal(rng), normal(rng));
  return fft.inverse(spectrum);
}

// tanh(x / sd(x)): a linear process seen through a saturating sensor (a static monotone
// nonlinearity: what IAAFT surrogates keep).
inline std::vector<double> saturated(std::vector<double> x) {
  double mean = 0, var = 0;
  for (double v : x) mean += v / double(x.size());
  for (double v : x) var += (v - mean) * (v - mean) / double(x.size());
  for (double& v : x) v = std::tanh((v - mean) / std::sqrt(var));
  return x;
}

// x + level sd(x) e_i, e Gaussian white: measurement noise at `level` (0.05 = 5 %) of the
// signal's standard deviation.
inline std::vector<double> with_noise(std::vector<double> x, double level, unsigned seed) {
  double mean = 0, var = 0;
  for (double v : x) mean += v / double(x.size());
  for (double v : x) var += (v - mean) * (v - mean) / double(x.size());
  const auto e = white_noise(x.size(), seed);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] += level * std::sqrt(var) * e[i];
  return x;
}

inline SampledSeries series(std::vector<double> values, double dt, const char* name) {
  SampledSeries s;
  s.set_samples(std::move(values));
  s.sample_interval = dt;
  s.name = name;
  return s;
}

// An analysis plugin built from `params` (validated like a study's table; defaults filled in).
inline std::unique_ptr<Analysis> make_analysis(const std::string& name,
                                               const Json& params = Json::object()) {
  const auto& entry = analysis_registry().at(name);
  kit::FileSourceMap sources("test");
  return entry.create(ParamValues(validate_params(params, entry.info.params, name, sources)));
}

}  // namespace chatterlab::test_signals
