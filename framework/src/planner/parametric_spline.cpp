#include "chatterlab/planner/parametric_spline.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

namespace chatterlab::planner {

namespace {
constexpr double pi = std::numbers::pi;
}

ParametricSpline::ParametricSpline(std::vector<std::array<double, 2>> points, SplineEnds ends,
                                   std::array<double, 2> start_tangent,
                                   std::array<double, 2> end_tangent)
    : p_(std::move(points)), periodic_(ends == SplineEnds::periodic) {
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (!std::isfinite(p_[i][0]) || !std::isfinite(p_[i][1]))
      throw std::invalid_argument(fmt::format("spline point {} is not finite", i));
  if (periodic_ && !p_.empty() && (p_.front() != p_.back())) p_.push_back(p_.front());
  if (p_.size() < (periodic_ ? 4u : 3u))
    throw std::invalid_argument("a spline needs at least 3 distinct points");
  const std::size_t n = p_.size() - 1;  // segments
  l_.assign(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double h = std::hypot(p_[i + 1][0] - p_[i][0], p_[i + 1][1] - p_[i][1]);
    if (!(h > 0))
      throw std::invalid_argument(fmt::format("spline points {} and {} coincide", i, i + 1));
    l_[i + 1] = l_[i] + h;
  }
  auto h = [&](std::size_t i) { return l_[i + 1] - l_[i]; };
  const std::size_t unknowns = periodic_ ? n : n + 1;
  for (int c = 0; c < 2; ++c) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(unknowns), static_cast<Eigen::Index>(unknowns));
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(unknowns));
    auto slope = [&](std::size_t i) { return (p_[i + 1][c] - p_[i][c]) / h(i); };
    auto at = [&](std::size_t r, std::size_t col) -> double& {
      return a(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(col % unknowns));
    };
    for (std::size_t i = periodic_ ? 0 : 1; i < n; ++i) {
      const std::size_t prev = i == 0 ? n - 1 : i - 1;
      at(i, prev) += h(prev);
      at(i, i) += 2 * (h(prev) + h(i));
      at(i, i + 1) += h(i);
      rhs(static_cast<Eigen::Index>(i)) = 6 * (slope(i) - slope(prev));
    }
    if (!periodic_) {
      if (ends == SplineEnds::natural) {
        at(0, 0) = 1.0;
        at(n, n) = 1.0;
      } else {
        const double s0 = start_tangent[c] / std::hypot(start_tangent[0], start_tangent[1]);
        const double s1 = end_tangent[c] / std::hypot(end_tangent[0], end_tangent[1]);
        at(0, 0) = 2 * h(0);
        at(0, 1) = h(0);
        rhs(0) = 6 * (slope(0) - s0);
        at(n, n - 1) = h(n - 1);
        at(n, n) = 2 * h(n - 1);
        rhs(static_cast<Eigen::Index>(n)) = 6 * (s1 - slope(n - 1));
      }
    }
    const Eigen::VectorXd m = a.partialPivLu().solve(rhs);
    m_[c].assign(n + 1, 0.0);
    for (std::size_t i = 0; i < unknowns; ++i) m_[c][i] = m(static_cast<Eigen::Index>(i));
    if (periodic_) m_[c][n] = m_[c][0];
  }
}

void ParametricSpline::evaluate(double l, std::array<double, 2>& position, std::array<double, 2>& d1,
                                std::array<double, 2>& d2) const {
  const double total = l_.back();
  l = periodic_ ? l - total * std::floor(l / total) : std::clamp(l, 0.0, total);
  const auto it = std::upper_bound(l_.begin() + 1, l_.end() - 1, l);
  const auto i = static_cast<std::size_t>(it - l_.begin()) - 1;
  const double h = l_[i + 1] - l_[i], a = (l_[i + 1] - l) / h, b = (l - l_[i]) / h;
  for (int c = 0; c < 2; ++c) {
    const double m0 = m_[c][i], m1 = m_[c][i + 1], y0 = p_[i][c], y1 = p_[i + 1][c];
    position[c] = a * y0 + b * y1 + ((a * a * a - a) * m0 + (b * b * b - b) * m1) * h * h / 6;
    d1[c] = (y1 - y0) / h - (3 * a * a - 1) * h / 6 * m0 + (3 * b * b - 1) * h / 6 * m1;
    d2[c] = a * m0 + b * m1;
  }
}

