#pragma once
// MODELS.md C1 (book 5.1.3, eqs 5-8..5-10): features of a vibration signal per window of N
// samples, the inputs of the chatter-onset network (C2):
//   variance           sx2 = (1/N) sum_{t=1..N} (x_t - mu)^2                             (5-9)
//   lag-1 correlation  rho1 = sum_{t=2..N} (x_t - mu)(x_{t-1} - mu) / sum_{t=2..N} (x_t - mu)^2
//                                                                                         (5-8)
//   AR(1) residual variance  sa2 = (1/(N-1)) sum_{t=2..N} [(x_t - mu) - rho1 (x_{t-1} - mu)]^2
//                                                                                         (5-10)
// mu is the window mean. (5-8) is used as printed (denominator from t = 2, not the usual t = 1;
// the difference is one term, O(1/N)). Plugin `window_features`: the series of these over
// consecutive windows. docs/analysis/monitoring.md.
// Shared by the window_features and bp_network analyses and the chatter_monitor study kind.
#include <cstddef>
#include <span>
#include <vector>

namespace chatterlab {

struct WindowFeatures {
  double variance = 0.0;           // sx2 (5-9), signal unit^2
  double rho1 = 0.0;               // (5-8); 0 for a constant window (undefined there)
  double residual_variance = 0.0;  // sa2 (5-10), signal unit^2
};

// Features of one window (at least 3 samples).
WindowFeatures window_features(std::span<const double> window);

struct FeatureSeries {
  std::vector<std::size_t> first_sample;  // index of each window's first sample
  std::vector<double> t_s;                // time of each window's last sample
  std::vector<WindowFeatures> features;
};

// Windows of `window` samples starting every `hop` samples, from sample 0 while they fit.
FeatureSeries feature_series(std::span<const double> values, std::size_t window, std::size_t hop,
                             double sample_interval);

// The same windows one at a time, nothing stored: visit(first_sample, t_s, features) in order,
// t_s the time of the window's last sample. For signals of 10^7 samples, whose FeatureSeries
// (40 bytes a window) a caller that only reduces it need not hold.
template <class Visit>
void for_each_window(std::span<const double> values, std::size_t window, std::size_t hop,
                     double sample_interval, Visit&& visit) {
  for (std::size_t start = 0; start + window <= values.size(); start += hop)
    visit(start, static_cast<double>(start + window - 1) * sample_interval,
          window_features(values.subspan(start, window)));
}

}  // namespace chatterlab
