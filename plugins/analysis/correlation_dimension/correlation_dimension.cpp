#include "analysis/correlation_dimension/correlation_dimension.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>

#include "analysis/embedding/embedding.hpp"
#include "analysis/nonlinear_common/box_grid.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"

namespace chatterlab {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
// Exponent/mantissa key of 2^-octaves: (biased exponent << 3) with 3 mantissa bits = 8 bins per
// octave read straight from the IEEE-754 bits (no logarithm per pair).
constexpr std::uint64_t key_base = std::uint64_t(1023 - CorrelationSums::octaves) << 3;
static_assert(CorrelationSums::bins_per_octave == 8);

inline std::size_t bin_of(double v) {  // v = distance / range, >= 0
  const std::uint64_t key = std::bit_cast<std::uint64_t>(v) >> 49;
  if (key < key_base) return 0;
  return std::min<std::size_t>(std::size_t(key - key_base) + 1, CorrelationSums::bins - 1);
}

// Pairs at or beyond the cut go to the last bin, so that the cumulative count reaches the pair
// total.
void add_uncounted_pairs(CorrelationSums& sums) {
  const std::size_t bins = CorrelationSums::bins, dims = std::size_t(sums.max_dimension);
  for (std::size_t b = 0; b < CorrelationSums::blocks; ++b)
    for (std::size_t d = 0; d < dims; ++d) {
      std::uint64_t* h = sums.counts.data() + (b * dims + d) * bins;
      std::uint64_t counted = 0;
      for (std::size_t k = 0; k < bins; ++k) counted += h[k];
      h[bins - 1] += std::uint64_t(sums.pairs[b]) - counted;
    }
}

// Zeroed histograms for dimensions 1..max_dimension of the series x.
CorrelationSums empty_sums(const std::vector<double>& x, int max_dimension) {
  CorrelationSums out;
  out.max_dimension = max_dimension;
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  out.range = *hi - *lo;
  out.counts.assign(CorrelationSums::blocks * std::size_t(max_dimension) * CorrelationSums::bins,
                    0);
  out.pairs.assign(CorrelationSums::blocks, 0.0);
  return out;
}

// (x - min) / range: distances come out as fractions of the range directly.
std::vector<double> normalised(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double scale = 1.0 / (*hi - *lo);
  std::vector<double> y(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) y[i] = (x[i] - *lo) * scale;
  return y;
}

using Vector4 = double __attribute__((vector_size(32)));          // AVX2; SSE2: two halves
constexpr std::size_t max_pair_dimensions = 32;  // of correlation_sums_within (the parameter: 30)
using Bits4 = std::uint64_t __attribute__((vector_size(32)));

// What the pair pass of correlation_sums_within shares between its vectors: the grid, the
// coordinates and bootstrap blocks of the rows in hand (copied in grid order), and the compact
// per-thread counts, indexed [(dimension index d * kept_bins + bin) * blocks + block].
struct PairPass {
  const nonlinear::BoxGrid* grid = nullptr;
  const nonlinear::CopiedCoordinates* coordinates = nullptr;  // stride: dimensions rounded to 4
  const std::uint8_t* window_block = nullptr;                 // from window_begin on
  std::size_t window_begin = 0, dims = 0, theiler = 0, kept_bins = 0;
  double cut = 0;
  std::uint32_t* compact = nullptr;
  // d * kept_bins * blocks for each dimension index d (padded to groups of four; plain integers
  // loaded with memcpy: heap storage of 32-byte vectors is not reliably 32-byte aligned).
  std::vector<std::uint64_t> row_base;
  std::vector<std::size_t>* kept = nullptr;  // scratch
};

// Every pair (vector of grid entry q, a vector in its forward runs) closer than the cut in the
// maximum norm, counted in every dimension 2..dims where it stays closer (for both of its
// vectors' blocks). First the candidates closer than the cut in the first two coordinates (the
// grid's), compacted without branches (about half of them are not); then, per kept pair, the
// coordinate differences four dimensions at a time, their running maximum across the lanes
// and the bins from the exponent bits, before the scalar count updates.
[[gnu::target_clones("avx2", "default")]] void count_forward_pairs(const PairPass& pass,
                                                                   std::size_t q,
                                                                   const std::size_t* first,
                                                                   const std::size_t* last,
                                                                   std::size_t runs) {
  const nonlinear::BoxGrid::Entry* entries = pass.grid->entries();
  const std::size_t i = entries[q].index;
  const double a = entries[q].a, b = entries[q].b;
  std::size_t candidates = 0;
  for (std::size_t run = 0; run < runs; ++run) candidates += last[run] - first[run];
  if (pass.kept->size() < candidates) pass.kept->resize(candidates);
  std::size_t* __restrict kept = pass.kept->data();
  std::size_t count = 0;
  for (std::size_t run = 0; run < runs; ++run)
    for (std::size_t e = first[run]; e < last[run]; ++e) {
      const std::size_t j = entries[e].index;
      const double d01 = std::max(std::abs(entries[e].a - a), std::abs(entries[e].b - b));
      kept[count] = e;
      count += (d01 < pass.cut) & ((j > i ? j - i : i - j) > pass.theiler) ? 1 : 0;
    }
  const std::size_t groups = pass.coordinates->stride() / 4, blocks = CorrelationSums::blocks;
  const std::size_t block_i = pass.window_block[q - pass.window_begin];
  const double* yi = pass.coordinates->of(q);
  // Below the smallest bin edge 2^-octaves every distance maps to key_base - 1, i.e. bin 0.
  const double floor = std::nextafter(std::ldexp(1.0, -CorrelationSums::octaves), 0.0);
  std::uint64_t offset[max_pair_dimensions];  // of each dimension's count row
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t e = kept[k];
    const double* yj = pass.coordinates->of(e);
    Vector4 carry = {};
    Vector4 closer = {};  // per lane: dimensions closer than the cut (a prefix of them)
    for (std::size_t g = 0; g < groups; ++g) {
      Vector4 own, other;
      std::memcpy(&own, yi + 4 * g, sizeof own);
      std::memcpy(&other, yj + 4 * g, sizeof other);
      Vector4 v = own - other;
      v = v < 0 ? -v : v;
      // Running maximum over the dimensions: the maximum-norm distance in each.
      const Vector4 zero = {};
      Vector4 shifted = __builtin_shuffle(v, zero, Bits4{4, 0, 1, 2});
      v = v > shifted ? v : shifted;
      shifted = __builtin_shuffle(v, zero, Bits4{4, 4, 0, 1});
      v = v > shifted ? v : shifted;
      v = v > carry ? v : carry;
      carry = Vector4{v[3], v[3], v[3], v[3]};
      closer += v < pass.cut ? Vector4{1, 1, 1, 1} : Vector4{};
      const Vector4 clamped = v > floor ? v : Vector4{floor, floor, floor, floor};
      Bits4 key;
      std::memcpy(&key, &clamped, sizeof key);
      Bits4 row;
      std::memcpy(&row, pass.row_base.data() + 4 * g, sizeof row);
      row += ((key >> 49) - (key_base - 1)) * blocks;
      std::memcpy(offset + 4 * g, &row, sizeof row);
    }
    const std::size_t block_j = pass.window_block[e - pass.window_begin];
    // Beyond the cut in one dimension: beyond it in every higher one (counted as uncounted).
    // Dimension index 0 is counted by the sorted pass.
    const auto within = std::size_t((closer[0] + closer[1]) + (closer[2] + closer[3]));
    const std::size_t end = std::min(within, pass.dims);
    for (std::size_t d = 1; d < end; ++d) {
      std::uint32_t* row = pass.compact + offset[d];
      ++row[block_i];
      ++row[block_j];
    }
  }
}
}  // namespace

