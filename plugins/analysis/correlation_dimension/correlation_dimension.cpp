#include "analysis/correlation_dimension/correlation_dimension.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>

#include "analysis/embedding/embedding.hpp"
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

using Vector4 = double __attribute__((vector_size(32)));  // AVX2; SSE2: two halves
using Bits4 = std::uint64_t __attribute__((vector_size(32)));
constexpr std::size_t max_pair_dimensions = 32;  // of correlation_sums_within (the parameter: 30)

// |v| by clearing the sign bits (one AND, where v < 0 ? -v : v takes three instructions). By
// reference: a 32-byte vector by value would change the ABI between the target clones.
inline void make_absolute(Vector4& v) {
  Bits4 bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits &= ~(Bits4{} + (std::uint64_t(1) << 63));
  std::memcpy(&v, &bits, sizeof v);
}

// The vectors of correlation_sums_within for the pair pass (dimensions >= 2), grouped by
// bootstrap block and, within a block, on strips of the first coordinate at least cut / 2 wide,
// sorted by the second coordinate within a strip. The partners of a vector closer than the cut
// in the first two coordinates then lie in the 5 strips around its own, each time in one
// contiguous band of the second coordinate (found by pointers sliding with the sorted vectors):
// the candidates cover 2.5 x 2 cuts around it, of which the 2 x 2 square holds the pairs (80 %,
// where 3 x 3 boxes of width cut kept 44 %). Grouped by block so that all pairs of two blocks
// are counted together into one small table (below). Coordinates are copied in this order
// (the first two separately; the others padded to groups of four) so the candidates stream
// through contiguous memory.
struct BlockStrips {
  static constexpr double strips_per_cut = 2;
  static constexpr std::size_t max_strips = 4096;
  std::size_t strips = 1, reach = 1, others = 0;  // others: stride of coordinates 3, 4, ...
  std::vector<std::size_t> start;                 // first entry of (block, strip), then n
  std::vector<double> a, b;                       // first two coordinates of each entry
  std::vector<std::uint32_t> index;               // time index of each entry's vector
  std::vector<double> rest;                       // coordinates 3..dims, `others` per entry
  std::vector<std::size_t> block_first;           // first time index of each block; then n

  BlockStrips(const std::vector<double>& y, std::size_t n, std::size_t tau, std::size_t dims,
              double cut, const std::vector<std::uint8_t>& block_of_vector) {
    const std::size_t blocks = CorrelationSums::blocks;
    // Strip count chosen so cut x strips stays off an integer (rounding of a x strips cannot add
    // a strip to the reach below).
    strips = std::size_t(std::clamp(std::floor(strips_per_cut / cut - 0.5), 1.0,
                                    double(max_strips)));
    // |a_i - a_j| < cut => the strips differ by at most ceil(cut x strips).
    reach = std::size_t(std::ceil(cut * double(strips) * (1 + 1e-9) + 1e-9));
    others = 4 * ((dims - 2 + 3) / 4);
    auto strip_of = [&](double v) { return std::min(strips - 1, std::size_t(v * double(strips))); };
    start.assign(blocks * strips + 1, 0);
    std::vector<std::size_t> cell_of(n);
    for (std::size_t i = 0; i < n; ++i) {
      cell_of[i] = block_of_vector[i] * strips + strip_of(y[i]);
      ++start[cell_of[i] + 1];
    }
    for (std::size_t c = 0; c < blocks * strips; ++c) start[c + 1] += start[c];
    block_first.assign(blocks + 1, n);
    for (std::size_t i = n; i-- > 0;) block_first[block_of_vector[i]] = i;
    for (std::size_t k = blocks; k-- > 0;)  // empty blocks: the next one's first
      block_first[k] = std::min(block_first[k], block_first[k + 1]);
    std::vector<std::uint32_t> order(n);
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) order[fill[cell_of[i]]++] = std::uint32_t(i);
    for (std::size_t c = 0; c < blocks * strips; ++c)
      std::sort(order.begin() + std::ptrdiff_t(start[c]),
                order.begin() + std::ptrdiff_t(start[c + 1]),
                [&](std::uint32_t u, std::uint32_t v) { return y[u + tau] < y[v + tau]; });
    a.resize(n);
    b.resize(n);
    index = order;
    rest.assign(n * others, 0.0);
    for (std::size_t e = 0; e < n; ++e) {
      const double* from = y.data() + order[e];
      a[e] = from[0];
      b[e] = from[tau];
      for (std::size_t l = 2; l < dims; ++l) rest[e * others + l - 2] = from[l * tau];
    }
  }
  std::size_t cell(std::size_t block, std::size_t strip) const { return block * strips + strip; }
};

// What the pair pass shares between its vectors. Counts go to a per-thread table of 32-bit counts
// [(dimension - 2) x row_length + bin], one row per dimension 2..dims; it holds the pairs of one
// pair of bootstrap blocks and is added to both blocks' histograms when they are done (flush).
// So one increment per pair and dimension serves both of its vectors (the old per-block table
// took two, one per block, into rows spread over 20 blocks), and the table (~9 KB) stays in L1.
struct PairPass {
  const BlockStrips* strips = nullptr;
  std::size_t dims = 0, theiler = 0, row_length = 0;
  double cut = 0;
  std::uint32_t* table = nullptr;
  // Per lane l of the coordinates 3, 4, ... (padded to groups of four): the start of the row of
  // dimension 3 + l minus the key of bin 0 (plain integers loaded with memcpy: heap storage of
  // 32-byte vectors is not reliably 32-byte aligned).
  std::vector<std::uint64_t> row_base;
  std::vector<std::uint32_t>* kept = nullptr;  // scratch
  std::vector<double>* kept_distance = nullptr;
};

