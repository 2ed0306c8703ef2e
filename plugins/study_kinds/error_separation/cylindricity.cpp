#include "study_kinds/error_separation/cylindricity.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace chatterlab::error_separation {

namespace {

// Mean and first Fourier coefficients: x ~ mean + a cos th + b sin th.
struct FirstHarmonic {
  double mean = 0.0, a = 0.0, b = 0.0;
};
FirstHarmonic fit_first_harmonic(std::span<const double> x) {
  const double n = static_cast<double>(x.size());
  FirstHarmonic h;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double th = 2.0 * std::numbers::pi * static_cast<double>(i) / n;
    h.mean += x[i] / n;
    h.a += 2.0 * x[i] * std::cos(th) / n;
    h.b += 2.0 * x[i] * std::sin(th) / n;
  }
  return h;
}

}  // namespace

Cylinder reconstruct_cylinder(
    std::span<const std::vector<std::vector<double>>> probes_per_section, std::span<const double> z,
    const std::function<Separation(std::span<const std::vector<double>>)>& separate) {
  if (probes_per_section.size() < 2 || z.size() != probes_per_section.size())
    throw std::invalid_argument("cylindricity needs at least two sections, one z per section");
  Cylinder out;
  for (std::size_t j = 0; j < probes_per_section.size(); ++j) {
    CylinderSection s;
    s.z = z[j];
    s.separation = separate(probes_per_section[j]);
    if (!s.separation.mean_radius_known)
      throw std::invalid_argument(
          "cylindricity: the probe weights sum to zero (G(0) = 0), so the mean radius of a "
          "section cannot be separated");
    s.mean_radius_difference = s.separation.mean_radius;
    const FirstHarmonic hx = fit_first_harmonic(s.separation.dx);
    const FirstHarmonic hy = fit_first_harmonic(s.separation.dy);
    s.straightness_u = hx.mean;
    s.straightness_v = hy.mean;
    s.centre_x = 0.5 * (hx.a - hy.b);
    s.centre_y = 0.5 * (hx.b + hy.a);
    out.sections.push_back(std::move(s));
  }

  // 3-D form and its least-squares cylinder (linear in R0, a0, a1, b0, b1).
  const std::size_t n = out.sections.front().separation.profile.size();
  const auto rows = static_cast<Eigen::Index>(n * out.sections.size());
  Eigen::MatrixXd design(rows, 5);
  Eigen::VectorXd values(rows);
  Eigen::Index row = 0;
  for (const CylinderSection& s : out.sections) {
    std::vector<double> f(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double th = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
      f[i] = s.mean_radius_difference + s.separation.profile[i] + s.centre_x * std::cos(th) +
             s.centre_y * std::sin(th);
      design.row(row) << 1.0, std::cos(th), s.z * std::cos(th), std::sin(th), s.z * std::sin(th);
      values(row++) = f[i];
    }
    out.form.push_back(std::move(f));
  }
  const Eigen::VectorXd beta = design.colPivHouseholderQr().solve(values);
  out.ls_radius = beta(0);
  out.axis_x0 = beta(1);
  out.axis_x_slope = beta(2);
  out.axis_y0 = beta(3);
  out.axis_y_slope = beta(4);
  const Eigen::VectorXd residual = values - design * beta;
  double lo = residual.minCoeff(), hi = residual.maxCoeff();
  out.cylindricity = hi - lo;
  row = 0;
  for (std::size_t j = 0; j < out.sections.size(); ++j) {
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n; ++i) r[i] = residual(row++);
    out.residual.push_back(std::move(r));
  }
  return out;
}

}  // namespace chatterlab::error_separation
