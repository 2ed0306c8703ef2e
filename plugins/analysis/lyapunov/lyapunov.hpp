#pragma once
// Analysis `lyapunov` (MODELS.md N3/N4, largest exponent): divergence of neighbouring
// trajectories in the delay embedding. Kantz's curves (1994, all neighbours within eps) for three
// embedding dimensions x five neighbourhood sizes, Rosenstein's (1993, the nearest neighbour)
// for the same dimensions; each curve S(k) = < ln distance after k samples > with the slope of its
// automatically detected linear region. The exponent is reported only when the curves show
// exponential divergence: a linear region whose slope is the same for several dimensions and
// neighbourhood sizes, with curves for different sizes staying apart (parallel) over it, as
// they do for deterministic divergence and do not for noise, where neighbours separate at
// once. docs/analysis/chaos.md, section "Largest Lyapunov exponent".
#include <string>
#include <vector>

#include "analysis/lyapunov/kantz_scan.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// Rosenstein et al. (1993): S(k) = < ln |X_{i + k stride} - X_{j(i) + k stride}| >_i over
// `references` vectors evenly spread, j(i) the nearest neighbour outside the Theiler window
// (Euclidean), k = 0..steps-1; per-block sums for the bootstrap.
BlockCurve rosenstein_curve(const std::vector<double>& x, int dimension, int delay,
                            std::size_t theiler, std::size_t steps, std::size_t stride,
                            std::size_t references);

// The slope of the linear region of a divergence curve y(k) (k = 0..): the longest run of local
// slopes (each over a fifth of the range) within 10 % of their median, before the curve has made
// 80 % of its rise to saturation. A curve that rises by less than ln 2 shows no exponential
// separation (diverging = false; slope = its mean trend).
struct LinearRegionFit {
  bool found = false;
  bool diverging = true;
  std::size_t begin = 0, end = 0;
  double slope = 0, intercept = 0;
};
LinearRegionFit linear_region(const std::vector<double>& y);

// Largest divisor of `delay` that still leaves `min_points` curve points over `horizon` samples
// (1 if none): the history stride of kantz_scan and rosenstein_curve.
std::size_t curve_stride(int delay, std::size_t horizon, std::size_t min_points);

class LyapunovAnalysis final : public nonlinear::ParameterisedAnalysis {
 public:
  static PluginInfo info();
  using ParameterisedAnalysis::ParameterisedAnalysis;
  Json analyse(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