double CorrelationSums::edge(std::size_t bin) {
  return std::ldexp(1.0 + double(bin % 8) / 8.0, int(bin / 8) - octaves);
}

CorrelationSums correlation_sums(const std::vector<double>& x, int max_dimension, int delay,
                                 std::size_t theiler, std::size_t references) {
  CorrelationSums out = empty_sums(x, max_dimension);
  std::vector<double> y = normalised(x);
  const std::size_t n = nonlinear::vector_count(x.size(), max_dimension, delay);
  const std::size_t dims = std::size_t(max_dimension);
  const std::size_t bins = CorrelationSums::bins, blocks = CorrelationSums::blocks;
  references = std::max<std::size_t>(1, std::min(references, n));
  const std::size_t tau = std::size_t(delay);
#pragma omp parallel
  {
    std::vector<std::uint64_t> local(out.counts.size(), 0);
    std::vector<double> local_pairs(blocks, 0.0);
#pragma omp for schedule(dynamic, 4)
    for (std::size_t r = 0; r < references; ++r) {
      const std::size_t i = std::size_t(double(r) * double(n) / double(references));
      const std::size_t block = r * blocks / references;
      std::uint64_t* h = local.data() + block * dims * bins;
      auto scan = [&](std::size_t from, std::size_t to) {
        for (std::size_t j = from; j < to; ++j) {
          double dist = 0;
          for (std::size_t d = 0; d < dims; ++d) {
            dist = std::max(dist, std::abs(y[i + d * tau] - y[j + d * tau]));
            // The running maximum only grows: this pair is beyond the cut in every higher
            // dimension too, and is counted there through the pair total (overflow bin).
            if (dist >= CorrelationSums::sampled_cut) break;
            ++h[d * bins + bin_of(dist)];
          }
        }
      };
      // Both sides of i outside the Theiler window |i - j| <= theiler.
      if (i > theiler) scan(0, i - theiler);
      if (i + theiler + 1 < n) scan(i + theiler + 1, n);
      local_pairs[block] += double((i > theiler ? i - theiler : 0) +
                                   (i + theiler + 1 < n ? n - i - theiler - 1 : 0));
    }
#pragma omp critical
    {
      for (std::size_t k = 0; k < local.size(); ++k) out.counts[k] += local[k];
      for (std::size_t b = 0; b < blocks; ++b) out.pairs[b] += local_pairs[b];
    }
  }
  add_uncounted_pairs(out);
  return out;
}

