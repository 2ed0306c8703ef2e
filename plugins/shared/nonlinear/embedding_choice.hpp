#pragma once
// Delay, embedding dimension and Theiler window of a scalar series (MODELS.md N1): the numerical
// core of the `embedding` analysis, shared with every analysis that embeds a series
// (correlation_dimension, lyapunov, lyapunov_spectrum, surrogates) through resolve_embedding.
// docs/analysis/chaos.md.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/params.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"

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
DelayChoice choose_delay(std::span<const double> x, std::size_t max_lag, int bins);

struct DimensionChoice {
  int fnn_dimension = 0;   // 0: the FNN fraction never fell below the threshold
  int cao_dimension = 0;   // 0: E1 never saturated
  std::vector<double> fnn_fraction;  // index d-1, d = 1..max_dimension
  std::vector<double> cao_e1, cao_e2;
  bool deterministic = false;  // some E2(d) differs from 1 (Cao)
  double e2_max_deviation = 0;
};
DimensionChoice choose_dimension(std::span<const double> x, int delay, int max_dimension,
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
// Appends the embedding to an analysis result: delay_samples, embedding_dimension,
// theiler_window_samples, embedding_source.
void add_embedding_fields(Json& result, const EmbeddingParameters& embedding);

// Defaults of the `embedding` analysis, also used when another analysis embeds without one.
constexpr int embedding_default_bins = 16;
constexpr int embedding_default_max_dimension = 10;
constexpr double embedding_default_distance_ratio = 10.0;
constexpr double embedding_default_fnn_threshold = 0.01;
std::size_t embedding_default_max_lag(std::size_t n);    // min(1000, n / 10)
std::size_t theiler_range(int delay);          // lags the space-time separation plot examines

// Delay (fixed when `fixed_delay` is an integer), dimension (FNN, else Cao, else the largest
// examined) and the space-time Theiler window of the chosen embedding.
struct EmbeddingChoice {
  DelayChoice delay;
  DimensionChoice dimension;
  nonlinear::TheilerChoice theiler;
  int chosen_dimension = 2;
};
EmbeddingChoice choose_embedding(std::span<const double> x, std::size_t max_lag, int bins,
                                 int max_dimension, double ratio, double threshold,
                                 const Json& fixed_delay);

}  // namespace chatterlab
