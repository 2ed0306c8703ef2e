#pragma once
// MODELS.md C1 (book 5.1.3, eqs 5-8..5-10): features of a vibration signal per window of N
// samples, the inputs of the chatter-onset network (C2):
//   variance           sx2 = (1/N) sum_{t=1..N} (x_t - mu)^2                             (5-9)
//   lag-1 correlation  rho1 = sum_{t=2..N} (x_t - mu)(x_{t-1} - mu) / sum_{t=2..N} (x_t - mu)^2
//                                                                                         (5-8)
//   AR(1) residual variance  sa2 = (1/(N-1)) sum_{t=2..N} [(x_t - mu) - rho1 (x_{t-1} - mu)]^2
//                                                                                         (5-10)
// mu is the window mean. (5-8) is used as printed (denominator from t = 2, not the usual t = 1;
// the difference is one term, O(1/N)).
// Plugin `window_features` (plugins/analysis/window_features) writes the series of these over
// consecutive windows. docs/analysis/monitoring.md.
#include "shared/monitoring/features.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/analysis_arrays.hpp"

namespace chatterlab {

class WindowFeaturesAnalysis final : public Analysis, public AnalysisWithArrays {
 public:
  static PluginInfo info();
  explicit WindowFeaturesAnalysis(const ParamValues& params);

  Json analyse(const SampledSeries& series, const Json& context) const override;
  // t_s, variance, rho1, residual_variance as vectors (one value per window).
  ResultWithArrays analyse_with_arrays(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;

 private:
  std::size_t window_, hop_;
};

}  // namespace chatterlab
