// C1 window features (5-8..5-10): a hand-computed window, and AR(1) processes whose generating
// parameters the features must recover within sampling error.
#include "analysis/window_features/window_features.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "shared/monitoring/monitor_common.hpp"
#include "chatterlab/errors.hpp"

namespace chatterlab {
namespace {

// x_t = phi x_{t-1} + a_t, a_t ~ N(0, sigma_a^2), started in its stationary distribution.
std::vector<double> ar1(double phi, double sigma_a, std::size_t n, std::uint64_t seed) {
  monitor::SplitMix64 rng(seed);
  std::vector<double> x(n);
  x[0] = sigma_a / std::sqrt(1.0 - phi * phi) * rng.normal();
  for (std::size_t t = 1; t < n; ++t) x[t] = phi * x[t - 1] + sigma_a * rng.normal();
  return x;
}

TEST(WindowFeatures, HandComputedWindow) {
  // mean 2.5, deviations -1.5 -0.5 0.5 1.5: sx2 = 5/4; rho1 = 1.25 / 2.75 (5-8, sums from t = 2);
  // residuals 0.5/2.75, 2/2.75, 3.5/2.75 -> sa2 = (0.25 + 4 + 12.25) / 2.75^2 / 3.
  const std::vector<double> x{1, 2, 3, 4};
  const WindowFeatures f = window_features(x);
  EXPECT_DOUBLE_EQ(f.variance, 1.25);
  EXPECT_DOUBLE_EQ(f.rho1, 1.25 / 2.75);
  EXPECT_NEAR(f.residual_variance, 16.5 / (2.75 * 2.75) / 3.0, 1e-14);
}

TEST(WindowFeatures, ConstantWindowHasZeroFeatures) {
  const std::vector<double> x(10, 3.0);
  const WindowFeatures f = window_features(x);
  EXPECT_EQ(f.variance, 0.0);
  EXPECT_EQ(f.rho1, 0.0);
  EXPECT_EQ(f.residual_variance, 0.0);
}

// One long window: rho1 -> phi, sa2 -> sigma_a^2, sx2 -> sigma_a^2 / (1 - phi^2). Tolerances are
// 4 standard errors of the estimators for an AR(1) process of n samples:
//   se(rho1) = sqrt((1 - phi^2)/n), se(sa2) = sigma_a^2 sqrt(2/n),
//   se(sx2) = sx2 sqrt(2 (1 + phi^2) / ((1 - phi^2) n)).
TEST(WindowFeatures, RecoversAr1Parameters) {
  const std::size_t n = 40000;
  for (double phi : {-0.6, 0.0, 0.5, 0.9}) {
    SCOPED_TRACE(phi);
    const double sigma_a = 2.0;
    const std::vector<double> x = ar1(phi, sigma_a, n, 11);
    const WindowFeatures f = window_features(x);
    const double dn = static_cast<double>(n);
    const double sx2 = sigma_a * sigma_a / (1.0 - phi * phi);
    EXPECT_NEAR(f.rho1, phi, 4.0 * std::sqrt((1.0 - phi * phi) / dn));
    EXPECT_NEAR(f.residual_variance, sigma_a * sigma_a, 4.0 * sigma_a * sigma_a * std::sqrt(2.0 / dn));
    EXPECT_NEAR(f.variance, sx2, 4.0 * sx2 * std::sqrt(2.0 * (1.0 + phi * phi) / ((1.0 - phi * phi) * dn)));
  }
}

// The book's 10-sample windows: averaged over many windows, rho1 tells the processes apart, sa2
// still estimates sigma_a^2 with the small-sample bias of a fitted AR(1) (below 25 % here), and
// sx2 (about the window's own mean) has the exact expectation
//   E[sx2] = sigma_x^2 [1 - (1/N)(1 + 2 sum_{k=1}^{N-1} (1 - k/N) phi^k)].
TEST(WindowFeatures, TenSampleWindowsSeparateProcesses) {
  const std::vector<double> white = ar1(0.0, 1.0, 20000, 3), correlated = ar1(0.8, 1.0, 20000, 4);
  auto mean_features = [](const std::vector<double>& x) {
    const FeatureSeries fs = feature_series(x, 10, 10, 1.0);
    WindowFeatures m;
    for (const auto& f : fs.features) {
      m.variance += f.variance / static_cast<double>(fs.features.size());
      m.rho1 += f.rho1 / static_cast<double>(fs.features.size());
      m.residual_variance += f.residual_variance / static_cast<double>(fs.features.size());
    }
    return m;
  };
  const WindowFeatures w = mean_features(white), c = mean_features(correlated);
  EXPECT_LT(w.rho1, 0.0);  // the short-window bias of rho1 is negative
  EXPECT_GT(c.rho1, 0.4);
  EXPECT_NEAR(w.residual_variance, 1.0, 0.25);
  EXPECT_NEAR(c.residual_variance, 1.0, 0.25);
  auto expected_variance = [](double phi, int n) {
    double sum = 0;
    for (int k = 1; k < n; ++k) sum += (1.0 - double(k) / n) * std::pow(phi, k);
    return 1.0 / (1.0 - phi * phi) * (1.0 - (1.0 + 2.0 * sum) / n);
  };
  EXPECT_NEAR(w.variance, expected_variance(0.0, 10), 0.05 * expected_variance(0.0, 10));
  EXPECT_NEAR(c.variance, expected_variance(0.8, 10), 0.05 * expected_variance(0.8, 10));
}

TEST(WindowFeatures, SeriesTimesAndHop) {
  std::vector<double> x(35);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::sin(0.3 * static_cast<double>(i));
  const FeatureSeries fs = feature_series(x, 10, 10, 0.5);
  ASSERT_EQ(fs.features.size(), 3u);  // the 5 samples left over make no window
  EXPECT_EQ(fs.first_sample[2], 20u);
  EXPECT_DOUBLE_EQ(fs.t_s[0], 4.5);   // last sample of the window, 9 * 0.5 s
  EXPECT_EQ(feature_series(x, 10, 5, 0.5).features.size(), 6u);
}

TEST(WindowFeatures, PluginThroughRegistry) {
  const auto& entry = analysis_registry().at("window_features");
  auto analysis = entry.create(ParamValues(Json{{"window_samples", 10}, {"hop_samples", nullptr}}));
  SampledSeries s;
  const std::vector<double> x = ar1(0.5, 1.0, 1000, 5);
  s.values = x;
  s.sample_interval = 1.0 / 8000.0;
  const Json r = analysis->analyse(s, Json::object());
  EXPECT_EQ(r.at("rho1").size(), 100u);
  EXPECT_DOUBLE_EQ(r.at("t_s")[0].get<double>(), 9.0 / 8000.0);

  s.values = s.values.first(7);
  s.name = "displacement_m";
  try {
    analysis->analyse(s, Json::object());
    FAIL() << "no error for a signal shorter than the window";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "window_features.window_samples = 10: the signal 'displacement_m' has 7 samples, "
                 "fewer than the 10 this needs");
  }
}

}  // namespace
}  // namespace chatterlab
