#include "shared/metrology/profile_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace chatterlab::surface {
namespace {

constexpr double pi = std::numbers::pi;

// Amplitude of the sine/cosine pair at `cycles_per_sample` in y[from, to), by least squares
// (with an offset), so the transmission is measured, not assumed.
double fitted_amplitude(const std::vector<double>& y, double cycles_per_sample, std::size_t from,
                        std::size_t to) {
  double m[3][3] = {}, r[3] = {};
  for (std::size_t i = from; i < to; ++i) {
    const double ph = 2 * pi * cycles_per_sample * static_cast<double>(i);
    const double b[3] = {std::sin(ph), std::cos(ph), 1.0};
    for (int a = 0; a < 3; ++a) {
      r[a] += b[a] * y[i];
      for (int c = 0; c < 3; ++c) m[a][c] += b[a] * b[c];
    }
  }
  // Gaussian elimination on the 3x3 normal equations.
  for (int k = 0; k < 3; ++k)
    for (int i = k + 1; i < 3; ++i) {
      const double f = m[i][k] / m[k][k];
      for (int j = k; j < 3; ++j) m[i][j] -= f * m[k][j];
      r[i] -= f * r[k];
    }
  double x[3];
  for (int i = 2; i >= 0; --i) {
    double s = r[i];
    for (int j = i + 1; j < 3; ++j) s -= m[i][j] * x[j];
    x[i] = s / m[i][i];
  }
  return std::hypot(x[0], x[1]);
}

constexpr std::array<double, 5> ratios = {0.5, 1, 2, 4, 8};
constexpr std::array<double, 5> iso_values = {0.0625, 0.5000, 0.8409, 0.9576, 0.9892};

TEST(ProfileFilter, AnalyticTransmissionMatchesIsoTable) {
  for (std::size_t i = 0; i < ratios.size(); ++i)
    EXPECT_NEAR(waviness_transmission(FilterType::gaussian, ratios[i]), iso_values[i], 1e-4);
  EXPECT_NEAR(waviness_transmission(FilterType::robust_gaussian, 1.0), 0.5, 1e-4);
}

TEST(ProfileFilter, OpenGaussianTransmissionAwayFromEnds) {
  // Densely sampled, and at 7.5 samples per cut-off (near the 7 that the surface study accepts).
  for (const double cutoff : {200.0, 7.5}) {
    for (std::size_t r = 0; r < ratios.size(); ++r) {
      const double wavelength = ratios[r] * cutoff;
      const std::size_t n = static_cast<std::size_t>(wavelength * 40 + 4 * cutoff);
      std::vector<double> z(n);
      for (std::size_t i = 0; i < n; ++i) z[i] = std::sin(2 * pi * static_cast<double>(i) / wavelength);
      FilterSettings s;
      s.cutoff_samples = cutoff;
      const auto w = filter_profile(z, s).waviness;
      // Interior: >= 1.5 cut-offs (the kernel's half-width) from either end.
      const auto edge = static_cast<std::size_t>(1.5 * cutoff);
      const double h = fitted_amplitude(w, 1 / wavelength, edge, n - edge);
      EXPECT_NEAR(h, iso_values[r], 0.002) << "lambda/lc = " << ratios[r] << ", cut-off " << cutoff;
    }
  }
}

TEST(ProfileFilter, OpenGaussianKeepsAStraightLineUpToTheEnds) {
  // Moment retention (ISO 16610-28): no end run-out on a tilted profile.
  std::vector<double> z(1000);
  for (std::size_t i = 0; i < z.size(); ++i) z[i] = 3.0 + 0.01 * static_cast<double>(i);
  FilterSettings s;
  s.cutoff_samples = 300;
  const auto w = filter_profile(z, s).waviness;
  for (std::size_t i = 0; i < z.size(); ++i) ASSERT_NEAR(w[i], z[i], 1e-9) << i;
}

TEST(ProfileFilter, ClosedGaussianTransmissionEverywhere) {
  const std::size_t n = 3000;  // not a power of two: any length
  const double cutoff_upr = 40;
  for (std::size_t r = 0; r < ratios.size(); ++r) {
    const double lobes = cutoff_upr / ratios[r];
    std::vector<double> z(n);
    for (std::size_t i = 0; i < n; ++i)
      z[i] = std::cos(2 * pi * lobes * static_cast<double>(i) / static_cast<double>(n));
    FilterSettings s;
    s.closed = true;
    s.cutoff_samples = static_cast<double>(n) / cutoff_upr;
    const auto w = filter_profile(z, s).waviness;
    for (std::size_t i = 0; i < n; ++i)
      ASSERT_NEAR(w[i], iso_values[r] * z[i], 0.002) << "lambda/lc " << ratios[r] << " at " << i;
  }
}

TEST(ProfileFilter, RobustRegressionTransmission) {
  // Without outliers the biweights stay near 1 and the interior transmission is the 2nd-order
  // regression filter's (1 + t) e^-t.
  const double cutoff = 100.0;
  for (double ratio : {0.5, 1.0, 2.0, 4.0}) {
    const double wavelength = ratio * cutoff;
    const std::size_t n = static_cast<std::size_t>(wavelength * 6 + 6 * cutoff);
    std::vector<double> z(n);
    for (std::size_t i = 0; i < n; ++i) z[i] = std::sin(2 * pi * static_cast<double>(i) / wavelength);
    FilterSettings s;
    s.type = FilterType::robust_gaussian;
    s.cutoff_samples = cutoff;
    s.max_iterations = 1;  // the non-robust start: the linear regression filter itself
    const auto w = filter_profile(z, s).waviness;
    const std::size_t edge = 2 * static_cast<std::size_t>(cutoff);
    EXPECT_NEAR(fitted_amplitude(w, 1 / wavelength, edge, n - edge),
                waviness_transmission(FilterType::robust_gaussian, ratio), 0.002)
        << ratio;
  }
}

TEST(ProfileFilter, RobustRegressionIgnoresAnOutlierSpike) {
  const double cutoff = 100.0;
  const std::size_t n = 2000, spike = 1000;
  std::vector<double> z(n);
  for (std::size_t i = 0; i < n; ++i)
    z[i] = std::sin(2 * pi * static_cast<double>(i) / 800.0) +
           0.05 * std::sin(2 * pi * static_cast<double>(i) / 7.3);  // roughness
  z[spike] += 50.0;
  FilterSettings gaussian;
  gaussian.cutoff_samples = cutoff;
  FilterSettings robust = gaussian;
  robust.type = FilterType::robust_gaussian;
  const auto g = filter_profile(z, gaussian);
  const auto r = filter_profile(z, robust);
  EXPECT_TRUE(r.converged);
  EXPECT_GE(r.zero_weight_samples, 1u);
  EXPECT_LE(r.iterations, 20);
  auto deviation = [&](const std::vector<double>& w) {
    double worst = 0;
    for (std::size_t i = spike - 150; i < spike + 150; ++i)
      worst = std::max(worst, std::abs(w[i] - std::sin(2 * pi * static_cast<double>(i) / 800.0)));
    return worst;
  };
  EXPECT_GT(deviation(g.waviness), 0.5);   // the spike drags the Gaussian mean line up
  EXPECT_LT(deviation(r.waviness), 0.03);  // the robust mean line does not see it
}

TEST(ProfileFilter, RobustClosedProfileIsPeriodic) {
  const std::size_t n = 1024;
  std::vector<double> z(n);
  for (std::size_t i = 0; i < n; ++i)
    z[i] = std::cos(2 * pi * 3 * static_cast<double>(i) / static_cast<double>(n));
  FilterSettings s;
  s.type = FilterType::robust_gaussian;
  s.closed = true;
  s.cutoff_samples = static_cast<double>(n) / 50;  // 50 UPR: 3 lobes pass almost unchanged
  const FilterResult result = filter_profile(z, s);
  EXPECT_TRUE(result.converged);
  const auto& w = result.waviness;
  const double h = waviness_transmission(FilterType::robust_gaussian, 50.0 / 3);
  for (std::size_t i = 0; i < n; ++i) ASSERT_NEAR(w[i], h * z[i], 1e-6) << i;
}

// Direct O(H) evaluation at sample i of the local polynomial regression the filters compute
// (order 1: Gaussian with moment retention; order 2: robust regression with weights delta): an
// independent route to the FFT/overlap-save sums and the cumulative unit-weight moments.
double direct_regression(const std::vector<double>& z, const std::vector<double>& delta,
                         std::size_t i, double cutoff, double constant, int order,
                         double half_width_cutoffs, bool closed) {
  const auto n = static_cast<std::ptrdiff_t>(z.size());
  const auto h = static_cast<std::ptrdiff_t>(std::ceil(half_width_cutoffs * cutoff));
  double s[5] = {}, t[3] = {};
  for (std::ptrdiff_t m = -h; m <= h; ++m) {
    std::ptrdiff_t j = static_cast<std::ptrdiff_t>(i) + m;
    if (closed) j = (j % n + n) % n;
    if (j < 0 || j >= n) continue;
    const double u = static_cast<double>(m) / cutoff;
    const double g = std::exp(-pi * (u / constant) * (u / constant));
    const double d = delta[static_cast<std::size_t>(j)], y = z[static_cast<std::size_t>(j)];
    for (int p = 0; p <= 2 * order; ++p) s[p] += d * g * std::pow(u, p);
    for (int p = 0; p <= order; ++p) t[p] += d * y * g * std::pow(u, p);
  }
  if (order == 1) return (t[0] * s[2] - t[1] * s[1]) / (s[0] * s[2] - s[1] * s[1]);
  const double det = s[0] * (s[2] * s[4] - s[3] * s[3]) - s[1] * (s[1] * s[4] - s[3] * s[2]) +
                     s[2] * (s[1] * s[3] - s[2] * s[2]);
  return (t[0] * (s[2] * s[4] - s[3] * s[3]) - s[1] * (t[1] * s[4] - s[3] * t[2]) +
          s[2] * (t[1] * s[3] - s[2] * t[2])) /
         det;
}

// A rough, wavy profile with sparse outliers, long enough (>= 2^15 samples) that the filters
// work in several overlap-save blocks.
std::vector<double> long_rough_profile(std::size_t n) {
  std::vector<double> z(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i);
    z[i] = std::sin(2 * pi * x / 1700.0) + 0.2 * std::sin(2 * pi * x / 23.7) +
           0.05 * std::sin(2 * pi * x / 3.1 + 0.3 * std::sin(x));
    if (i % 997 == 500) z[i] += 3.0;  // outliers the robust filter must weight out
  }
  return z;
}

