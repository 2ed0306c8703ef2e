#pragma once
// Analysis `embedding` (MODELS.md N1): the delay from the first minimum of the average mutual
// information (autocorrelation 1/e as the reported fallback), the embedding dimension from false
// nearest neighbours (Kennel et al. 1992) cross-checked with Cao's method (E1 saturation, E2 for
// determinism), and the Theiler window from a space-time separation plot. Other analyses reuse
// its result through the study's shared context (resolve_embedding). docs/analysis/chaos.md.
#include <string>
#include <vector>

#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

struct DelayChoice {
  int delay = 1;
  std::string rule;                 // which criterion chose it
  bool from_mutual_information = false;
  std::vector<double> mutual_information, autocorrelation;  // index = lag in samples
};
// AMI with `bins` equal-width bins over lags 0..max_lag; the first lag whose AMI is below both
// neighbours within +-2 lags and below the bias floor + half the drop from lag 0 to there is the
// first minimum; else the first lag where the autocorrelation falls below 1/e.
DelayChoice choose_delay(const std::vector<double>& x, std::size_t max_lag, int bins);

struct DimensionChoice {
  int fnn_dimension = 0;   // 0: the FNN fraction never fell below the threshold
  int cao_dimension = 0;   // 0: E1 never saturated
  std::vector<double> fnn_fraction;  // index d-1, d = 1..max_dimension
  std::vector<double> cao_e1, cao_e2;
  bool deterministic = false;  // some E2(d) differs from 1 (Cao)
  double e2_max_deviation = 0;
};
DimensionChoice choose_dimension(const std::vector<double>& x, int delay, int max_dimension,
                                 std::size_t theiler, double distance_ratio,
                                 double fnn_threshold);

// Delay, dimension and Theiler window for an analysis that embeds the series: its own
// parameters (delay_samples, embedding_dimension, theiler_window_samples) when set, else the
// earlier `embedding` result in `context`, else chosen here with the embedding defaults.
// `source` says where each came from (for the result's reasons).
struct EmbeddingParameters {
  int delay = 1;
  int dimension = 2;
  std::size_t theiler = 0;
  std::string source;
};
EmbeddingParameters resolve_embedding(const ParamValues& params, const SampledSeries& series,
                                      const Json& context);

class EmbeddingAnalysis final : public nonlinear::ParameterisedAnalysis {
 public:
  static PluginInfo info();
  using ParameterisedAnalysis::ParameterisedAnalysis;
  Json analyse(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
