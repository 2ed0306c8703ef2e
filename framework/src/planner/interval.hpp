#pragma once
// Closed intervals [lo, hi] of reals with outward-widened arithmetic: every operation returns an
// interval that contains the exact result for every point of its arguments. Round-to-nearest
// results are widened by a few units in the last place (library functions are accurate to about
// one ulp), which is enough for the enclosures the geometry analysis needs (docs/planner.md,
// "Geometry analysis"); it is not a verified-arithmetic library. An empty or undefined result
// (sqrt of a negative interval) is NaN in both ends.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace chatterlab::planner {

struct Interval {
  double lo = 0.0, hi = 0.0;

  static Interval point(double v) { return {v, v}; }
  static Interval entire() {
    return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  }
  bool contains(double v) const { return lo <= v && v <= hi; }
  bool finite() const { return std::isfinite(lo) && std::isfinite(hi); }
  double width() const { return hi - lo; }
  double mid() const { return 0.5 * (lo + hi); }
  double magnitude() const { return std::max(std::abs(lo), std::abs(hi)); }
};

namespace interval_detail {
inline double down(double v, int ulps = 1) {
  for (int i = 0; i < ulps && std::isfinite(v); ++i) v = std::nextafter(v, -std::numeric_limits<double>::infinity());
  return v;
}
inline double up(double v, int ulps = 1) {
  for (int i = 0; i < ulps && std::isfinite(v); ++i) v = std::nextafter(v, std::numeric_limits<double>::infinity());
  return v;
}
inline Interval widen(double lo, double hi, int ulps = 1) {
  if (std::isnan(lo) || std::isnan(hi)) return {std::nan(""), std::nan("")};
  return {down(lo, ulps), up(hi, ulps)};
}
// A monotone increasing function applied to the ends.
template <class F>
Interval increasing(const Interval& a, F f, int ulps = 2) {
  return widen(f(a.lo), f(a.hi), ulps);
}
}  // namespace interval_detail

inline Interval hull(const Interval& a, const Interval& b) {
  return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}
inline Interval operator+(const Interval& a, const Interval& b) {
  return interval_detail::widen(a.lo + b.lo, a.hi + b.hi);
}
inline Interval operator-(const Interval& a, const Interval& b) {
  return interval_detail::widen(a.lo - b.hi, a.hi - b.lo);
}
inline Interval operator-(const Interval& a) { return {-a.hi, -a.lo}; }
inline Interval operator*(const Interval& a, const Interval& b) {
  // 0 * inf is taken as 0: an unbounded factor times an exact zero stays zero.
  auto mul = [](double x, double y) { return (x == 0.0 || y == 0.0) ? 0.0 : x * y; };
  const double p[4] = {mul(a.lo, b.lo), mul(a.lo, b.hi), mul(a.hi, b.lo), mul(a.hi, b.hi)};
  return interval_detail::widen(*std::min_element(p, p + 4), *std::max_element(p, p + 4));
}
inline Interval operator*(double s, const Interval& a) { return Interval::point(s) * a; }
// Division by an interval that contains 0 is unbounded (the caller flags it).
inline Interval operator/(const Interval& a, const Interval& b) {
  if (b.contains(0.0)) return Interval::entire();
  return a * interval_detail::widen(1.0 / b.hi, 1.0 / b.lo);
}
inline Interval sqr(const Interval& a) {
  const double l = a.lo * a.lo, h = a.hi * a.hi;
  if (a.contains(0.0)) return {0.0, interval_detail::up(std::max(l, h))};
  return interval_detail::widen(std::min(l, h), std::max(l, h));
}
// a^n for a whole exponent n (of either sign).
inline Interval pow_int(const Interval& a, int n) {
  if (n == 0) return Interval::point(1.0);
  if (n < 0) return Interval::point(1.0) / pow_int(a, -n);
  const double l = std::pow(a.lo, n), h = std::pow(a.hi, n);
  if (n % 2 == 1) return interval_detail::widen(l, h, 2);
  if (a.contains(0.0)) return {0.0, interval_detail::up(std::max(l, h), 2)};
  return interval_detail::widen(std::min(l, h), std::max(l, h), 2);
}
inline Interval abs(const Interval& a) {
  if (a.lo >= 0) return a;
  if (a.hi <= 0) return -a;
  return {0.0, a.magnitude()};
}
inline Interval exp(const Interval& a) { return interval_detail::increasing(a, [](double v) { return std::exp(v); }); }
inline Interval sqrt(const Interval& a) {  // domain a >= 0 (the caller checks)
  return interval_detail::increasing({std::max(a.lo, 0.0), a.hi}, [](double v) { return std::sqrt(v); });
}
inline Interval log(const Interval& a) { return interval_detail::increasing(a, [](double v) { return std::log(v); }); }
inline Interval atan(const Interval& a) { return interval_detail::increasing(a, [](double v) { return std::atan(v); }); }
inline Interval sinh(const Interval& a) { return interval_detail::increasing(a, [](double v) { return std::sinh(v); }); }
inline Interval tanh(const Interval& a) { return interval_detail::increasing(a, [](double v) { return std::tanh(v); }); }
inline Interval asinh(const Interval& a) { return interval_detail::increasing(a, [](double v) { return std::asinh(v); }); }
inline Interval cosh(const Interval& a) {
  const double l = std::cosh(a.lo), h = std::cosh(a.hi);
  if (a.contains(0.0)) return {1.0, interval_detail::up(std::max(l, h), 2)};
  return interval_detail::widen(std::min(l, h), std::max(l, h), 2);
}
// sin over [lo, hi]: the end values and every extremum x = pi/2 + k pi inside.
inline Interval sin(const Interval& a) {
  if (!a.finite() || a.width() >= 2 * std::numbers::pi) return {-1.0, 1.0};
  double lo = std::min(std::sin(a.lo), std::sin(a.hi)), hi = std::max(std::sin(a.lo), std::sin(a.hi));
  const double first = std::ceil((a.lo - std::numbers::pi / 2) / std::numbers::pi);
  for (double k = first; std::numbers::pi / 2 + k * std::numbers::pi <= a.hi; k += 1.0) {
    const bool maximum = std::fmod(std::abs(k), 2.0) == 0.0;
    (maximum ? hi : lo) = maximum ? 1.0 : -1.0;
  }
  // The argument itself carries rounding of its own size: an absolute slack of a few ulps of |x|.
  const double slack = 4 * std::numeric_limits<double>::epsilon() * (1.0 + a.magnitude());
  return {std::max(lo - slack, -1.0), std::min(hi + slack, 1.0)};
}
inline Interval cos(const Interval& a) {
  return sin(a + Interval::point(std::numbers::pi / 2));
}

}  // namespace chatterlab::planner