std::array<double, 2> ParametricSpline::position(double l) const {
  std::array<double, 2> p{}, d1{}, d2{};
  evaluate(l, p, d1, d2);
  return p;
}

double ParametricSpline::parameter_at_polar_angle(double angle) const {
  // Unwrapped polar angles of the knots (the curve winds once, counter-clockwise, round 0).
  std::vector<double> theta(p_.size());
  theta[0] = std::atan2(p_[0][1], p_[0][0]);
  for (std::size_t i = 1; i < p_.size(); ++i) {
    double step = std::atan2(p_[i][1], p_[i][0]) - std::atan2(p_[i - 1][1], p_[i - 1][0]);
    step -= 2 * pi * std::round(step / (2 * pi));
    theta[i] = theta[i - 1] + step;
  }
  double target = angle - 2 * pi * std::floor((angle - theta[0]) / (2 * pi));
  const auto it = std::upper_bound(theta.begin() + 1, theta.end() - 1, target);
  const auto i = static_cast<std::size_t>(it - theta.begin()) - 1;
  double lo = l_[i], hi = l_[i + 1];
  auto angle_at = [&](double l) {  // unwrapped next to the segment's start angle
    const auto q = position(l);
    const double t = std::atan2(q[1], q[0]);
    return t + 2 * pi * std::round((theta[i] - t) / (2 * pi));
  };
  for (int k = 0; k < 80; ++k) {
    const double mid = 0.5 * (lo + hi);
    (angle_at(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double ParametricSpline::polar_radius(double angle) const {
  const auto q = position(parameter_at_polar_angle(angle));
  return std::hypot(q[0], q[1]);
}

CamFit fit_cam(const LiftTable& table, std::vector<double> chosen, double target_error_mm,
               ParametricSpline* spline_out) {
  std::map<double, double> rows;  // angle in [0, 360) -> radius
  for (std::size_t i = 0; i < table.angle_deg.size(); ++i)
    rows[std::fmod(table.angle_deg[i], 360.0)] = table.radius_mm[i];
  for (double& a : chosen) a = std::fmod(a, 360.0);
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  CamFit fit;
  for (;;) {
    std::vector<std::array<double, 2>> points;
    for (double a : chosen) {
      const auto row = rows.find(a);
      if (row == rows.end())
        throw std::invalid_argument(fmt::format("chosen angle {} deg is not a row of the lift table", a));
      points.push_back({row->second * std::cos(a * pi / 180), row->second * std::sin(a * pi / 180)});
    }
    ParametricSpline spline(points, SplineEnds::periodic);
    fit.max_radius_error_mm = fit.mean_abs_radius_error_mm = fit.max_x_error_mm = fit.max_y_error_mm = 0.0;
    double worst_angle = -1.0;
    for (const auto& [angle, radius] : rows) {
      const double phi = angle * pi / 180;
      const double e = spline.polar_radius(phi) - radius;
      fit.mean_abs_radius_error_mm += std::abs(e) / static_cast<double>(rows.size());
      fit.max_x_error_mm = std::max(fit.max_x_error_mm, std::abs(e * std::cos(phi)));
      fit.max_y_error_mm = std::max(fit.max_y_error_mm, std::abs(e * std::sin(phi)));
      if (std::abs(e) > fit.max_radius_error_mm) {
        fit.max_radius_error_mm = std::abs(e);
        worst_angle = angle;
      }
    }
    fit.worst_angle_deg = worst_angle;
    const bool done = target_error_mm <= 0 || fit.max_radius_error_mm <= target_error_mm ||
                      std::binary_search(chosen.begin(), chosen.end(), worst_angle);
    if (done) {
      fit.chosen_angles_deg = chosen;
      if (spline_out) *spline_out = spline;
      return fit;
    }
    chosen.insert(std::upper_bound(chosen.begin(), chosen.end(), worst_angle), worst_angle);
    ++fit.inserted;
  }
}

}  // namespace chatterlab::planner