CorrelationSums correlation_sums_within(const std::vector<double>& x, int max_dimension,
                                        int delay, std::size_t theiler, double cut) {
  if (max_dimension < 1 || std::size_t(max_dimension) > max_pair_dimensions || !(cut > 0))
    throw PointFailure(fmt::format("correlation_sums_within: needs 1 <= dimensions <= {} and a "
                                   "positive cut (got {} and {})",
                                   max_pair_dimensions, max_dimension, cut));
  CorrelationSums out = empty_sums(x, max_dimension);
  out.cut = cut;
  std::vector<double> y = normalised(x);
  const std::size_t n = nonlinear::vector_count(x.size(), max_dimension, delay);
  const std::size_t dims = std::size_t(max_dimension);
  const std::size_t bins = CorrelationSums::bins, blocks = CorrelationSums::blocks;
  const std::size_t tau = std::size_t(delay);
  // Bootstrap block of each vector, looked up (a division per pair cost as much as the count).
  std::vector<std::uint8_t> block_of_vector(n);
  for (std::size_t i = 0; i < n; ++i) block_of_vector[i] = std::uint8_t(i * blocks / n);
  auto block_of = [&](std::size_t i) { return std::size_t(block_of_vector[i]); };
  static_assert(CorrelationSums::blocks <= 256);
  // Dimension 1 from the values in sorted order (a pair close in the first coordinate may be far
  // in the second, so the 2-d grid below would miss it); dimensions >= 2 from a box grid on the
  // first two coordinates. Pairs closer in time than the Theiler window are skipped in both.
  std::vector<std::pair<double, std::uint32_t>> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = {y[i], std::uint32_t(i)};
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> edges(bins);
  for (std::size_t k = 0; k < bins; ++k) edges[k] = CorrelationSums::edge(k);
  const std::optional<nonlinear::BoxGrid> grid =
      max_dimension >= 2 ? std::optional<nonlinear::BoxGrid>(std::in_place, y, delay, 2, n, cut)
                         : std::nullopt;
  const std::vector<std::size_t> row_order =
      grid ? grid->rows_most_work_first() : std::vector<std::size_t>{};
#pragma omp parallel
  {
    std::vector<std::uint64_t> local(out.counts.size(), 0);
    std::vector<double> local_pairs(blocks, 0.0);
    // Dimensions >= 2 count into a compact table first: 32-bit counts, only the bins below the
    // cut, the blocks of one (dimension, bin) side by side. Its busy part (the top octaves below
    // the cut) then stays in L1, where the full 64-bit [block][dimension][bin] rows did not.
    const std::size_t kept_bins = bin_of(cut) + 1;
    std::vector<std::uint32_t> compact(dims * kept_bins * blocks, 0);
    std::uint64_t updates = 0;  // since the last flush: no compact count can exceed it
    auto flush = [&] {
      for (std::size_t d = 1; d < dims; ++d)
        for (std::size_t bin = 0; bin < kept_bins; ++bin)
          for (std::size_t b = 0; b < blocks; ++b) {
            std::uint32_t& c = compact[(d * kept_bins + bin) * blocks + b];
            local[(b * dims + d) * bins + bin] += c;
            c = 0;
          }
      updates = 0;
    };
    // Dimension 1: the vectors closer than each bin edge e_k (capped at the cut) on either side
    // of yi in sorted order form a stretch [left_k, right_k) around p; as p moves up, yi grows
    // and both ends only move up, so one pointer per edge slides along (O(bins) per vector, not
    // O(pairs within the cut)). Chunks of consecutive p: pointers found by bisection per chunk.
    std::size_t edge_count = 0;
    while (edge_count < bins && (edge_count == 0 || edges[edge_count - 1] < cut)) ++edge_count;
    std::vector<double> capped(edge_count);
    for (std::size_t k = 0; k < edge_count; ++k) capped[k] = std::min(edges[k], cut);
    std::vector<std::size_t> left(edge_count), right(edge_count);
    constexpr std::size_t chunk = 512;
#pragma omp for schedule(dynamic, 1) nowait
    for (std::size_t c = 0; c < (n + chunk - 1) / chunk; ++c) {
      const std::size_t p0 = c * chunk, p1 = std::min(n, p0 + chunk);
      for (std::size_t k = 0; k < edge_count; ++k) {
        const double y0 = sorted[p0].first, e = capped[k];
        left[k] = std::size_t(std::partition_point(sorted.begin(), sorted.begin() + std::ptrdiff_t(p0),
                                                   [&](const auto& v) { return !(y0 - v.first < e); }) -
                              sorted.begin());
        right[k] = std::size_t(std::partition_point(sorted.begin() + std::ptrdiff_t(p0 + 1), sorted.end(),
                                                    [&](const auto& v) { return v.first - y0 < e; }) -
                               sorted.begin());
      }
      for (std::size_t p = p0; p < p1; ++p) {
        const std::size_t i = sorted[p].second;
        const double yi = sorted[p].first;
        local_pairs[block_of(i)] += double((i > theiler ? i - theiler : 0) +
                                           (i + theiler + 1 < n ? n - i - theiler - 1 : 0));
        std::uint64_t* h = local.data() + block_of(i) * dims * bins;  // dimension 1
        // Bins below the gap to the nearest value on either side hold nothing: start above.
        // (Pointers of skipped edges lag behind and catch up when next used.)
        double gap = cut;
        if (p + 1 < n) gap = std::min(gap, sorted[p + 1].first - yi);
        if (p > 0) gap = std::min(gap, yi - sorted[p - 1].first);
        std::size_t previous = 0;
        for (std::size_t k = std::min(bin_of(gap), edge_count); k < edge_count; ++k) {
          const double e = capped[k];
          std::size_t r = std::max(right[k], p + 1), l = left[k];
          while (r < n && sorted[r].first - yi < e) ++r;
          while (l < p && !(yi - sorted[l].first < e)) ++l;
          right[k] = r;
          left[k] = l;
          const std::size_t within = (r - p - 1) + (p - l);
          h[k] += within - previous;
          previous = within;
        }
        // Minus the pairs inside the Theiler window (counted above, in their bins).
        for (std::size_t j = i > theiler ? i - theiler : 0; j <= std::min(i + theiler, n - 1); ++j) {
          const double dist = std::abs(y[j] - y[i]);
          if (j != i && dist < cut) --h[bin_of(dist)];
        }
      }
    }
    if (grid) {
      const nonlinear::BoxGrid::Entry* entries = grid->entries();
      // Row by row of the grid (each pair once: a vector's forward runs lie in its own row and
      // the next), with the coordinates and blocks of those two rows copied in grid order.
      nonlinear::CopiedCoordinates coordinates;
      std::vector<std::uint8_t> window_block;
      std::vector<std::size_t> kept;
      PairPass pass;
      pass.grid = &*grid;
      pass.coordinates = &coordinates;
      pass.dims = dims;
      pass.theiler = theiler;
      pass.kept_bins = kept_bins;
      pass.cut = cut;
      pass.compact = compact.data();
      pass.row_base.resize(4 * ((dims + 3) / 4));
      for (std::size_t d = 0; d < pass.row_base.size(); ++d)
        pass.row_base[d] = d * kept_bins * blocks;
      pass.kept = &kept;
#pragma omp for schedule(dynamic, 1)
      for (std::size_t rank = 0; rank < row_order.size(); ++rank) {
        const std::size_t row = row_order[rank];
        const std::size_t row_first = grid->row_begin(row), row_end = grid->row_begin(row + 1);
        const std::size_t window_end = grid->row_begin(std::min(row + 2, grid->rows()));
        coordinates.fill(*grid, y.data(), tau, row_first, window_end, dims, 4 * ((dims + 3) / 4));
        window_block.resize(window_end - row_first);
        for (std::size_t e = row_first; e < window_end; ++e)
          window_block[e - row_first] = block_of_vector[entries[e].index];
        pass.window_begin = row_first;
        pass.window_block = window_block.data();
        for (std::size_t q = row_first; q < row_end; ++q) {
          std::size_t first[2], last[2];
          const std::size_t runs = grid->forward_runs(q, first, last);  // each pair once
          // At most 2 (dims - 1) updates per candidate pair.
          std::uint64_t bound = 0;
          for (std::size_t run = 0; run < runs; ++run)
            bound += 2 * (dims - 1) * (last[run] - first[run]);
          if (updates + bound > std::numeric_limits<std::uint32_t>::max()) flush();
          updates += bound;
          count_forward_pairs(pass, q, first, last, runs);
        }
      }
      flush();
    }
#pragma omp critical
    {
      for (std::size_t k = 0; k < local.size(); ++k) out.counts[k] += local[k];
      for (std::size_t b = 0; b < blocks; ++b) out.pairs[b] += local_pairs[b];
    }
  }
  add_uncounted_pairs(out);
  return out;
}

