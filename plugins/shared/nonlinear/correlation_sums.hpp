#pragma once
// Grassberger-Procaccia correlation sums C(r) with a Theiler window (MODELS.md N2): the numerical
// core of the `correlation_dimension` analysis, shared with `surrogates` (its correlation-sum
// statistic). docs/analysis/chaos.md, section "Correlation dimension".
#include <cstddef>
#include <span>
#include <cstdint>
#include <vector>

namespace chatterlab {

// Pair-distance histograms in the maximum norm for embedding dimensions 1..max_dimension (the
// distance in dimension d is the running maximum over the first d coordinates, so one pass
// serves every dimension). Sampled-reference scheme: `references` vectors evenly spread over the
// series are each compared with every other vector outside the Theiler window; memory is
// O(N + dimensions x bins x blocks). Bins: 8 per octave of r / (max - min of the series), exact
// below `cut`.
struct CorrelationSums {
  static constexpr int bins_per_octave = 8;
  static constexpr int octaves = 30;        // r from 2^-30 of the signal range up
  static constexpr std::size_t bins = std::size_t(octaves * bins_per_octave + 2);
  static constexpr std::size_t blocks = 20;  // reference blocks for the bootstrap
  // Distances from half the range up are not binned (the last bin holds them): scaling regions
  // lie far below (C <= 0.1), and most pairs of a large series stop there after one or two
  // coordinates, which halves the cost.
  static constexpr double sampled_cut = 0.5;
  double cut = sampled_cut;  // fraction of the range below which pairs are binned
  int max_dimension = 0;
  double range = 1;  // max - min of the series: r = range x edge
  // counts[(block * max_dimension + (d - 1)) * bins + bin]
  std::vector<std::uint64_t> counts;
  std::vector<double> pairs;  // per block
  // Upper edge of `bin` as a fraction of the range (bin 0: distances below 2^-octaves).
  static double edge(std::size_t bin);
  // ln C(r) of dimension d at the upper bin edges r = range x edge (all blocks; NaN where no pair
  // is counted or beyond the cut), and ln r there.
  std::vector<double> log_correlation(int d) const;
  std::vector<double> log_radii() const;
};
CorrelationSums correlation_sums(std::span<const double> x, int max_dimension, int delay,
                                 std::size_t theiler, std::size_t references);
// The same histograms from every pair (i, j), |i - j| > theiler, closer than `cut` x range (TISEAN
// d2 with -N 0 and -R = cut): exact C(r) for r < cut x range, no sampling. Strips of the first
// delay coordinate, sorted by the second, skip the farther pairs, so the cost grows with `cut`
// (pairs within it), not with N^2. Each pair is counted for both its vectors (as an ordered pair,
// like correlation_sums), so both schemes share one normalisation.
CorrelationSums correlation_sums_within(std::span<const double> x, int max_dimension,
                                        int delay, std::size_t theiler, double cut);

}  // namespace chatterlab
