#pragma once
// Divergence curves of neighbouring trajectories in a delay embedding and what the `lyapunov`
// analysis reads from them (MODELS.md N3/N4): Rosenstein's nearest-neighbour curve (Kantz's
// curves are in kantz_scan.hpp), the linear region of a curve, the curve resolution and
// horizon, and neighbour distances with the local dimensions they imply.
#include <cstddef>
#include <span>
#include <vector>

#include "shared/nonlinear/kantz_scan.hpp"

namespace chatterlab {

// Rosenstein et al. (1993): S(k) = < ln |X_{i + k stride} - X_{j(i) + k stride}| >_i over
// `references` vectors evenly spread, j(i) the nearest neighbour outside the Theiler window
// (Euclidean), k = 0..steps-1; per-block sums for the bootstrap.
BlockCurve rosenstein_curve(std::span<const double> x, int dimension, int delay,
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

// The horizon the curves need: 1.5 x the time a pilot Rosenstein curve (500 references, up to
// `horizon` samples) takes to make 90 % of its rise, at least 30 samples; the whole `horizon`
// when it never rises by ln 2 (no divergence must be seen over a long time, not over 30
// samples).
std::size_t saturation_horizon(std::span<const double> x, int dimension, int delay,
                               std::size_t theiler, std::size_t horizon, std::size_t min_points);

// Median distance (Euclidean, dimension `dimension`, vectors below `limit`) to the k-th nearest
// neighbour for each k of `ks` (ascending), over `sample` references evenly spread; NaN where
// fewer than half of them have k neighbours (at most a quarter of the vectors is asked for).
std::vector<double> neighbour_distances(std::span<const double> x, int dimension, int delay,
                                        std::size_t theiler, std::size_t limit,
                                        const std::vector<std::size_t>& ks, std::size_t sample);
// Local dimension between the neighbour counts k_q and k_{q+1}: ln(k ratio) / ln(distance
// ratio) (NaN where the distances do not grow).
std::vector<double> local_dimensions(const std::vector<double>& distances,
                                     const std::vector<std::size_t>& ks);

}  // namespace chatterlab