namespace {

// One dimension's curve ln C(ln r) at the bin edges, from block-weighted counts.
struct Curve {
  std::vector<double> log_r, log_c, count;
};

Curve curve(const CorrelationSums& sums, int d, const std::vector<double>& weights) {
  Curve c;
  const std::size_t bins = CorrelationSums::bins, dims = std::size_t(sums.max_dimension);
  std::vector<double> cumulative(bins, 0.0);
  double pairs = 0;
  for (std::size_t b = 0; b < CorrelationSums::blocks; ++b) {
    if (weights[b] == 0) continue;
    pairs += weights[b] * sums.pairs[b];
    const std::uint64_t* h = sums.counts.data() + (b * dims + std::size_t(d - 1)) * bins;
    double running = 0;
    for (std::size_t k = 0; k < bins; ++k) {
      running += double(h[k]);
      cumulative[k] += weights[b] * running;
    }
  }
  for (std::size_t k = 0; k < bins; ++k) {
    c.log_r.push_back(std::log(sums.range * CorrelationSums::edge(k)));
    c.count.push_back(cumulative[k]);
    const bool counted = CorrelationSums::edge(k) <= sums.cut;
    c.log_c.push_back(counted && cumulative[k] > 0 ? std::log(cumulative[k] / pairs) : nan);
  }
  return c;
}

struct DimensionFit {
  int dimension = 0;
  bool found = false;
  std::size_t begin = 0, end = 0;
  double d2 = nan, stderr_ = nan;
  Curve curve;
  std::vector<double> slopes;
};

constexpr std::size_t slope_half_window = 4;  // local slopes over a factor 2 in r
// Scaling holds at small r only: where more than 10 % of all pairs are within r, the finite
// extent of the attractor bends ln C down.
constexpr double max_correlation_sum = 0.1;
constexpr double min_scaling_slope = 0.05;

std::vector<bool> usable_points(const Curve& c, double min_pairs, double min_log_r) {
  std::vector<bool> usable(c.log_r.size());
  for (std::size_t k = 0; k < c.log_r.size(); ++k)
    usable[k] = c.count[k] >= min_pairs && std::isfinite(c.log_c[k]) &&
                c.log_c[k] <= std::log(max_correlation_sum) && c.log_r[k] >= min_log_r;
  return usable;
}

DimensionFit fit_dimension(const CorrelationSums& sums, int d, double min_pairs,
                           double min_log_r, double tolerance, double min_span) {
  DimensionFit f;
  f.dimension = d;
  f.curve = curve(sums, d, std::vector<double>(CorrelationSums::blocks, 1.0));
  const auto usable = usable_points(f.curve, min_pairs, min_log_r);
  f.slopes = nonlinear::local_slopes(f.curve.log_r, f.curve.log_c, usable, slope_half_window);
  // A flat ln C (slope < 0.05) is a gap between the points of a finite or lattice-like set (an
  // exactly periodic or quantised signal), not scaling.
  for (double& s : f.slopes)
    if (s < min_scaling_slope) s = nan;
  std::vector<double> finite;
  for (double s : f.slopes)
    if (std::isfinite(s)) finite.push_back(s);
  if (finite.empty()) return f;
  std::nth_element(finite.begin(), finite.begin() + std::ptrdiff_t(finite.size() / 2),
                   finite.end());
  const double scale = std::max(1.0, finite[finite.size() / 2]);
  const auto region =
      nonlinear::find_plateau(f.curve.log_r, f.slopes, tolerance * scale, min_span);
  if (!region.found) return f;
  // The fit uses the curve points whose slope windows formed the plateau.
  f.found = true;
  f.begin = region.begin - slope_half_window;
  f.end = region.end + slope_half_window;
  const auto line = nonlinear::fit_line(f.curve.log_r, f.curve.log_c, f.begin, f.end);
  f.d2 = line.slope;
  f.stderr_ = line.slope_stderr;
  return f;
}

}  // namespace

