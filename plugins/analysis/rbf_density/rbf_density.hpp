#pragma once
// MODELS.md C3 (book 5.2, eqs 5-11..5-22): amplitude-domain chatter detection. A stable grinding
// signal is close to Gaussian (density peak at the mean); chatter is a sine with random phase,
// whose arcsine density (5-13) peaks at the extremes; their sum has the convolved density (5-15),
// whose peak moves from the mean towards the extremes as the sine grows. The density of the
// latest window (book: 50 samples) is estimated by a Gaussian RBF network (5-20, 5-21)
//     P(x) = sum_k w_k N(x; c_k, s_k),   sum_k w_k = 1,   s_k = half the distance from c_k to
//     the nearest other centre,
// and chatter is flagged when (5-22)
//     |x_at_max_density - mean| / |x_max - mean| >= rho     (book: rho = 0.2).
// The book's network learns unsupervised with adaptive centres but gives no more detail; here the
// centres are a 1-D k-means (Lloyd) clustering of the window's samples started from evenly spaced
// quantiles, w_k = share of samples in cluster k. Deterministic, and the same for every window.
#include <cstddef>
#include <span>
#include <vector>

#include "shared/monitoring/monitor_common.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/analysis_arrays.hpp"

namespace chatterlab {

struct RbfDensity {
  std::vector<double> centre, width, weight;
  double operator()(double x) const;  // (5-20)
};

// The RBF density of `samples` with at most `nodes` centres (fewer when samples coincide).
RbfDensity fit_rbf_density(std::span<const double> samples, std::size_t nodes);

struct DensityCriterion {
  double x_at_max_density = 0.0, mean = 0.0, x_max = 0.0;
  double ratio = 0.0;  // left side of (5-22); 0 for a constant window
};

// (5-22) for `samples` with their fitted density; the maximum of P is searched on a grid of 801
// points over [min, max] of the samples plus the centres.
DensityCriterion density_criterion(std::span<const double> samples, const RbfDensity& density);

class RbfDensityAnalysis final : public Analysis, public AnalysisWithArrays, public monitor::Detector {
 public:
  static PluginInfo info();
  explicit RbfDensityAnalysis(const ParamValues& params);

  Json analyse(const SampledSeries& series, const Json& context) const override;
  // t_s, score and alarm (one value per evaluation) as vectors.
  ResultWithArrays analyse_with_arrays(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;

  void check(const SampledSeries& series) const override;
  monitor::ScoreTrack scores(const SampledSeries& series, Json& details) const override;
  std::size_t persistence() const override { return persistence_; }

  // The window ending at sample `last_sample`: its density on a grid, the criterion's points and
  // a label (for "stable vs chatter" snapshot plots).
  Json snapshot(const SampledSeries& series, std::size_t last_sample) const override;

 private:
  std::size_t window_, hop_, nodes_, persistence_;
  double rho_;
};

}  // namespace chatterlab
