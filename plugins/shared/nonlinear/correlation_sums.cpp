#include "shared/nonlinear/correlation_sums.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"

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
CorrelationSums empty_sums(std::span<const double> x, int max_dimension) {
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
std::vector<double> normalised(std::span<const double> x) {
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

CorrelationSums correlation_sums(std::span<const double> x, int max_dimension, int delay,
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

CorrelationSums correlation_sums_within(std::span<const double> x, int max_dimension,
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

}  // namespace chatterlab
