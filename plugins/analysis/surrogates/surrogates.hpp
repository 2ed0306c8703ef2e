#pragma once
// Analysis `surrogates`: test for determinism against the null hypothesis "linear Gaussian
// process observed through a static monotone nonlinearity" with IAAFT surrogates (Schreiber and
// Schmitz 1996: same amplitude distribution and, iteratively, the same power spectrum). The
// discriminating statistic is the one-step error of a locally constant (nearest-neighbour)
// predictor in the delay embedding; a rank test rejects the null hypothesis at significance
// 1 / (surrogates + 1) when the data predict better than every surrogate. Time-reversal
// asymmetry is reported as a second statistic. docs/analysis/chaos.md, section "Surrogates".
#include <cstdint>
#include <vector>

#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// One IAAFT surrogate of x (iterations until the ranks stop changing, at most max_iterations).
std::vector<double> iaaft_surrogate(const std::vector<double>& x, std::uint64_t seed,
                                    int max_iterations = 200);

// Normalised RMS one-step error of the locally constant predictor (k nearest neighbours).
double prediction_error(const std::vector<double>& x, int dimension, int delay,
                        std::size_t theiler, std::size_t neighbours, std::size_t references);

// <(x_{n+tau} - x_n)^3> / <(x_{n+tau} - x_n)^2>^{3/2}: zero for time-reversible processes.
double time_reversal_asymmetry(const std::vector<double>& x, int delay);

class Surrogates final : public nonlinear::ParameterisedAnalysis {
 public:
  static PluginInfo info();
  using ParameterisedAnalysis::ParameterisedAnalysis;
  Json analyse(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
