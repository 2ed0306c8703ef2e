#pragma once
// Lyapunov exponents of the validation systems computed from their equations (the tangent
// dynamics, not the time series): the independent route against which the literature values
// quoted in chaos_validation_test.cpp are checked, so that a generator that drifted from the
// published system would be caught. Maps: products of Jacobians re-orthonormalised by
// Gram-Schmidt every iteration; flows: the variational equations integrated with the same RK4
// step as the signal; the delay system: two nearby trajectories renormalised every time unit
// (Benettin et al. 1980).
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "shared/nonlinear/test_signals.hpp"

namespace chatterlab::reference {

using Matrix2 = std::array<double, 4>;  // row-major
using Vector3 = std::array<double, 3>;
using Matrix3 = std::array<double, 9>;

// Exponents of a 2-D map from its Jacobians along the orbit (per iteration).
template <class Step, class Jacobian>
std::array<double, 2> map_exponents(double x, double y, std::size_t iterations, const Step& step,
                                    const Jacobian& jacobian) {
  double q[4] = {1, 0, 0, 1};  // columns q0 = (q[0], q[2]), q1 = (q[1], q[3])
  double sum0 = 0, sum1 = 0;
  for (std::size_t i = 0; i < 1000; ++i) step(x, y);
  for (std::size_t i = 0; i < iterations; ++i) {
    const Matrix2 j = jacobian(x, y);
    step(x, y);
    const double a0 = j[0] * q[0] + j[1] * q[2], b0 = j[2] * q[0] + j[3] * q[2];
    const double a1 = j[0] * q[1] + j[1] * q[3], b1 = j[2] * q[1] + j[3] * q[3];
    const double r0 = std::hypot(a0, b0);
    const double u0 = a0 / r0, v0 = b0 / r0;
    const double p = u0 * a1 + v0 * b1;
    const double c1 = a1 - p * u0, d1 = b1 - p * v0;
    const double r1 = std::hypot(c1, d1);
    sum0 += std::log(r0);
    sum1 += std::log(r1);
    q[0] = u0, q[2] = v0, q[1] = c1 / r1, q[3] = d1 / r1;
  }
  return {sum0 / double(iterations), sum1 / double(iterations)};
}

inline std::array<double, 2> henon(std::size_t iterations = 1000000) {
  return map_exponents(
      0.1, 0.1, iterations,
      [](double& x, double& y) {
        const double next = 1 - 1.4 * x * x + y;
        y = 0.3 * x;
        x = next;
      },
      [](double x, double) { return Matrix2{-2.8 * x, 1.0, 0.3, 0.0}; });
}

inline std::array<double, 2> ikeda(std::size_t iterations = 1000000) {
  return map_exponents(
      0.1, 0.1, iterations,
      [](double& x, double& y) {
        const double phase = 0.4 - 6.0 / (1 + x * x + y * y);
        const double c = std::cos(phase), s = std::sin(phase);
        const double xn = 1 + 0.9 * (x * c - y * s);
        y = 0.9 * (x * s + y * c);
        x = xn;
      },
      [](double x, double y) {
        const double r = 1 + x * x + y * y;
        const double phase = 0.4 - 6.0 / r;
        const double c = std::cos(phase), s = std::sin(phase);
        const double px = 12 * x / (r * r), py = 12 * y / (r * r);  // d phase / dx, dy
        const double u = x * c - y * s, v = x * s + y * c;
        return Matrix2{0.9 * (c - v * px), 0.9 * (-s - v * py), 0.9 * (s + u * px),
                       0.9 * (c + u * py)};
      });
}

// Exponents of a 3-D flow (per time unit): state and tangent matrix by RK4 with step h,
// re-orthonormalised every `every` steps, after `transient` time units.
template <class Field, class Jacobian>
Vector3 flow_exponents(Vector3 s, double h, double transient, double time, const Field& f,
                       const Jacobian& jacobian) {
  Matrix3 q = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major, columns are the tangent vectors
  auto derivative = [&](const Vector3& state, const Matrix3& tangent, Vector3& ds, Matrix3& dq) {
    ds = f(state);
    const Matrix3 j = jacobian(state);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        double v = 0;
        for (int k = 0; k < 3; ++k) v += j[std::size_t(3 * r + k)] * tangent[std::size_t(3 * k + c)];
        dq[std::size_t(3 * r + c)] = v;
      }
  };
  auto step = [&](bool with_tangent) {
    Vector3 k[4];
    Matrix3 l[4];
    Vector3 ss = s;
    Matrix3 qq = q;
    const double w[4] = {0, 0.5, 0.5, 1};
    for (int stage = 0; stage < 4; ++stage) {
      if (stage > 0) {
        for (std::size_t c = 0; c < 3; ++c) ss[c] = s[c] + w[stage] * h * k[stage - 1][c];
        if (with_tangent)
          for (std::size_t c = 0; c < 9; ++c) qq[c] = q[c] + w[stage] * h * l[stage - 1][c];
      }
      if (with_tangent)
        derivative(ss, qq, k[stage], l[stage]);
      else
        k[stage] = f(ss);
    }
    for (std::size_t c = 0; c < 3; ++c)
      s[c] += h / 6 * (k[0][c] + 2 * k[1][c] + 2 * k[2][c] + k[3][c]);
    if (with_tangent)
      for (std::size_t c = 0; c < 9; ++c)
        q[c] += h / 6 * (l[0][c] + 2 * l[1][c] + 2 * l[2][c] + l[3][c]);
  };
  for (std::size_t i = 0; i < std::size_t(transient / h); ++i) step(false);
  Vector3 sums = {0, 0, 0};
  const auto steps = std::size_t(time / h);
  for (std::size_t i = 0; i < steps; ++i) {
    step(true);
    // Gram-Schmidt on the columns
    for (std::size_t c = 0; c < 3; ++c) {
      for (std::size_t p = 0; p < c; ++p) {
        double dot = 0;
        for (std::size_t r = 0; r < 3; ++r) dot += q[3 * r + c] * q[3 * r + p];
        for (std::size_t r = 0; r < 3; ++r) q[3 * r + c] -= dot * q[3 * r + p];
      }
      double norm = 0;
      for (std::size_t r = 0; r < 3; ++r) norm += q[3 * r + c] * q[3 * r + c];
      norm = std::sqrt(norm);
      sums[c] += std::log(norm);
      for (std::size_t r = 0; r < 3; ++r) q[3 * r + c] /= norm;
    }
  }
  for (double& v : sums) v /= double(steps) * h;
  return sums;
}