// Every pair (vector of entry q, a vector in the runs [first, last)) closer than the cut in the
// maximum norm, counted in every dimension 2..dims. First the candidates closer than the cut in
// the first two coordinates, compacted without branches (about a fifth are not); then, per kept
// pair, the differences of the other coordinates four at a time, their running maximum across
// the lanes and the bins from the exponent bits, and one increment per dimension of the group
// (a fixed count: no branch on how many of the four are within the cut; the ones beyond land in
// bins above the cut that are never read). After a group whose last dimension is beyond the cut
// the pair stops (most pairs do after the first group).
[[gnu::target_clones("avx2", "default")]] void count_pairs(const PairPass& pass, std::size_t q,
                                                           const std::size_t* first,
                                                           const std::size_t* last,
                                                           std::size_t runs,
                                                           bool near_in_time) {
  const BlockStrips& s = *pass.strips;
  const double a = s.a[q], b = s.b[q];
  const std::size_t i = s.index[q];
  std::size_t candidates = 0;
  for (std::size_t run = 0; run < runs; ++run) candidates += last[run] - first[run];
  if (pass.kept->size() < candidates) {
    pass.kept->resize(candidates);
    pass.kept_distance->resize(candidates);
  }
  std::uint32_t* __restrict kept = pass.kept->data();
  double* __restrict kept_distance = pass.kept_distance->data();
  const double* sa = s.a.data();
  const double* sb = s.b.data();
  const std::uint32_t* sindex = s.index.data();
  const double cut = pass.cut;
  const std::size_t theiler = pass.theiler;
  std::size_t count = 0;
  auto filter = [&](auto check_theiler) __attribute__((always_inline)) {
    for (std::size_t run = 0; run < runs; ++run) {
      std::size_t e = first[run];
      if constexpr (!decltype(check_theiler)::value) {
        // Four candidates at a time (contiguous coordinates), then their scalar compaction.
        const Vector4 a4 = {a, a, a, a}, b4 = {b, b, b, b}, cut4 = {cut, cut, cut, cut};
        for (; e + 4 <= last[run]; e += 4) {
          Vector4 va, vb;
          std::memcpy(&va, sa + e, sizeof va);
          std::memcpy(&vb, sb + e, sizeof vb);
          Vector4 da = va - a4, db = vb - b4;
          make_absolute(da);
          make_absolute(db);
          const Vector4 d = da > db ? da : db;
          const Bits4 keep = d < cut4;  // all ones or zero per lane
          for (std::size_t l = 0; l < 4; ++l) {
            kept[count] = std::uint32_t(e + l);
            kept_distance[count] = d[l];
            count += std::size_t(keep[l] & 1);
          }
        }
      }
      for (; e < last[run]; ++e) {
        const double d01 = std::max(std::abs(sa[e] - a), std::abs(sb[e] - b));
        kept[count] = std::uint32_t(e);
        kept_distance[count] = d01;
        bool keep = d01 < cut;
        if constexpr (decltype(check_theiler)::value) {
          const std::size_t j = sindex[e];
          keep = keep & ((j > i ? j - i : i - j) > theiler);
        }
        count += keep ? 1 : 0;
      }
    }
  };
  if (near_in_time)
    filter(std::true_type{});
  else
    filter(std::false_type{});
  const std::size_t groups = s.others / 4, rows = pass.dims - 1;
  const double* yi = s.rest.data() + q * s.others;
  // Below the smallest bin edge 2^-octaves every distance maps to key_base - 1, i.e. bin 0.
  const double floor = std::nextafter(std::ldexp(1.0, -CorrelationSums::octaves), 0.0);
  const Vector4 floor4 = {floor, floor, floor, floor};
  std::uint32_t* __restrict table = pass.table;
  // Known group counts (dimensions 3..6, 7..10) compiled apart: the loop over the groups unrolls
  // and the query's coordinates stay in registers.
  auto count_kept = [&](auto fixed_groups) __attribute__((always_inline)) {
    const std::size_t group_count = fixed_groups() > 0 ? fixed_groups() : groups;
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t e = kept[k];
      const double d01 = kept_distance[k];
      ++table[bin_of(d01)];  // dimension 2
      const double* yj = s.rest.data() + e * s.others;
      Vector4 carry = {d01, d01, d01, d01};
      for (std::size_t g = 0; g < group_count; ++g) {
        Vector4 own, other;
        std::memcpy(&own, yi + 4 * g, sizeof own);
        std::memcpy(&other, yj + 4 * g, sizeof other);
        Vector4 v = own - other;
        make_absolute(v);
        // Running maximum over the dimensions: the maximum-norm distance in each.
        const Vector4 zero = {};
        Vector4 shifted = __builtin_shuffle(v, zero, Bits4{4, 0, 1, 2});
        v = v > shifted ? v : shifted;
        shifted = __builtin_shuffle(v, zero, Bits4{4, 4, 0, 1});
        v = v > shifted ? v : shifted;
        v = v > carry ? v : carry;
        carry = Vector4{v[3], v[3], v[3], v[3]};
        const Vector4 clamped = v > floor4 ? v : floor4;
        Bits4 key, base;
        std::memcpy(&key, &clamped, sizeof key);
        std::memcpy(&base, pass.row_base.data() + 4 * g, sizeof base);
        const Bits4 row = base + (key >> 49);
        // Straight from the register (through memory the loads waited on the vector store).
        if (5 + 4 * g <= rows) {
          ++table[row[0]];
          ++table[row[1]];
          ++table[row[2]];
          ++table[row[3]];
        } else {
          for (std::size_t l = 0; 1 + 4 * g + l < rows; ++l) ++table[row[l]];
        }
        // Beyond the cut here: beyond it in every higher dimension (whose bins above the cut are
        // never read). Taken by most pairs, so the branch costs less than the work it skips.
        if (!(v[3] < cut)) break;
      }
    }
  };
  if (groups == 1)
    count_kept(std::integral_constant<std::size_t, 1>{});
  else if (groups == 2)
    count_kept(std::integral_constant<std::size_t, 2>{});
  else
    count_kept(std::integral_constant<std::size_t, 0>{});
}

