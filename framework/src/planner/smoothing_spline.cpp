#include "planner/smoothing_spline.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace chatterlab::planner {

Jet CubicSpline::evaluate(double at) const {
  const auto it = std::upper_bound(x.begin() + 1, x.end() - 1, at);
  const auto i = static_cast<std::size_t>(it - x.begin()) - 1;
  const double h = x[i + 1] - x[i], a = (x[i + 1] - at) / h, b = (at - x[i]) / h;
  Jet out;
  out.v = a * g[i] + b * g[i + 1] + ((a * a * a - a) * m[i] + (b * b * b - b) * m[i + 1]) * h * h / 6;
  out.d1 = (g[i + 1] - g[i]) / h - (3 * a * a - 1) * h / 6 * m[i] + (3 * b * b - 1) * h / 6 * m[i + 1];
  out.d2 = a * m[i] + b * m[i + 1];
  return out;
}

void check_point_table(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 3 || y.size() != n) throw std::invalid_argument("a point table needs at least 3 points (x, y)");
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
      throw std::invalid_argument(fmt::format("point {} is not finite", i + 1));
  for (std::size_t i = 0; i + 1 < n; ++i)
    if (!(x[i + 1] > x[i]))
      throw std::invalid_argument(fmt::format(
          "x must increase strictly: point {} has x = {} after x = {}", i + 2, x[i + 1], x[i]));
}

CubicSpline interpolating_spline(const std::vector<double>& x, const std::vector<double>& y) {
  check_point_table(x, y);
  const std::size_t n = x.size();
  CubicSpline s{x, y, std::vector<double>(n, 0.0)};
  // Tridiagonal system for the interior m_i (Thomas algorithm).
  std::vector<double> c(n, 0.0), d(n, 0.0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
    const double rhs = 6 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
    const double diag = 2 * (h0 + h1) - h0 * c[i - 1];
    c[i] = h1 / diag;
    d[i] = (rhs - h0 * d[i - 1]) / diag;
  }
  for (std::size_t i = n - 2; i >= 1; --i) s.m[i] = d[i] - c[i] * s.m[i + 1];
  return s;
}

namespace {

// The banded pieces of the Reinsch system for the interior knots j = 1..n-2 (index c = j - 1):
// Q (n x (n-2)) has in column c the entries 1/h_{j-1}, -(1/h_{j-1} + 1/h_j), 1/h_j in rows
// j-1, j, j+1; R ((n-2) square) is tridiagonal with R_cc = (h_{j-1} + h_j)/3, R_c,c+1 = h_j/6.
struct ReinschSystem {
  std::size_t n = 0, m = 0;  // points, interior knots
  std::vector<double> h;
  std::vector<double> qtq0, qtq1, qtq2;  // Q^T Q: diagonal, first and second off-diagonals
  std::vector<double> r0, r1;            // R: diagonal, off-diagonal
  std::vector<double> qty;               // Q^T y

