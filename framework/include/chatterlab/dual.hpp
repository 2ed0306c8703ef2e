#pragma once
// Forward-mode automatic differentiation: a dual number a + b eps (eps^2 = 0) carries a value and
// one directional derivative through any arithmetic, so a function written once as a template over
// its scalar type gives its derivative exactly (to rounding, no step size), the way Ceres'
// Jet / AutoDiffCostFunction and Drake's scalar-templated systems do. The framework seeds one input
// at a time (derived_model.hpp) to take the Jacobians of a model's right-hand side.
//
// Writing a template that works for double and Dual:
//   - call math functions unqualified after a using-declaration, so argument-dependent lookup picks
//     the Dual overload:   using std::sin; using std::exp;  ...  return sin(w * t) * exp(x);
//   - constants mix freely (Dual(2.0), 2.0 * x); comparisons compare values (a branch is
//     differentiated on the side it takes, like any piecewise function);
//   - value_of(x) gives the plain double of either type (for messages, table look-ups).
#include <cmath>
#include <ostream>

namespace chatterlab {

namespace autodiff {

struct Dual {
  double value = 0.0;
  double derivative = 0.0;  // d value / d (the seeded input)

  constexpr Dual() = default;
  constexpr Dual(double v) : value(v) {}  // NOLINT: implicit, constants enter expressions freely
  constexpr Dual(double v, double d) : value(v), derivative(d) {}

  constexpr Dual& operator+=(const Dual& b) { value += b.value; derivative += b.derivative; return *this; }
  constexpr Dual& operator-=(const Dual& b) { value -= b.value; derivative -= b.derivative; return *this; }
  constexpr Dual& operator*=(const Dual& b) {
    derivative = derivative * b.value + value * b.derivative;
    value *= b.value;
    return *this;
  }
  constexpr Dual& operator/=(const Dual& b) {
    value /= b.value;
    derivative = (derivative - value * b.derivative) / b.value;
    return *this;
  }
};

constexpr Dual operator+(Dual a) { return a; }
constexpr Dual operator-(const Dual& a) { return {-a.value, -a.derivative}; }
constexpr Dual operator+(Dual a, const Dual& b) { return a += b; }
constexpr Dual operator-(Dual a, const Dual& b) { return a -= b; }
constexpr Dual operator*(Dual a, const Dual& b) { return a *= b; }
constexpr Dual operator/(Dual a, const Dual& b) { return a /= b; }
constexpr Dual operator+(Dual a, double b) { a.value += b; return a; }
constexpr Dual operator+(double a, Dual b) { b.value += a; return b; }
constexpr Dual operator-(Dual a, double b) { a.value -= b; return a; }
constexpr Dual operator-(double a, const Dual& b) { return {a - b.value, -b.derivative}; }
constexpr Dual operator*(const Dual& a, double b) { return {a.value * b, a.derivative * b}; }
constexpr Dual operator*(double a, const Dual& b) { return {a * b.value, a * b.derivative}; }
constexpr Dual operator/(const Dual& a, double b) { return {a.value / b, a.derivative / b}; }
constexpr Dual operator/(double a, const Dual& b) {
  const double v = a / b.value;
  return {v, -v * b.derivative / b.value};
}

constexpr bool operator==(const Dual& a, const Dual& b) { return a.value == b.value; }
constexpr bool operator!=(const Dual& a, const Dual& b) { return a.value != b.value; }
constexpr bool operator<(const Dual& a, const Dual& b) { return a.value < b.value; }
constexpr bool operator>(const Dual& a, const Dual& b) { return a.value > b.value; }
constexpr bool operator<=(const Dual& a, const Dual& b) { return a.value <= b.value; }
constexpr bool operator>=(const Dual& a, const Dual& b) { return a.value >= b.value; }

// Elementary functions: f(a + b eps) = f(a) + f'(a) b eps.
inline Dual sin(const Dual& a) { return {std::sin(a.value), std::cos(a.value) * a.derivative}; }
inline Dual cos(const Dual& a) { return {std::cos(a.value), -std::sin(a.value) * a.derivative}; }
inline Dual tan(const Dual& a) {
  const double t = std::tan(a.value);
  return {t, (1.0 + t * t) * a.derivative};
}
inline Dual exp(const Dual& a) {
  const double e = std::exp(a.value);
  return {e, e * a.derivative};
}
inline Dual log(const Dual& a) { return {std::log(a.value), a.derivative / a.value}; }
inline Dual sqrt(const Dual& a) {
  const double r = std::sqrt(a.value);
  return {r, a.derivative / (2.0 * r)};
}
inline Dual pow(const Dual& a, double p) {
  return {std::pow(a.value, p), p * std::pow(a.value, p - 1.0) * a.derivative};
}
inline Dual pow(const Dual& a, const Dual& p) {  // a > 0
  const double v = std::pow(a.value, p.value);
  return {v, v * (p.derivative * std::log(a.value) + p.value * a.derivative / a.value)};
}
inline Dual abs(const Dual& a) { return a.value < 0.0 ? -a : a; }
inline Dual fabs(const Dual& a) { return abs(a); }
inline Dual atan(const Dual& a) { return {std::atan(a.value), a.derivative / (1.0 + a.value * a.value)}; }
inline Dual atan2(const Dual& y, const Dual& x) {
  const double r2 = x.value * x.value + y.value * y.value;
  return {std::atan2(y.value, x.value), (x.value * y.derivative - y.value * x.derivative) / r2};
}
inline Dual tanh(const Dual& a) {
  const double t = std::tanh(a.value);
  return {t, (1.0 - t * t) * a.derivative};
}
inline Dual hypot(const Dual& a, const Dual& b) {
  const double h = std::hypot(a.value, b.value);
  return {h, (a.value * a.derivative + b.value * b.derivative) / h};
}
// max/min of two Duals: the derivative of the larger (smaller) one (ties: the first).
inline Dual max(const Dual& a, const Dual& b) { return b.value > a.value ? b : a; }
inline Dual min(const Dual& a, const Dual& b) { return b.value < a.value ? b : a; }

inline std::ostream& operator<<(std::ostream& os, const Dual& a) {
  return os << a.value << " + " << a.derivative << " eps";
}

}  // namespace autodiff

using autodiff::Dual;

// The plain value of a scalar of either type.
constexpr double value_of(double x) { return x; }
constexpr double value_of(const Dual& x) { return x.value; }

}  // namespace chatterlab