PluginInfo CorrelationDimension::info() {
  PluginInfo info;
  info.name = "correlation_dimension";
  info.description =
      "correlation dimension D2 (Grassberger-Procaccia, Theiler window) from an automatically "
      "detected scaling region, versus embedding dimension until saturation";
  info.models_md_ids = "N2";
  using nonlinear::numeric_spec;
  info.params = {
      nonlinear::delay_spec(),
      nonlinear::dimension_spec(),
      nonlinear::theiler_spec(),
      numeric_spec("max_dimension", ValueKind::integer, "1",
                   "largest embedding dimension of the D2 sweep (absent: max(8, 2 x embedding "
                   "dimension + 2))",
                   Json(), 1, 30),
      numeric_spec("max_reference_points", ValueKind::integer, "1",
                   "reference vectors compared with all others (sampled references: cost "
                   "references x N x dimensions, memory O(N))",
                   2000, 10),
      numeric_spec("all_pairs_within", ValueKind::real, "1",
                   "when given: count every pair closer than this fraction of the signal range "
                   "(box-assisted, like TISEAN d2 -N 0 -R) instead of sampled references: exact "
                   "C(r) below it, cost growing with the number of such pairs",
                   Json(), 0, CorrelationSums::sampled_cut, true),
      numeric_spec("min_pairs", ValueKind::integer, "1",
                   "a correlation sum counts only where at least this many pairs lie within r "
                   "(statistical floor of the scaling region)",
                   2000, 1),
      numeric_spec("slope_tolerance", ValueKind::real, "1",
                   "the scaling region is the longest range of r whose local slopes stay within "
                   "this fraction of their median",
                   0.05, 0, 1, true),
      numeric_spec("saturation_tolerance", ValueKind::real, "1",
                   "D2 has saturated when three successive embedding dimensions agree within "
                   "this fraction",
                   0.05, 0, 1, true),
      nonlinear::bootstrap_spec(),
      nonlinear::seed_spec(),
  };
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_dimension", 4}, {"max_reference_points", 200}};
  return info;
}