inline Vector3 lorenz(double time = 2000.0) {
  return flow_exponents(
      {1, 1, 1}, 0.01, 50.0, time,
      [](const Vector3& s) {
        return Vector3{10.0 * (s[1] - s[0]), s[0] * (28.0 - s[2]) - s[1],
                       s[0] * s[1] - 8.0 / 3.0 * s[2]};
      },
      [](const Vector3& s) {
        return Matrix3{-10, 10, 0, 28 - s[2], -1, -s[0], s[1], s[0], -8.0 / 3.0};
      });
}

inline Vector3 roessler(double time = 20000.0) {
  return flow_exponents(
      {1, 1, 1}, 0.01, 500.0, time,
      [](const Vector3& s) {
        return Vector3{-s[1] - s[2], s[0] + 0.2 * s[1], 0.2 + s[2] * (s[0] - 5.7)};
      },
      [](const Vector3& s) { return Matrix3{0, -1, -1, 1, 0.2, 0, s[2], 0, s[0] - 5.7}; });
}

// Largest exponent of the Mackey-Glass system (per time unit): a reference trajectory and one
// displaced by 1e-8 (in the whole history), renormalised every time unit.
inline double mackey_glass(double time = 100000.0, double tau = 17.0) {
  test_signals::MackeyGlass a(tau);
  a.advance(2000.0);
  test_signals::MackeyGlass b = a;
  auto distance = [&] {
    double s = 0;
    for (std::size_t i = 0; i < a.history().size(); ++i)
      s += std::pow(a.history()[i] - b.history()[i], 2);
    return std::sqrt(s);
  };
  for (double& v : b.history()) v += 1e-8;
  const double d0 = distance();
  double sum = 0;
  const auto units = std::size_t(time);
  for (std::size_t t = 0; t < units; ++t) {
    a.advance(1.0);
    b.advance(1.0);
    const double d = distance();
    sum += std::log(d / d0);
    for (std::size_t i = 0; i < a.history().size(); ++i)
      b.history()[i] = a.history()[i] + (b.history()[i] - a.history()[i]) * d0 / d;
  }
  return sum / double(units);
}

}  // namespace chatterlab::reference
