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
  for (std::size_t start = 0; start + window <= values.size(); start += hop) {
    out.first_sample.push_back(start);
    out.t_s.push_back(static_cast<double>(start + window - 1) * sample_interval);
    out.features.push_back(window_features(values.subspan(start, window)));
  }
  return out;
}

}  // namespace chatterlab