Json CorrelationDimension::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const auto given_max = nonlinear::given_integer(params_, "max_dimension");
  const int max_dimension = given_max ? int(*given_max) : std::max(8, 2 * embedding.dimension + 2);
  const std::string name = series.name.empty() ? std::string("series") : series.name;
  nonlinear::check_series(x, max_dimension, embedding.delay, name);

  const auto all_pairs_within = nonlinear::given_real(params_, "all_pairs_within");
  const CorrelationSums sums =
      all_pairs_within
          ? correlation_sums_within(x, max_dimension, embedding.delay, embedding.theiler,
                                    *all_pairs_within)
          : correlation_sums(x, max_dimension, embedding.delay, embedding.theiler,
                             std::size_t(params_.integer("max_reference_points")));
  const double min_pairs = double(params_.integer("min_pairs"));
  const double tolerance = params_.real("slope_tolerance");
  const double min_span = std::log(4.0);  // at least a factor 4 in r

  // Noise level: at scales below it the highest-dimensional local slopes approach the embedding
  // dimension (noise fills every direction). It is the largest r where the slope exceeds 3/4 of
  // the top dimension; the scaling windows of every dimension start above twice that.
  double noise_log_r = -std::numeric_limits<double>::infinity();
  std::string noise_note = "no noise scale detected";
  if (max_dimension >= 4) {
    const auto top = fit_dimension(sums, max_dimension, min_pairs, noise_log_r, tolerance, min_span);
    double top_usable = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < top.slopes.size(); ++k)
      if (std::isfinite(top.slopes[k])) {
        top_usable = std::max(top_usable, top.curve.log_r[k]);
        if (top.slopes[k] > 0.75 * max_dimension)
          noise_log_r = std::max(noise_log_r, top.curve.log_r[k]);
      }
    if (std::isfinite(noise_log_r)) {
      if (noise_log_r + std::log(2.0) + min_span < top_usable) {
        noise_note = fmt::format("noise level {:.3g}: scaling windows start above {:.3g}",
                                 std::exp(noise_log_r), 2 * std::exp(noise_log_r));
      } else {
        noise_note = fmt::format("noise-like at every resolved scale (local slopes near the "
                                 "embedding dimension up to r = {:.3g})",
                                 std::exp(noise_log_r));
      }
    }
  }
  const double min_log_r = std::isfinite(noise_log_r) &&
                                   noise_note.rfind("noise level", 0) == 0
                               ? noise_log_r + std::log(2.0)
                               : -std::numeric_limits<double>::infinity();

  std::vector<DimensionFit> fits;
  for (int d = 1; d <= max_dimension; ++d)
    fits.push_back(fit_dimension(sums, d, min_pairs, min_log_r, tolerance, min_span));

  // Saturation: the first d >= 2 where D2(d), D2(d+1), D2(d+2) agree within the tolerance.
  const double sat_tol = params_.real("saturation_tolerance");
  int saturated = 0;
  for (int d = 2; d + 2 <= max_dimension; ++d) {
    const auto& a = fits[std::size_t(d - 1)];
    const auto& b = fits[std::size_t(d)];
    const auto& c = fits[std::size_t(d + 1)];
    if (!(a.found && b.found && c.found)) continue;
    const double hi = std::max({a.d2, b.d2, c.d2}), lo = std::min({a.d2, b.d2, c.d2});
    if (hi - lo <= sat_tol * hi) {
      saturated = d;
      break;
    }
  }

  Json out;
  Json by_dimension = Json::array();
  for (const auto& f : fits) {
    Json entry{{"dimension", f.dimension}, {"d2", f.found ? Json(f.d2) : Json()},
               {"d2_stderr", f.found ? Json(f.stderr_) : Json()}};
    entry["r_low"] = f.found ? Json(std::exp(f.curve.log_r[f.begin])) : Json();
    entry["r_high"] = f.found ? Json(std::exp(f.curve.log_r[f.end - 1])) : Json();
    std::vector<double> r, c, slope;
    for (std::size_t k = 0; k < f.curve.log_r.size(); ++k)
      if (std::isfinite(f.curve.log_c[k])) {
        r.push_back(std::exp(f.curve.log_r[k]));
        c.push_back(std::exp(f.curve.log_c[k]));
        slope.push_back(f.slopes[k]);
      }
    entry["r"] = r;
    entry["correlation_sum"] = c;
    Json slopes_json = Json::array();
    for (double s : slope) slopes_json.push_back(std::isfinite(s) ? Json(s) : Json());
    entry["local_slope"] = slopes_json;
    by_dimension.push_back(entry);
  }

  std::vector<int> used;
  if (saturated > 0) used = {saturated, saturated + 1, saturated + 2};
  double value = nan;
  nonlinear::Interval ci{nan, nan};
  std::string quality = "failed", reason;
  if (!used.empty()) {
    // One scaling region for the saturated dimensions: the plateau of their mean local slope
    // (per-dimension plateaus wander with the lacunarity wiggles of the slopes).
    const std::size_t bins = CorrelationSums::bins;
    std::vector<double> mean_slope(bins, nan);
    for (std::size_t k = 0; k < bins; ++k) {
      double sum = 0;
      bool all = true;
      for (int d : used) {
        const double v = fits[std::size_t(d - 1)].slopes[k];
        all = all && std::isfinite(v);
        sum += v;
      }
      if (all) mean_slope[k] = sum / double(used.size());
    }
    const auto& log_r = fits[std::size_t(saturated - 1)].curve.log_r;
    const double scale = std::max(1.0, fits[std::size_t(saturated - 1)].d2);
    const auto common = nonlinear::find_plateau(log_r, mean_slope, tolerance * scale, min_span);
    std::size_t begin = 0, end = 0;
    bool joint = common.found;
    if (joint) {
      begin = common.begin - slope_half_window;
      end = common.end + slope_half_window;
    }
    auto estimate_with = [&](const std::vector<double>& w) {
      double mean = 0;
      for (int d : used) {
        const auto& f = fits[std::size_t(d - 1)];
        const std::size_t b = joint ? begin : f.begin, e = joint ? end : f.end;
        const Curve c = curve(sums, d, w);
        for (std::size_t k = b; k < e; ++k)
          if (!std::isfinite(c.log_c[k])) return nan;
        mean += nonlinear::fit_line(c.log_r, c.log_c, b, e).slope / double(used.size());
      }
      return mean;
    };
    value = estimate_with(std::vector<double>(CorrelationSums::blocks, 1.0));
    // Bootstrap over blocks of reference points with the scaling region held fixed.
    ci = nonlinear::block_bootstrap(CorrelationSums::blocks,
                                    std::size_t(params_.integer("bootstrap_replicates")),
                                    std::uint64_t(params_.integer("seed")), estimate_with);
    const auto& f = fits[std::size_t(saturated - 1)];
    if (!joint) {
      begin = f.begin;
      end = f.end;
    }
    const double decades = (log_r[end - 1] - log_r[begin]) / std::log(10.0);
    quality = joint && decades >= 1.0 ? "good" : "uncertain";
    reason = fmt::format(
        "D2 saturates from embedding dimension {} (mean of dimensions {}-{}); {} scaling region "
        "{:.3g}..{:.3g} ({:.2f} decades); {}",
        saturated, saturated, saturated + 2,
        joint ? "common" : "no common plateau: per-dimension", std::exp(log_r[begin]),
        std::exp(log_r[end - 1]), decades, noise_note);
    out["scaling_region"] = {std::exp(log_r[begin]), std::exp(log_r[end - 1])};
  } else {
    reason = fmt::format("no saturation of D2 up to embedding dimension {} (noise-like, "
                         "high-dimensional or too short a series); {}",
                         max_dimension, noise_note);
  }
  out["correlation_dimension"] = nonlinear::estimate(value, ci.low, ci.high, quality, reason);
  out["saturation_dimension"] = saturated;
  out["noise_level"] = std::isfinite(noise_log_r) ? Json(std::exp(noise_log_r)) : Json();
  out["delay_samples"] = embedding.delay;
  out["theiler_window_samples"] = embedding.theiler;
  out["embedding_source"] = embedding.source;
  out["reference_points"] = params_.integer("max_reference_points");
  if (all_pairs_within) out["all_pairs_within"] = *all_pairs_within;
  out["by_dimension"] = by_dimension;
  return out;
}