// All pairs of vectors of two blocks (each unordered pair once; the same block twice: the pairs
// within it) closer than the cut, counted into pass.table.
template <class BeforeQuery>
void count_block_pairs(const PairPass& pass, std::size_t block_i, std::size_t block_j,
                       BeforeQuery&& before_query) {
  const BlockStrips& s = *pass.strips;
  const bool same = block_i == block_j;
  // Blocks further apart than the Theiler window need no check per pair.
  // (The closest pair: the first vector of block_j and the last of block_i.)
  const bool near_in_time =
      same || s.block_first[block_j] + 1 <= s.block_first[block_i + 1] + pass.theiler;
  // The band of the second coordinate around a query: a superset of |b - b_q| < cut.
  const double band = pass.cut + 1e-9;
  std::vector<std::size_t> low(2 * s.reach + 1), high(low.size()), end(low.size());
  std::vector<std::size_t> first(low.size()), last(low.size());
  for (std::size_t u = 0; u < s.strips; ++u) {
    const std::size_t q0 = s.start[s.cell(block_i, u)], q1 = s.start[s.cell(block_i, u) + 1];
    if (q0 == q1) continue;
    // Within one block each pair once: partners in this strip after the query, or in the next
    // strips; between two blocks every partner strip.
    const std::size_t s0 = same ? u : (u > s.reach ? u - s.reach : 0);
    const std::size_t s1 = std::min(s.strips - 1, u + s.reach);
    const std::size_t runs = s1 - s0 + 1;
    for (std::size_t r = 0; r < runs; ++r) {
      low[r] = high[r] = s.start[s.cell(block_j, s0 + r)];
      end[r] = s.start[s.cell(block_j, s0 + r) + 1];
    }
    for (std::size_t q = q0; q < q1; ++q) {
      const double lower = s.b[q] - band, upper = s.b[q] + band;
      std::size_t candidates = 0;
      for (std::size_t r = 0; r < runs; ++r) {
        while (low[r] < end[r] && s.b[low[r]] < lower) ++low[r];
        while (high[r] < end[r] && s.b[high[r]] < upper) ++high[r];
        first[r] = same && s0 + r == u ? q + 1 : low[r];
        last[r] = std::max(first[r], high[r]);
        candidates += last[r] - first[r];
      }
      before_query(candidates);
      count_pairs(pass, q, first.data(), last.data(), runs, near_in_time);
    }
  }
}
}  // namespace

double CorrelationSums::edge(std::size_t bin) {
  return std::ldexp(1.0 + double(bin % 8) / 8.0, int(bin / 8) - octaves);
}

std::vector<double> CorrelationSums::log_correlation(int d) const {
  std::vector<double> out(bins, nan);
  const std::size_t dims = std::size_t(max_dimension);
  double total = 0;
  for (double p : pairs) total += p;
  std::vector<double> cumulative(bins, 0.0);
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::uint64_t* h = counts.data() + (b * dims + std::size_t(d - 1)) * bins;
    double running = 0;
    for (std::size_t k = 0; k < bins; ++k) cumulative[k] += (running += double(h[k]));
  }
  for (std::size_t k = 0; k < bins; ++k)
    if (edge(k) <= cut && cumulative[k] > 0) out[k] = std::log(cumulative[k] / total);
  return out;
}

