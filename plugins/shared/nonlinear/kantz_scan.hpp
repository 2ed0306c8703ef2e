#pragma once
// Kantz's largest-Lyapunov divergence curves over a scan of embedding dimensions and radii, the
// statistic of TISEAN's lyap_k (MODELS.md N3/N4), used by the `lyapunov` analysis
// (radius_scan_count) and benchmarked against lyap_k in tests/bench/chaos_bench.cpp.
#include <cstddef>
#include <span>
#include <vector>

namespace chatterlab {

// Blocks of consecutive reference points whose sums are kept apart (block bootstrap).
inline constexpr std::size_t kantz_blocks = 20;

// A divergence curve S(k), k < steps, kept as sums per block of reference points:
// sum[b * steps + k] of ln distance and count[b * steps + k] of the references contributing.
struct BlockCurve {
  std::size_t steps = 0;
  std::vector<double> sum, count;
  // The mean curve with block b weighted by weights[b] (a bootstrap replicate); NaN where no
  // reference contributes.
  std::vector<double> mean(const std::vector<double>& weights) const;
  std::vector<double> mean() const { return mean(std::vector<double>(kantz_blocks, 1.0)); }
  // References contributing at k = 0 (with a neighbour).
  double references_at_start() const;
};

// Kantz's divergence the way TISEAN's lyap_k computes it, for a scan over embedding dimensions
// [min_dimension, max_dimension] and several radii eps at once: for each reference vector i,
// every neighbour j (|i - j| > theiler) with |X_i - X_j| <= eps (Euclidean, in that dimension;
// a neighbour within eps in m + 1 dimensions is also within eps in m) and
//   S(k) = < ln sqrt( < |X_{i+k} - X_{j+k}|^2 >_j ) >_i .
// One fixed-radius search at the largest eps serves all radii and dimensions: each neighbour's
// separation history is computed once (coordinate differences shared by all dimensions) and
// binned by the smallest eps that holds it; the bins are summed per reference. The search runs
// over rows (half-eps boxes of the first coordinate), each sorted along the second coordinate
// (if m >= 2): a +-eps stretch per row. `references` = 0 takes every vector. Neighbour sets and
// radius bins are decided in double precision; the separation histories are summed from
// single-precision copies of the signal, which moves S(k) by at most about
// sqrt(m) 2^-24 (max - min) / (rms separation) (see kantz_scan.cpp).
// `stride` > 1 evaluates S only every `stride` samples (curve point k is S(k stride)), for flows
// whose divergence takes hundreds of samples: the histories hold every stride-th sample, so the
// delay must be a multiple of the stride.
struct KantzScan {
  int min_dimension = 1, max_dimension = 1;
  std::vector<double> radii;  // ascending
  std::size_t steps = 0, stride = 1, references = 0;
  // Per block of references (kantz_blocks, for a bootstrap) b, radius r, dimension index d = m - min_dimension:
  // sum[((b * radii + r) * dims + d) * steps + k] of ln rms distance, count likewise.
  std::vector<double> sum, count;
  std::size_t dimensions() const { return std::size_t(max_dimension - min_dimension + 1); }
  // Mean curve S(k) for radius index r and dimension m (NaN where no reference had neighbours).
  std::vector<double> curve(std::size_t r, int m) const;
  // The same with its sums per block.
  BlockCurve block_curve(std::size_t r, int m) const;
};
KantzScan kantz_scan(std::span<const double> x, int min_dimension, int max_dimension, int delay,
                     std::size_t theiler, std::size_t steps, std::size_t references,
                     std::vector<double> radii, std::size_t stride = 1);

}  // namespace chatterlab