  ReinschSystem(const std::vector<double>& x, const std::vector<double>& y) : n(x.size()), m(x.size() - 2) {
    h.resize(n - 1);
    for (std::size_t i = 0; i + 1 < n; ++i) h[i] = x[i + 1] - x[i];
    auto q = [&](std::size_t row, std::size_t c) -> double {  // Q entry
      const std::size_t j = c + 1;
      if (row + 1 == j) return 1.0 / h[j - 1];
      if (row == j) return -1.0 / h[j - 1] - 1.0 / h[j];
      if (row == j + 1) return 1.0 / h[j];
      return 0.0;
    };
    qtq0.assign(m, 0.0);
    qtq1.assign(m, 0.0);
    qtq2.assign(m, 0.0);
    r0.assign(m, 0.0);
    r1.assign(m, 0.0);
    qty.assign(m, 0.0);
    for (std::size_t c = 0; c < m; ++c) {
      const std::size_t j = c + 1;
      for (std::size_t row = j - 1; row <= j + 1; ++row) {
        qtq0[c] += q(row, c) * q(row, c);
        if (c + 1 < m) qtq1[c] += q(row, c) * q(row, c + 1);
        if (c + 2 < m) qtq2[c] += q(row, c) * q(row, c + 2);
        qty[c] += q(row, c) * y[row];
      }
      r0[c] = (h[j - 1] + h[j]) / 3.0;
      if (c + 1 < m) r1[c] = h[j] / 6.0;
    }
  }
  // (Q gamma)_row
  double q_times(const std::vector<double>& gamma, std::size_t row) const {
    double s = 0.0;
    // columns c with Q(row, c) != 0: c + 1 in {row - 1, row, row + 1}
    for (std::size_t j = (row == 0 ? 1 : row - 1); j <= row + 1 && j <= m; ++j) {
      if (j < 1) continue;
      const std::size_t c = j - 1;
      double entry = 0.0;
      if (row + 1 == j) entry = 1.0 / h[j - 1];
      else if (row == j) entry = -1.0 / h[j - 1] - 1.0 / h[j];
      else if (row == j + 1) entry = 1.0 / h[j];
      s += entry * gamma[c];
    }
    return s;
  }
};

// B = R + lambda Q^T Q as L D L^T (unit lower L with two sub-diagonals).
struct BandedLdl {
  std::vector<double> d, l1, l2;  // l1[i] = L(i, i-1), l2[i] = L(i, i-2)
  BandedLdl(const ReinschSystem& s, double lambda) {
    const std::size_t m = s.m;
    d.assign(m, 0.0);
    l1.assign(m + 2, 0.0);
    l2.assign(m + 2, 0.0);
    auto b0 = [&](std::size_t i) { return s.r0[i] + lambda * s.qtq0[i]; };
    auto b1 = [&](std::size_t i) { return s.r1[i] + lambda * s.qtq1[i]; };  // B(i+1, i)
    auto b2 = [&](std::size_t i) { return lambda * s.qtq2[i]; };             // B(i+2, i)
    for (std::size_t i = 0; i < m; ++i) {
      d[i] = b0(i);
      if (i >= 1) d[i] -= l1[i] * l1[i] * d[i - 1];
      if (i >= 2) d[i] -= l2[i] * l2[i] * d[i - 2];
      if (i + 2 < m) l2[i + 2] = b2(i) / d[i];
      if (i + 1 < m) l1[i + 1] = (b1(i) - (i >= 1 ? l2[i + 1] * l1[i] * d[i - 1] : 0.0)) / d[i];
    }
  }
  std::vector<double> solve(const std::vector<double>& rhs) const {
    const std::size_t m = d.size();
    std::vector<double> z(rhs);
    for (std::size_t i = 0; i < m; ++i) {
      if (i >= 1) z[i] -= l1[i] * z[i - 1];
      if (i >= 2) z[i] -= l2[i] * z[i - 2];
    }
    for (std::size_t i = 0; i < m; ++i) z[i] /= d[i];
    for (std::size_t k = m; k-- > 0;) {
      if (k + 1 < m) z[k] -= l1[k + 1] * z[k + 1];
      if (k + 2 < m) z[k] -= l2[k + 2] * z[k + 2];
    }
    return z;
  }
  // tr(Q^T Q B^-1) from the five central bands of B^-1 (Hutchinson & de Hoog).
  double trace_with(const ReinschSystem& s) const {
    const std::size_t m = d.size();
    std::vector<double> s0(m + 2, 0.0), s1(m + 2, 0.0), s2(m + 2, 0.0);  // Sigma(i,i), (i,i+1), (i,i+2)
    for (std::size_t i = m; i-- > 0;) {
      const double a1 = i + 1 < m ? l1[i + 1] : 0.0, a2 = i + 2 < m ? l2[i + 2] : 0.0;
      s2[i] = -a1 * s1[i + 1] - a2 * s0[i + 2];
      s1[i] = -a1 * s0[i + 1] - a2 * s1[i + 1];
      s0[i] = 1.0 / d[i] - a1 * s1[i] - a2 * s2[i];
    }
    double trace = 0.0;
    for (std::size_t i = 0; i < m; ++i)
      trace += s0[i] * s.qtq0[i] + 2 * s1[i] * s.qtq1[i] + 2 * s2[i] * s.qtq2[i];
    return trace;
  }
};

}  // namespace

namespace {

// The end trend: a cubic t with t'' linear from m0 at x_0 to m1 at x_n, the second derivatives
// of local quadratic least-squares fits to the points nearest each end. The natural condition
// g'' = 0 at the ends (which the penalty imposes) then applies to y - t: the smoothed curve keeps
// the ends' curvature instead of being bent straight there.
struct EndTrend {
  double a = 0.0, b = 1.0, m0 = 0.0, m1 = 0.0;
  double value(double x) const {
    const double l = b - a;
    return m0 * std::pow(b - x, 3) / (6 * l) + m1 * std::pow(x - a, 3) / (6 * l);
  }
  double second(double x) const { return (m0 * (b - x) + m1 * (x - a)) / (b - a); }
};

double end_curvature(const std::vector<double>& x, const std::vector<double>& y, std::size_t from,
                     std::size_t count) {
  // Quadratic least squares about the window's first point: y = c0 + c1 u + c2 u^2.
  double s[5] = {0, 0, 0, 0, 0}, r[3] = {0, 0, 0};
  const double u0 = x[from];
  for (std::size_t i = from; i < from + count; ++i) {
    const double u = x[i] - u0;
    double p = 1.0;
    for (int k = 0; k < 5; ++k) {
      s[k] += p;
      if (k < 3) r[k] += p * y[i];
      p *= u;
    }
  }
  Eigen::Matrix3d m;
  m << s[0], s[1], s[2], s[1], s[2], s[3], s[2], s[3], s[4];
  const Eigen::Vector3d c = m.colPivHouseholderQr().solve(Eigen::Vector3d(r[0], r[1], r[2]));
  return std::isfinite(c[2]) ? 2 * c[2] : 0.0;
}

EndTrend end_trend(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  const std::size_t q = std::min(n, std::max<std::size_t>(7, n / 20));
  return {x.front(), x.back(), end_curvature(x, y, 0, q), end_curvature(x, y, n - q, q)};
}

}  // namespace

