#include "shared/monitoring/features.hpp"

#include <cmath>

namespace chatterlab {

WindowFeatures window_features(std::span<const double> x) {
  const std::size_t n = x.size();
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(n);
  double sum_sq = 0.0, lag_product = 0.0, tail_sq = 0.0;  // tail: t = 2..N, as (5-8) prints it
  for (std::size_t t = 0; t < n; ++t) {
    const double d = x[t] - mean;
    sum_sq += d * d;
    if (t > 0) {
      lag_product += d * (x[t - 1] - mean);
      tail_sq += d * d;
    }
  }
  WindowFeatures f;
  f.variance = sum_sq / static_cast<double>(n);
  f.rho1 = tail_sq > 0.0 ? lag_product / tail_sq : 0.0;
  double residual = 0.0;
  for (std::size_t t = 1; t < n; ++t) {
    const double e = (x[t] - mean) - f.rho1 * (x[t - 1] - mean);
    residual += e * e;
  }
  f.residual_variance = residual / static_cast<double>(n - 1);
  return f;
}

FeatureSeries feature_series(std::span<const double> values, std::size_t window, std::size_t hop,
                             double sample_interval) {
  FeatureSeries out;
  for_each_window(values, window, hop, sample_interval,
                  [&](std::size_t first, double t_s, const WindowFeatures& f) {
                    out.first_sample.push_back(first);
                    out.t_s.push_back(t_s);
                    out.features.push_back(f);
                  });
  return out;
}

}  // namespace chatterlab
