#pragma once
// Analysis `correlation_dimension` (MODELS.md N2): Grassberger-Procaccia correlation sums C(r)
// with a Theiler window (no self-pairs, no temporally correlated pairs), D2 from an automatically
// detected scaling region (plateau of the local slopes d ln C / d ln r), D2 versus embedding
// dimension until it saturates, a noise level that moves the scaling window, and a bootstrap
// confidence interval. docs/analysis/chaos.md, section "Correlation dimension".
#include "shared/nonlinear/correlation_sums.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

class CorrelationDimension final : public nonlinear::ParameterisedAnalysis {
 public:
  static PluginInfo info();
  using ParameterisedAnalysis::ParameterisedAnalysis;
  Json analyse(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