TEST(ProfileFilter, BlockedGaussianEqualsDirectRegression) {
  const std::size_t n = 100000;
  const double cutoff = 150.0;
  const auto z = long_rough_profile(n);
  const std::vector<double> ones(n, 1.0);
  for (bool closed : {false, true}) {
    FilterSettings s;
    s.cutoff_samples = cutoff;
    s.closed = closed;
    const auto w = filter_profile(z, s).waviness;
    // Both ends, and every 61st sample (which crosses every block seam with some neighbours).
    for (std::size_t i = 0; i < n; i += (i < 400 || i + 400 > n) ? 1 : 61) {
      // The closed filter is the periodic Gaussian itself; its direct form is the order-1
      // regression with the full window (the first moment of a symmetric kernel vanishes).
      const double direct =
          direct_regression(z, ones, i, cutoff, gaussian_alpha, 1, closed ? 4.0 : 1.5, closed);
      ASSERT_NEAR(w[i], direct, 1e-9) << (closed ? "closed " : "open ") << i;
    }
  }
}

TEST(ProfileFilter, BlockedRobustRegressionIsTheFixedPointOfItsWeights) {
  // The converged mean line w must reproduce itself: the biweights of z - w, fed to the direct
  // weighted quadratic regression, give w again (to the convergence tolerance).
  const std::size_t n = 90000;
  const double cutoff = 150.0;
  const auto z = long_rough_profile(n);
  for (bool closed : {false, true}) {
    FilterSettings s;
    s.type = FilterType::robust_gaussian;
    s.cutoff_samples = cutoff;
    s.closed = closed;
    const FilterResult r = filter_profile(z, s);
    ASSERT_TRUE(r.converged);
    EXPECT_GE(r.zero_weight_samples, n / 997);  // the outliers are weighted out
    std::vector<double> residual(n), magnitude(n);
    for (std::size_t i = 0; i < n; ++i) magnitude[i] = std::abs(residual[i] = z[i] - r.waviness[i]);
    std::nth_element(magnitude.begin(), magnitude.begin() + n / 2, magnitude.end());
    const double c = tukey_c_over_median * magnitude[n / 2];
    std::vector<double> delta(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double q = residual[i] / c;
      delta[i] = std::abs(q) < 1 ? (1 - q * q) * (1 - q * q) : 0.0;
    }
    for (std::size_t i = 0; i < n; i += (i < 400 || i + 400 > n) ? 7 : 67) {
      const double direct = direct_regression(z, delta, i, cutoff, regression_gamma, 2, 2.0, closed);
      ASSERT_NEAR(r.waviness[i], direct, 2e-5) << (closed ? "closed " : "open ") << i;
    }
  }
}

TEST(ProfileFilter, RejectsTooShortProfiles) {
  FilterSettings s;
  s.cutoff_samples = 10;
  EXPECT_THROW(filter_profile(std::vector<double>{1, 2, 3}, s), std::invalid_argument);
  s.cutoff_samples = 0;
  EXPECT_THROW(filter_profile(std::vector<double>{1, 2, 3, 4, 5}, s), std::invalid_argument);
}

}  // namespace
}  // namespace chatterlab::surface