std::vector<double> CorrelationSums::log_radii() const {
  std::vector<double> out(bins);
  for (std::size_t k = 0; k < bins; ++k) out[k] = std::log(range * edge(k));
  return out;
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
  // The sorted values alone (dense for the pointers below), with +infinity after the last: the
  // right pointers stop there without a bounds check.
  std::vector<double> sorted_value(n + 1, std::numeric_limits<double>::infinity());
  for (std::size_t p = 0; p < n; ++p) sorted_value[p] = sorted[p].first;
  std::vector<double> edges(bins);
  for (std::size_t k = 0; k < bins; ++k) edges[k] = CorrelationSums::edge(k);
  const std::optional<BlockStrips> strips =
      max_dimension >= 2
          ? std::optional<BlockStrips>(std::in_place, y, n, tau, dims, cut, block_of_vector)
          : std::nullopt;
  // Tasks: the pairs of blocks (i <= j), handed out dynamically (they all cost about the same).
  std::vector<std::pair<std::size_t, std::size_t>> block_pairs;
  for (std::size_t bi = 0; bi < blocks; ++bi)
    for (std::size_t bj = bi; bj < blocks; ++bj) block_pairs.emplace_back(bi, bj);
#pragma omp parallel
  {
    std::vector<std::uint64_t> local(out.counts.size(), 0);
    std::vector<double> local_pairs(blocks, 0.0);
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
          // The pointers mostly move by 0, 1 or 2: two steps without branches (the loops that
          // follow rarely run; a left pointer stops at p at the latest, where the gap is 0).
          const double* v = sorted_value.data();
          r += v[r] - yi < e ? 1 : 0;
          l += yi - v[l] < e ? 0 : 1;
          r += v[r] - yi < e ? 1 : 0;
          l += yi - v[l] < e ? 0 : 1;
          while (v[r] - yi < e) ++r;
          while (!(yi - v[l] < e)) ++l;
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
    if (strips) {
      // Dimensions >= 2: the pairs of two blocks into one table (PairPass), then added to both.
      // Rows cover every bin a distance can reach (normalised distances are at most 1 + 2^-52,
      // bin bins - 1; up to 2 for safety): the pairs beyond the cut land in bins above kept_bins
      // that are never read, spread out, instead of in one overflow count per row that every
      // pair would update in turn.
      const std::size_t kept_bins = bin_of(cut) + 1;
      const std::size_t row_length = bins + CorrelationSums::bins_per_octave;
      std::vector<std::uint32_t> table((dims - 1) * row_length, 0);
      std::vector<std::uint32_t> kept;
      std::vector<double> kept_distance;
      PairPass pass;
      pass.strips = &*strips;
      pass.dims = dims;
      pass.theiler = theiler;
      pass.row_length = row_length;
      pass.cut = cut;
      pass.table = table.data();
      pass.kept = &kept;
      pass.kept_distance = &kept_distance;
      for (std::size_t l = 0; l < strips->others; ++l) {
        const std::size_t row = std::min(l + 1, dims - 2);  // padding lanes: any valid row
        pass.row_base.push_back(row * row_length - (key_base - 1));  // modulo 2^64
      }
#pragma omp for schedule(dynamic, 1)
      for (std::size_t task = 0; task < block_pairs.size(); ++task) {
        const auto [bi, bj] = block_pairs[task];
        auto flush = [&] {
          for (std::size_t r = 0; r + 1 < dims; ++r)
            for (std::size_t bin = 0; bin < row_length; ++bin) {
              std::uint32_t& c = table[r * row_length + bin];
              if (bin < kept_bins) {
                local[(bi * dims + r + 1) * bins + bin] += c;
                local[(bj * dims + r + 1) * bins + bin] += c;
              }
              c = 0;
            }
        };
        // Each pair adds at most one to a count: flush before a count could pass 2^32 - 1.
        std::uint64_t since_flush = 0;
        count_block_pairs(pass, bi, bj, [&](std::size_t candidates) {
          if (since_flush + candidates > std::numeric_limits<std::uint32_t>::max()) {
            flush();
            since_flush = 0;
          }
          since_flush += candidates;
        });
        flush();
      }
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

constexpr std::size_t slope_half_window = 4;  // local slopes over a factor 2 in r
// Points where more than half of all pairs are within r are not used: there the finite extent of
// the attractor bends every curve (the upper end of the scaling region is detected below it).
constexpr double max_correlation_sum = 0.5;
constexpr double min_scaling_slope = 0.05;
// Embedding dimensions whose local slopes must agree for a scaling region: the saturation
// dimension and the next two.
constexpr int consistent_dimensions = 3;
// A scale is noise-dominated where the local slope in the highest of them exceeds that in the
// saturation dimension by this much (noise fills every added dimension).
constexpr double noise_slope_excess = 0.5;
// "good" needs a scaling region of a decade and an interval within +-5 % of the value.
constexpr double good_decades = 1.0;
constexpr double good_relative_half_width = 0.05;

// Local slopes d ln C / d ln r of dimension d at the bin edges: NaN where a point of the slope
// window has fewer than min_pairs pairs, C above max_correlation_sum, or where ln C is flat (a
// gap between the points of a finite or lattice-like set, not scaling).
struct DimensionSlopes {
  int dimension = 0;
  Curve curve;
  std::vector<double> slopes;
};
DimensionSlopes dimension_slopes(const CorrelationSums& sums, int d, double min_pairs) {
  DimensionSlopes f;
  f.dimension = d;
  f.curve = curve(sums, d, std::vector<double>(CorrelationSums::blocks, 1.0));
  std::vector<bool> usable(f.curve.log_r.size());
  for (std::size_t k = 0; k < usable.size(); ++k)
    usable[k] = f.curve.count[k] >= min_pairs && std::isfinite(f.curve.log_c[k]) &&
                f.curve.log_c[k] <= std::log(max_correlation_sum);
  f.slopes = nonlinear::local_slopes(f.curve.log_r, f.curve.log_c, usable, slope_half_window);
  for (double& v : f.slopes)
    if (v < min_scaling_slope) v = nan;
  return f;
}

// Binned maximum-likelihood dimension between the bin edges `begin` and `end` (Takens 1985,
// Theiler 1988, with Judd's (1992) treatment of binned distances and a lower cut-off): pair
// distances in [r_begin, r_end) distributed as r^D, bin probabilities
// (r_{k+1}^D - r_k^D) / (r_end^D - r_begin^D); D maximises sum n_k ln p_k (golden section).
double ml_dimension(const Curve& c, std::size_t begin, std::size_t end, double max_d) {
  if (end <= begin + 1) return nan;
  std::vector<double> n;
  for (std::size_t k = begin; k + 1 <= end - 1; ++k) n.push_back(c.count[k + 1] - c.count[k]);
  const double r0 = c.log_r[begin];
  auto likelihood = [&](double d) {
    // Work with u_k = exp(d (ln r_k - ln r_begin)) to stay in range.
    const double top = std::expm1(d * (c.log_r[end - 1] - r0));
    double l = 0;
    for (std::size_t j = 0; j < n.size(); ++j) {
      if (n[j] <= 0) continue;
      const double a = std::exp(d * (c.log_r[begin + j] - r0));
      const double b = std::exp(d * (c.log_r[begin + j + 1] - r0));
      l += n[j] * std::log((b - a) / top);
    }
    return l;
  };
  double lo = 0.01, hi = max_d;
  const double golden = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - golden * (hi - lo), x2 = lo + golden * (hi - lo);
  double f1 = likelihood(x1), f2 = likelihood(x2);
  for (int it = 0; it < 80 && hi - lo > 1e-6; ++it) {
    if (f1 < f2) {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + golden * (hi - lo);
      f2 = likelihood(x2);
    } else {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - golden * (hi - lo);
      f1 = likelihood(x1);
    }
  }
  return 0.5 * (lo + hi);
}

// A scaling region: local slopes of dimensions saturation .. saturation + 2 agree with each other
// (within the saturation tolerance) and form a plateau (within the slope tolerance) spanning
// at least min_span in ln r; the one reaching the largest r (small-scale artefacts lie below).
// Indices are bins; [begin, end) are the curve points of the fit (the plateau's slope windows).
struct ScalingRegion {
  bool found = false;
  int saturation = 0, top = 0;
  std::size_t plateau_begin = 0, plateau_end = 0, begin = 0, end = 0;
  std::vector<double> mean_slope;  // per bin, NaN where the dimensions disagree
};
ScalingRegion scaling_region(const std::vector<DimensionSlopes>& dims, int saturation,
                             double dimension_tolerance, double slope_tolerance,
                             double min_span) {
  ScalingRegion out;
  out.saturation = saturation;
  out.top = std::min<int>(saturation + consistent_dimensions - 1, int(dims.size()));
  const std::size_t bins = dims.front().slopes.size();
  out.mean_slope.assign(bins, nan);
  std::vector<double> finite;
  for (std::size_t k = 0; k < bins; ++k) {
    double sum = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    bool all = true;
    for (int d = saturation; d <= out.top; ++d) {
      const double v = dims[std::size_t(d - 1)].slopes[k];
      all = all && std::isfinite(v);
      sum += v;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (!all) continue;
    const double mean = sum / double(out.top - saturation + 1);
    if (hi - lo <= dimension_tolerance * mean) {
      out.mean_slope[k] = mean;
      finite.push_back(mean);
    }
  }
  if (finite.empty()) return out;
  std::nth_element(finite.begin(), finite.begin() + std::ptrdiff_t(finite.size() / 2),
                   finite.end());
  const double scale = std::max(1.0, finite[finite.size() / 2]);
  const auto& log_r = dims.front().curve.log_r;
  const auto region =
      nonlinear::find_plateau(log_r, out.mean_slope, slope_tolerance * scale, min_span, true);
  if (!region.found) return out;
  out.found = true;
  out.plateau_begin = region.begin;
  out.plateau_end = region.end;
  out.begin = region.begin - slope_half_window;
  out.end = region.end + slope_half_window;
  return out;
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
                   "a scaling region is a range of r whose local slopes (mean of the consistent "
                   "dimensions) stay within this fraction of their median",
                   0.1, 0, 1, true),
      numeric_spec("saturation_tolerance", ValueKind::real, "1",
                   "D2 has saturated from the first embedding dimension whose local slopes agree "
                   "with those of the next two within this fraction, scale by scale (the "
                   "lacunarity of fractal sets moves them by a few per cent)",
                   0.1, 0, 1, true),
      nonlinear::bootstrap_spec(),
      nonlinear::seed_spec(),
  };
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_dimension", 4}, {"max_reference_points", 200}};
  return info;
}

namespace {

const double min_region_span = std::log(4.0);  // at least a factor 4 in r
// Another run of consistent slopes counts as a second scaling behaviour when it spans at least
// a factor 2 in r and levels off more than this fraction away from the region's level.
constexpr double other_level_difference = 0.15;

double span_of(const std::vector<double>& log_r, const ScalingRegion& g) {
  return log_r[g.plateau_end - 1] - log_r[g.plateau_begin];
}

// The sweep goes to max(8, 2 m + 2) dimensions, as far as the series holds minimum_vectors
// vectors (a short series with a long delay would otherwise have none).
int sweep_dimensions(std::size_t samples, const EmbeddingParameters& embedding,
                     std::optional<std::int64_t> given) {
  if (given) return int(*given);
  int max_dimension = std::max(8, 2 * embedding.dimension + 2);
  while (max_dimension > 2 && samples < nonlinear::minimum_samples(max_dimension, embedding.delay))
    --max_dimension;
  return max_dimension;
}

// The scales of the data: the scaling region (if any), else the longest consistent stretch
// (reported, not fitted), the noise scale below, a second level of consistent slopes.
struct Scales {
  ScalingRegion region, longest;
  double noise_r = nan;
  std::size_t other_begin = 0, other_end = 0;
  double other_level = nan;
};

// Saturation: the dimension from 2 on whose local slopes agree with those of the next two over
// the longest plateau of at least min_region_span (the first of equally long ones). A dimension
// below the embedding one may agree over a short range (Lorenz: d = 2 folds the attractor only
// at large scales); the longest plateau is where all agree. The lowest dimension whose plateau
// is nearly (3/4) as long as the longest is taken.
ScalingRegion saturation_region(const std::vector<DimensionSlopes>& dims,
                                double dimension_tolerance, double slope_tolerance) {
  const int max_dimension = int(dims.size());
  const auto& log_r = dims.front().curve.log_r;
  std::vector<ScalingRegion> candidates;
  double longest_span = 0;
  for (int d = 2; d + consistent_dimensions - 1 <= max_dimension; ++d) {
    candidates.push_back(
        scaling_region(dims, d, dimension_tolerance, slope_tolerance, min_region_span));
    if (candidates.back().found)
      longest_span = std::max(longest_span, span_of(log_r, candidates.back()));
  }
  for (const auto& c : candidates)
    if (c.found && span_of(log_r, c) >= 0.75 * longest_span) return c;
  return {};
}

// Without a scaling region: the longest consistent stretch of any span (at least three bins, a
// tenth of a decade: a lone point is no range).
ScalingRegion longest_consistent(const std::vector<DimensionSlopes>& dims,
                                 double dimension_tolerance, double slope_tolerance) {
  ScalingRegion longest;
  for (int d = 2; d + consistent_dimensions - 1 <= int(dims.size()); ++d) {
    auto candidate = scaling_region(dims, d, dimension_tolerance, slope_tolerance, 0.0);
    if (candidate.found && candidate.plateau_end - candidate.plateau_begin >= 3 &&
        (!longest.found || candidate.plateau_end - candidate.plateau_begin >
                               longest.plateau_end - longest.plateau_begin))
      longest = candidate;
  }
  return longest;
}

// The slope of the highest dimension with data at bin k, above dimension `above` (NaN if none).
double highest_slope(const std::vector<DimensionSlopes>& dims, int above, std::size_t k) {
  for (int d = int(dims.size()); d > above; --d)
    if (std::isfinite(dims[std::size_t(d - 1)].slopes[k])) return dims[std::size_t(d - 1)].slopes[k];
  return nan;
}

// Noise scale: below bin `below`, the largest r whose local slope in the highest swept
// dimension with data exceeds that of dimension low_d by noise_slope_excess.
double noise_scale(const std::vector<DimensionSlopes>& dims, int low_d, std::size_t below) {
  double noise_r = nan;
  const auto& log_r = dims.front().curve.log_r;
  for (std::size_t k = 0; k < below && int(dims.size()) > low_d; ++k) {
    const double base = dims[std::size_t(low_d - 1)].slopes[k];
    const double highest = highest_slope(dims, low_d, k);
    if (std::isfinite(base) && std::isfinite(highest) && highest - base > noise_slope_excess)
      noise_r = std::exp(log_r[k]);
  }
  return noise_r;
}

// Another stretch of consistent slopes (at least a factor 2 in r) whose level differs from the
// region's by more than other_level_difference: the data show two scaling behaviours (e.g. the
// strands of a finite trajectory below the scale of a quasi-periodic torus), and D2 is not
// settled. Above the region, slopes that still grow with the dimension beyond it are the bend at
// the attractor's extent, not a second scaling behaviour.
void find_other_level(const std::vector<DimensionSlopes>& dims, Scales& s) {
  const ScalingRegion& region = s.region;
  const auto& log_r = dims.front().curve.log_r;
  const std::size_t bins = log_r.size();
  const double level = region.mean_slope[(region.plateau_begin + region.plateau_end) / 2];
  auto outside = [&](std::size_t k) {
    return std::isfinite(region.mean_slope[k]) &&
           !(k >= region.plateau_begin && k < region.plateau_end);
  };
  for (std::size_t k = 0; k < bins;) {
    if (!outside(k)) {
      ++k;
      continue;
    }
    std::size_t e = k;
    std::vector<double> run;
    while (e < bins && outside(e)) run.push_back(region.mean_slope[e++]);
    const double median = run[run.size() / 2];
    bool bend = false;
    if (k >= region.plateau_end) {
      const std::size_t mid = (k + e) / 2;
      const double highest = highest_slope(dims, region.saturation, mid);
      bend = std::isfinite(highest) &&
             highest - dims[std::size_t(region.saturation - 1)].slopes[mid] > 0.05 * median;
    }
    if (!bend && log_r[e - 1] - log_r[k] >= std::log(2.0) &&
        std::abs(median - level) > other_level_difference * level &&
        (!std::isfinite(s.other_level) || e - k > s.other_end - s.other_begin)) {
      s.other_begin = k;
      s.other_end = e;
      s.other_level = median;
    }
    k = e;
  }
}

Scales find_scales(const std::vector<DimensionSlopes>& dims, double dimension_tolerance,
                   double slope_tolerance) {
  Scales s;
  s.region = saturation_region(dims, dimension_tolerance, slope_tolerance);
  if (!s.region.found) s.longest = longest_consistent(dims, dimension_tolerance, slope_tolerance);
  const ScalingRegion& seen = s.region.found ? s.region : s.longest;
  s.noise_r = noise_scale(dims, seen.found ? seen.saturation : 2,
                          seen.found ? seen.plateau_begin : dims.front().slopes.size());
  if (s.region.found) find_other_level(dims, s);
  return s;
}

// D2 over the scaling region: the mean slope of the consistent dimensions, its bootstrap
// interval, each dimension's slope, the ML estimate, and the interval spanning what the data
// leave open.
struct D2Fit {
  double value = nan, ml = nan, low = nan, high = nan;
  nonlinear::Interval ci{nan, nan};
  std::vector<double> per_dimension;
};

D2Fit fit_region(const CorrelationSums& sums, const std::vector<DimensionSlopes>& dims,
                 const Scales& s, std::size_t replicates, std::uint64_t seed) {
  const ScalingRegion& region = s.region;
  const int max_dimension = int(dims.size());
  D2Fit f;
  f.per_dimension.assign(std::size_t(max_dimension), nan);
  const std::vector<double> ones(CorrelationSums::blocks, 1.0);
  auto slope_over = [&](const std::vector<double>& w, int d, std::size_t b, std::size_t e) {
    const Curve c = curve(sums, d, w);
    for (std::size_t k = b; k < e; ++k)
      if (!std::isfinite(c.log_c[k])) return nan;
    return nonlinear::fit_line(c.log_r, c.log_c, b, e).slope;
  };
  const double consistent = double(region.top - region.saturation + 1);
  auto mean_over = [&](const std::vector<double>& w, std::size_t b, std::size_t e) {
    double mean = 0;
    for (int d = region.saturation; d <= region.top; ++d) mean += slope_over(w, d, b, e) / consistent;
    return mean;
  };
  f.value = mean_over(ones, region.begin, region.end);
  f.ci = nonlinear::block_bootstrap(
      CorrelationSums::blocks, replicates, seed,
      [&](const std::vector<double>& w) { return mean_over(w, region.begin, region.end); });
  for (int d = 1; d <= max_dimension; ++d)
    f.per_dimension[std::size_t(d - 1)] = slope_over(ones, d, region.begin, region.end);
  // Maximum likelihood over the same scales, mean of the consistent dimensions.
  f.ml = 0;
  for (int d = region.saturation; d <= region.top; ++d)
    f.ml += ml_dimension(dims[std::size_t(d - 1)].curve, region.begin, region.end,
                         2.0 * max_dimension) /
            consistent;
  // The interval spans the bootstrap interval, each consistent dimension's slope, the lower and
  // upper halves of the region, the ML estimate and a second level of consistent slopes.
  const std::size_t mid = (region.begin + region.end) / 2;
  std::vector<double> alternatives{f.ml, mean_over(ones, region.begin, mid + 1),
                                   mean_over(ones, mid, region.end)};
  for (int d = region.saturation; d <= region.top; ++d)
    alternatives.push_back(f.per_dimension[std::size_t(d - 1)]);
  if (std::isfinite(s.other_level)) alternatives.push_back(s.other_level);
  f.low = f.ci.low, f.high = f.ci.high;
  for (double v : alternatives)
    if (std::isfinite(v)) {
      f.low = std::isfinite(f.low) ? std::min(f.low, v) : v;
      f.high = std::isfinite(f.high) ? std::max(f.high, v) : v;
    }
  return f;
}

double decades_between(const std::vector<double>& log_r, std::size_t a, std::size_t b) {
  return (log_r[b] - log_r[a]) / std::log(10.0);
}

// Plateau range in r and decades (the slope points; the fit adds half a window each side).
std::string plateau_text(const std::vector<double>& log_r, const ScalingRegion& g) {
  return fmt::format("r = {:.3g}..{:.3g} ({:.2f} decades)", std::exp(log_r[g.plateau_begin]),
                     std::exp(log_r[g.plateau_end - 1]),
                     decades_between(log_r, g.plateau_begin, g.plateau_end - 1));
}

std::string noise_note(const Scales& s) {
  if (!s.region.found && !s.longest.found)
    return "local slopes grow with the dimension at every scale";
  return std::isfinite(s.noise_r) ? fmt::format("noise scale {:.3g} (local slopes grow with the "
                                                "embedding dimension below it)",
                                                s.noise_r)
                                  : "no noise scale detected";
}

// Why a fitted D2 is not "good" (empty: it is).
std::vector<std::string> doubts_about(const std::vector<double>& log_r, const Scales& s,
                                      const D2Fit& f) {
  const ScalingRegion& region = s.region;
  std::vector<std::string> doubts;
  const double span = decades_between(log_r, region.plateau_begin, region.plateau_end - 1);
  const double half_width = 0.5 * (f.high - f.low) / f.value;
  if (span < good_decades)
    doubts.push_back(fmt::format("the scaling region spans only {:.2f} decades", span));
  if (std::isfinite(s.other_level))
    doubts.push_back(fmt::format(
        "the slopes level off at {:.3g} over r = {:.3g}..{:.3g} as well (two scaling "
        "behaviours; the interval spans both)",
        s.other_level, std::exp(log_r[s.other_begin]), std::exp(log_r[s.other_end - 1])));
  else if (!(half_width <= good_relative_half_width))
    doubts.push_back(fmt::format("the interval is +-{:.1f} % wide", 100 * half_width));
  return doubts;
}

// What lies above the region: where the slopes leave the plateau.
std::string upper_scale_note(const std::vector<DimensionSlopes>& dims, const ScalingRegion& region) {
  const auto& log_r = dims.front().curve.log_r;
  const std::size_t bins = log_r.size();
  if (region.plateau_end >= bins || !std::isfinite(region.mean_slope[region.plateau_end - 1]))
    return "";
  std::size_t k = region.plateau_end;
  while (k < bins && !std::isfinite(dims[std::size_t(region.saturation - 1)].slopes[k])) ++k;
  return k < bins ? fmt::format("; above r = {:.3g} the slopes leave the plateau (curvature or "
                                "finite extent of the attractor)",
                                std::exp(log_r[region.end - 1]))
                  : "";
}

std::string region_reason(const std::vector<DimensionSlopes>& dims, const Scales& s,
                          const D2Fit& f, const std::vector<std::string>& doubts) {
  const ScalingRegion& region = s.region;
  const auto& log_r = dims.front().curve.log_r;
  std::string reason = fmt::format(
      "local slopes of dimensions {}-{} agree over {}: D2 = mean least-squares slope of ln C "
      "over r = {:.3g}..{:.3g}, maximum-likelihood estimate {:.4g}; {}{}; interval: "
      "bootstrap, dimensions, halves of the region and ML estimate",
      region.saturation, region.top, plateau_text(log_r, region), std::exp(log_r[region.begin]),
      std::exp(log_r[region.end - 1]), f.ml, noise_note(s), upper_scale_note(dims, region));
  if (!doubts.empty()) reason += fmt::format("; uncertain: {}", fmt::join(doubts, "; "));
  return reason;
}

std::string no_region_reason(const std::vector<double>& log_r, const Scales& s,
                             int max_dimension) {
  const ScalingRegion& longest = s.longest;
  if (longest.found)
    return fmt::format(
        "no scaling region: the longest range where the local slopes of dimensions {}-{} agree "
        "(about {:.3g}) is {}, shorter than the {:.2f} decades needed: not fitted; {}",
        longest.saturation, longest.top,
        longest.mean_slope[(longest.plateau_begin + longest.plateau_end) / 2],
        plateau_text(log_r, longest), min_region_span / std::log(10.0), noise_note(s));
  return fmt::format("no saturation: the local slopes grow with the embedding dimension at "
                     "every resolved scale up to dimension {} (noise-like, high-dimensional "
                     "or too short a series); {}",
                     max_dimension, noise_note(s));
}

// C(r), local slopes and D2 of every swept dimension, with the fitted region.
Json by_dimension_json(const std::vector<DimensionSlopes>& dims, const D2Fit& f,
                       const ScalingRegion& region) {
  const auto& log_r = dims.front().curve.log_r;
  Json by_dimension = Json::array();
  for (const auto& d : dims) {
    const double d2 = f.per_dimension.empty() ? nan : f.per_dimension[std::size_t(d.dimension - 1)];
    Json entry{{"dimension", d.dimension}, {"d2", std::isfinite(d2) ? Json(d2) : Json()}};
    entry["r_low"] = region.found ? Json(std::exp(log_r[region.begin])) : Json();
    entry["r_high"] = region.found ? Json(std::exp(log_r[region.end - 1])) : Json();
    std::vector<double> r, c;
    Json slopes_json = Json::array();
    for (std::size_t k = 0; k < d.curve.log_r.size(); ++k)
      if (std::isfinite(d.curve.log_c[k])) {
        r.push_back(std::exp(d.curve.log_r[k]));
        c.push_back(std::exp(d.curve.log_c[k]));
        slopes_json.push_back(std::isfinite(d.slopes[k]) ? Json(d.slopes[k]) : Json());
      }
    entry["r"] = r;
    entry["correlation_sum"] = c;
    entry["local_slope"] = slopes_json;
    by_dimension.push_back(entry);
  }
  return by_dimension;
}

}  // namespace

Json CorrelationDimension::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const int max_dimension = sweep_dimensions(
      x.size(), embedding, nonlinear::given_integer(params_, "max_dimension"));
  const std::string name = series.name.empty() ? std::string("series") : series.name;
  nonlinear::check_series(x, max_dimension, embedding.delay, name);

  const auto all_pairs_within = nonlinear::given_real(params_, "all_pairs_within");
  const CorrelationSums sums =
      all_pairs_within
          ? correlation_sums_within(x, max_dimension, embedding.delay, embedding.theiler,
                                    *all_pairs_within)
          : correlation_sums(x, max_dimension, embedding.delay, embedding.theiler,
                             std::size_t(params_.integer("max_reference_points")));
  std::vector<DimensionSlopes> dims;
  for (int d = 1; d <= max_dimension; ++d)
    dims.push_back(dimension_slopes(sums, d, double(params_.integer("min_pairs"))));
  const auto& log_r = dims.front().curve.log_r;
  const Scales scales =
      find_scales(dims, params_.real("saturation_tolerance"), params_.real("slope_tolerance"));
  const ScalingRegion& region = scales.region;

  Json out;
  D2Fit fit;
  std::string quality = "failed", reason;
  if (region.found) {
    fit = fit_region(sums, dims, scales, std::size_t(params_.integer("bootstrap_replicates")),
                     std::uint64_t(params_.integer("seed")));
    const auto doubts = doubts_about(log_r, scales, fit);
    quality = doubts.empty() ? "good" : "uncertain";
    reason = region_reason(dims, scales, fit, doubts);
    out["scaling_region"] = {std::exp(log_r[region.begin]), std::exp(log_r[region.end - 1])};
  } else {
    reason = no_region_reason(log_r, scales, max_dimension);
    out["scaling_region"] = Json();
  }
  const bool ml_found = std::isfinite(fit.ml);
  out["correlation_dimension"] = nonlinear::estimate(fit.value, fit.low, fit.high, quality, reason);
  out["correlation_dimension_ml"] = nonlinear::estimate(
      fit.ml, nan, nan, ml_found ? quality : "failed",
      ml_found ? "binned maximum likelihood (Takens-Theiler-Judd) over the scaling region"
               : "no scaling region");
  out["bootstrap_ci"] = {std::isfinite(fit.ci.low) ? Json(fit.ci.low) : Json(),
                         std::isfinite(fit.ci.high) ? Json(fit.ci.high) : Json()};
  out["saturation_dimension"] = region.found ? region.saturation : 0;
  out["consistent_dimensions"] =
      region.found ? Json::array({region.saturation, region.top}) : Json();
  out["noise_level"] = std::isfinite(scales.noise_r) ? Json(scales.noise_r) : Json();
  out["delay_samples"] = embedding.delay;
  out["theiler_window_samples"] = embedding.theiler;
  out["embedding_source"] = embedding.source;
  out["reference_points"] = params_.integer("max_reference_points");
  if (all_pairs_within) out["all_pairs_within"] = *all_pairs_within;
  out["by_dimension"] = by_dimension_json(dims, fit, region);
  return out;
}

void CorrelationDimension::plot(const Json& result, const SampledSeries& series,
                                const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  plot::Curves sums, slopes, saturation;
  sums.title = fmt::format("{}: correlation sums", title);
  sums.x_label = "r [signal units]";
  sums.y_label = "C(r)";
  sums.log_x = sums.log_y = true;
  slopes.title = fmt::format("{}: local slopes d ln C / d ln r", title);
  slopes.x_label = "r [signal units]";
  slopes.y_label = "local slope";
  slopes.log_x = true;
  saturation.title = fmt::format("{}: D2 versus embedding dimension (slopes over the scaling "
                                 "region)",
                                 title);
  saturation.x_label = "embedding dimension d";
  saturation.integer_x = true;
  saturation.y_label = "D2";
  // The scaling region is marked on the dimensions whose slopes agree there.
  const Json& used = result["consistent_dimensions"];
  const int first = used.is_array() ? used[0].get<int>() : 0;
  const int last = used.is_array() ? used[1].get<int>() : -1;
  const std::string region_label =
      used.is_array() ? fmt::format("scaling region (d = {}-{})", first, last) : "";
  plot::Series region{region_label, {}, {}, "points"}, region_slope{region_label, {}, {}, "points"};
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
    if (!entry["d2"].is_number()) continue;
    d2_curve.x.push_back(d);
    d2_curve.y.push_back(entry["d2"].get<double>());
    if (d < first || d > last) continue;
    const double lo = entry["r_low"].get<double>(), hi = entry["r_high"].get<double>();
    for (std::size_t k = 0; k < r.size(); ++k)
      if (r[k] >= lo && r[k] <= hi) {
        region.x.push_back(r[k]);
        region.y.push_back(c[k]);
        if (slope[k].is_number()) {
          region_slope.x.push_back(r[k]);
          region_slope.y.push_back(slope[k].get<double>());
        }
      }
  }
  if (!region.x.empty()) sums.series.push_back(std::move(region));
  if (!region_slope.x.empty()) slopes.series.push_back(std::move(region_slope));
  const Json& estimate = result["correlation_dimension"];
  if (estimate["value"].is_number()) {
    slopes.reference_y = saturation.reference_y = estimate["value"].get<double>();
    slopes.reference_label = saturation.reference_label =
        fmt::format("D2 = {:.3f}", estimate["value"].get<double>());
  }
  saturation.series.push_back(d2_curve);
  plot::render(sums, out_dir, "correlation_dimension_sums");
  plot::render(slopes, out_dir, "correlation_dimension_slopes");
  if (!d2_curve.x.empty()) plot::render(saturation, out_dir, "correlation_dimension_saturation");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::CorrelationDimension);
