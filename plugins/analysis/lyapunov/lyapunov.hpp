#pragma once
// Analysis `lyapunov` (MODELS.md N3/N4, largest exponent): divergence of neighbouring
// trajectories in the delay embedding by Rosenstein et al. (1993, nearest neighbour) and Kantz
// (1994, all neighbours within eps), each a curve S(k) = < ln distance after k steps >, with the
// exponent the slope of its automatically detected linear region; reported per sample and per
// second of signal time. docs/analysis/chaos.md, section "Largest Lyapunov exponent".
#include <vector>

#include "analysis/lyapunov/kantz_scan.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// Divergence curves with per-block sums (20 blocks of reference points, for the bootstrap).
struct DivergenceCurves {
  static constexpr std::size_t blocks = kantz_blocks;
  std::size_t steps = 0;  // k = 0..steps-1
  // sums[(block * steps + k)] and counts likewise, for each method
  std::vector<double> rosenstein_sum, rosenstein_count, kantz_sum, kantz_count;
  double radius = 0;  // Kantz eps
  std::size_t references = 0;
};
// Both curves for an embedding of `x`; `radius` <= 0 picks eps as the median distance to the
// 8th nearest neighbour. Neighbours obey the Theiler window.
DivergenceCurves divergence_curves(const std::vector<double>& x, int dimension, int delay,
                                   std::size_t theiler, std::size_t steps, std::size_t references,
                                   double radius);

// The slope of the linear region of a divergence curve y(k) (k = 0..): the longest run of local
// slopes (each over a fifth of the range) within 10 % of their median, before the curve has made
// 80 % of its rise to saturation.
struct LinearRegionFit {
  bool found = false;
  bool diverging = true;  // false: the curve rises by less than ln 2 (no exponential growth)
  std::size_t begin = 0, end = 0;
  double slope = 0, intercept = 0;
};
LinearRegionFit linear_region(const std::vector<double>& y);

class LyapunovAnalysis final : public nonlinear::ParameterisedAnalysis {
 public:
  static PluginInfo info();
  using ParameterisedAnalysis::ParameterisedAnalysis;
  Json analyse(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
