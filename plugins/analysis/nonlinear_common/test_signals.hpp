#pragma once
// Known-answer signals for the tests and benchmarks of the nonlinear analyses (MODELS.md N):
// Henon map x, Lorenz x (RK4), a sine and Gaussian white noise, all deterministic (fixed seeds).
#include <array>
#include <memory>
#include <string>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "study/source_map.hpp"

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

inline SampledSeries series(std::vector<double> values, double dt, const char* name) {
  SampledSeries s;
  s.values = std::move(values);
  s.sample_interval = dt;
  s.name = name;
  return s;
}

// An analysis plugin built from `params` (validated like a study's table; defaults filled in).
inline std::unique_ptr<Analysis> make_analysis(const std::string& name,
                                               const Json& params = Json::object()) {
  const auto& entry = analysis_registry().at(name);
  LineSourceMap sources("test");
  return entry.create(ParamValues(validate_params(params, entry.info.params, name, sources)));
}

}  // namespace chatterlab::test_signals