void CorrelationDimension::plot(const Json& result, const SampledSeries& series,
                                const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  plot::Curves sums, slopes, saturation;
  sums.title = fmt::format("{}: correlation sums (points: scaling regions)", title);
  sums.x_label = "r [signal units]";
  sums.y_label = "C(r)";
  sums.log_x = sums.log_y = true;
  slopes.title = fmt::format("{}: local slopes d ln C / d ln r (points: scaling regions)", title);
  slopes.x_label = "r [signal units]";
  slopes.y_label = "local slope";
  slopes.log_x = true;
  saturation.title = fmt::format("{}: D2 versus embedding dimension", title);
  saturation.x_label = "embedding dimension d";
  saturation.y_label = "D2";
  plot::Series d2_curve{"D2(d)", {}, {}, "linespoints"};
  for (const Json& entry : result["by_dimension"]) {
    const int d = entry["dimension"].get<int>();
    const auto r = entry["r"].get<std::vector<double>>();
    const auto c = entry["correlation_sum"].get<std::vector<double>>();
    plot::Series s{fmt::format("d = {}", d), r, c, "lines"};
    plot::Series ls{fmt::format("d = {}", d), {}, {}, "lines"};
    const Json& slope = entry["local_slope"];
    for (std::size_t k = 0; k < r.size(); ++k)
      if (slope[k].is_number()) {
        ls.x.push_back(r[k]);
        ls.y.push_back(slope[k].get<double>());
      }
    sums.series.push_back(std::move(s));
    slopes.series.push_back(std::move(ls));
    if (entry["d2"].is_number()) {
      const double lo = entry["r_low"].get<double>(), hi = entry["r_high"].get<double>();
      plot::Series region{"", {}, {}, "points"};
      plot::Series region_slope{"", {}, {}, "points"};
      for (std::size_t k = 0; k < r.size(); ++k)
        if (r[k] >= lo && r[k] <= hi) {
          region.x.push_back(r[k]);
          region.y.push_back(c[k]);
          if (slope[k].is_number()) {
            region_slope.x.push_back(r[k]);
            region_slope.y.push_back(slope[k].get<double>());
          }
        }
      if (d == 1) region.label = region_slope.label = "scaling region";
      sums.series.push_back(std::move(region));
      slopes.series.push_back(std::move(region_slope));
      d2_curve.x.push_back(d);
      d2_curve.y.push_back(entry["d2"].get<double>());
    }
  }
  saturation.series.push_back(d2_curve);
  const Json& estimate = result["correlation_dimension"];
  if (estimate["value"].is_number()) {
    saturation.reference_y = estimate["value"].get<double>();
    saturation.reference_label = fmt::format("D2 = {:.3f}", estimate["value"].get<double>());
  }
  plot::render(sums, out_dir, "correlation_dimension_sums");
  plot::render(slopes, out_dir, "correlation_dimension_slopes");
  plot::render(saturation, out_dir, "correlation_dimension_saturation");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::CorrelationDimension);