SmoothingSpline smoothing_spline(const std::vector<double>& x, const std::vector<double>& y, double lambda,
                                 bool keep_end_curvature) {
  check_point_table(x, y);
  const EndTrend trend = keep_end_curvature ? end_trend(x, y) : EndTrend{x.front(), x.back(), 0.0, 0.0};
  std::vector<double> detrended(y);
  for (std::size_t i = 0; i < y.size(); ++i) detrended[i] -= trend.value(x[i]);
  const ReinschSystem system(x, detrended);
  const BandedLdl ldl(system, lambda);
  const std::vector<double> gamma = ldl.solve(system.qty);
  SmoothingSpline out;
  out.lambda = lambda;
  const std::size_t n = x.size();
  out.spline.x = x;
  out.spline.g.resize(n);
  out.spline.m.assign(n, 0.0);
  double rss = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = lambda * system.q_times(gamma, i);  // y - g = lambda Q gamma
    out.spline.g[i] = y[i] - r;
    rss += r * r;
    out.residual_max_mm = std::max(out.residual_max_mm, std::abs(r));
  }
  for (std::size_t c = 0; c < system.m; ++c) out.spline.m[c + 1] = gamma[c];
  // The trend is a cubic on the whole range: its values and second derivatives at the knots
  // describe it exactly piece by piece, so adding them adds t to the spline.
  for (std::size_t i = 0; i < n; ++i) out.spline.m[i] += trend.second(x[i]);
  const auto count = static_cast<double>(n);
  out.residual_rms_mm = std::sqrt(rss / count);
  out.effective_parameters = count - lambda * ldl.trace_with(system);
  const double dof = std::max(count - out.effective_parameters, 1e-300);
  out.gcv_score = count * rss / (dof * dof);
  out.noise_estimate_mm = std::sqrt(rss / dof);
  return out;
}

namespace {

double mean_spacing_cubed(const std::vector<double>& x) {
  const double h = (x.back() - x.front()) / static_cast<double>(x.size() - 1);
  return h * h * h;
}

}  // namespace

SmoothingSpline cross_validated_spline(const std::vector<double>& x, const std::vector<double>& y) {
  check_point_table(x, y);
  const double scale = mean_spacing_cubed(x);
  auto score = [&](double log_lambda) { return smoothing_spline(x, y, scale * std::pow(10.0, log_lambda)).gcv_score; };
  // A grid over 22 decades, then golden section around the best grid point.
  constexpr double lo = -8.0, hi = 14.0;
  constexpr int steps = 88;
  double best = lo, best_score = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= steps; ++k) {
    const double t = lo + (hi - lo) * k / steps, s = score(t);
    if (s < best_score) {
      best_score = s;
      best = t;
    }
  }
  double a = std::max(lo, best - (hi - lo) / steps), b = std::min(hi, best + (hi - lo) / steps);
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - golden * (b - a), d = a + golden * (b - a), fc = score(c), fd = score(d);
  for (int it = 0; it < 40; ++it) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - golden * (b - a);
      fc = score(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + golden * (b - a);
      fd = score(d);
    }
  }
  const double chosen = fc < fd ? c : d;
  SmoothingSpline out = smoothing_spline(x, y, scale * std::pow(10.0, std::min(fc, fd) < best_score ? chosen : best));
  out.method = "cross_validated";
  return out;
}

SmoothingSpline tolerance_spline(const std::vector<double>& x, const std::vector<double>& y, double tolerance_mm) {
  check_point_table(x, y);
  if (!(tolerance_mm > 0)) throw std::invalid_argument("the smoothing tolerance must be > 0");
  const double scale = mean_spacing_cubed(x);
  auto rms = [&](double log_lambda) { return smoothing_spline(x, y, scale * std::pow(10.0, log_lambda)).residual_rms_mm; };
  // The RMS residual grows with lambda from 0 (interpolation) to that of the least-squares line.
  double lo = -12.0, hi = 16.0;
  SmoothingSpline out;
  if (rms(hi) <= tolerance_mm) {
    out = smoothing_spline(x, y, scale * std::pow(10.0, hi));
  } else {
    for (int it = 0; it < 80; ++it) {
      const double mid = 0.5 * (lo + hi);
      (rms(mid) > tolerance_mm ? hi : lo) = mid;
    }
    out = smoothing_spline(x, y, scale * std::pow(10.0, lo));
  }
  out.method = "tolerance";
  return out;
}

}  // namespace chatterlab::planner
