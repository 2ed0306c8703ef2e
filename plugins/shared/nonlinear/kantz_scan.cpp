#include "shared/nonlinear/kantz_scan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "shared/nonlinear/box_grid.hpp"
#include "shared/nonlinear/ordered_sum.hpp"
#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t minimum_pairs_margin = 100;  // vectors beyond one separation history

}  // namespace

std::vector<double> BlockCurve::mean(const std::vector<double>& weights) const {
  std::vector<double> y(steps, 0.0), c(steps, 0.0);
  for (std::size_t b = 0; b < kantz_blocks; ++b)
    for (std::size_t k = 0; k < steps; ++k) {
      y[k] += weights[b] * sum[b * steps + k];
      c[k] += weights[b] * count[b * steps + k];
    }
  for (std::size_t k = 0; k < steps; ++k) y[k] = c[k] > 0 ? y[k] / c[k] : nan;
  return y;
}

double BlockCurve::references_at_start() const {
  double n = 0;
  for (std::size_t b = 0; b < kantz_blocks; ++b) n += count[b * steps];
  return n;
}

BlockCurve KantzScan::block_curve(std::size_t r, int m) const {
  const std::size_t dims = dimensions(), nr = radii.size();
  const std::size_t d = std::size_t(m - min_dimension);
  BlockCurve out;
  out.steps = steps;
  out.sum.resize(kantz_blocks * steps);
  out.count.resize(kantz_blocks * steps);
  for (std::size_t b = 0; b < kantz_blocks; ++b) {
    const std::size_t row = (b * nr + r) * dims + d;
    std::copy_n(sum.begin() + std::ptrdiff_t(row * steps), steps,
                out.sum.begin() + std::ptrdiff_t(b * steps));
    std::copy_n(count.begin() + std::ptrdiff_t(row * steps), steps,
                out.count.begin() + std::ptrdiff_t(b * steps));
  }
  return out;
}

std::vector<double> KantzScan::curve(std::size_t r, int m) const { return block_curve(r, m).mean(); }

namespace {

// What one reference's neighbour pass needs to know about the scan.
using Vector4 = double __attribute__((vector_size(32)));  // four doubles (AVX2; SSE2: two halves)
using Mask4 = long long __attribute__((vector_size(32)));  // their comparisons (0 or -1)
using Code4 = std::int32_t __attribute__((vector_size(16)));  // four profile codes

struct ScanShape {
  int min_dimension = 1, axes = 1;
  // step: the delay in samples (delay coordinates); history_stride: samples between stored
  // history samples; history_step = step / history_stride: the delay in history samples.
  std::size_t dims = 1, radii = 1, step = 1, history_stride = 1, history_step = 1, history = 0,
              padded = 0, theiler = 0;
  const double* radii2 = nullptr;  // squared radii, ascending
  double floor2 = 0;               // coincident vectors (closer than this) are skipped
  double centre = 0;        // histories hold float(x - centre): mid-range halves the rounding
  double discard_code = 0;  // the profile code of a candidate lane that is no neighbour
  // Profile codes: place value (radii + 1)^d of dimension index d.
  std::vector<double> places;
  // The possible profiles (radius bins nondecreasing with the dimension, within the largest
  // radius in min_dimension), numbered densely: profile_of[code] (-1 for codes that cannot
  // occur), and for profile k the bins it adds to, bin_of[bins_begin[k] .. bins_begin[k + 1])
  // as r * dims + d. Precomputed once: a table of slots filled per reference and the decoding
  // of each slot's code were a visible cost.
  std::vector<std::int32_t> profile_of;
  std::vector<std::uint32_t> bins_begin, bin_of;
  std::size_t profile_count() const { return bins_begin.size() - 1; }
  void number_profiles() {
    std::size_t codes = 1;
    for (std::size_t d = 0; d < dims; ++d) codes *= radii + 1;
    profile_of.assign(codes, -1);
    bins_begin.assign(1, 0);
    bin_of.clear();
    std::vector<std::size_t> digits(dims);
    for (std::size_t code = 0; code < codes; ++code) {
      std::size_t rest = code;
      bool possible = true;
      for (std::size_t d = 0; d < dims; ++d, rest /= radii + 1) {
        digits[d] = rest % (radii + 1);
        possible = possible && (d == 0 ? digits[d] < radii : digits[d] >= digits[d - 1]);
      }
      if (!possible) continue;
      profile_of[code] = std::int32_t(bins_begin.size() - 1);
      for (std::size_t d = 0; d < dims && digits[d] < radii; ++d)
        bin_of.push_back(std::uint32_t(digits[d] * dims + d));
      bins_begin.push_back(std::uint32_t(bin_of.size()));
    }
    // Code `codes` is the discard code: its profile, one past the real ones, collects the lanes
    // of candidate blocks that hold no neighbour and is dropped by group_by_profile.
    profile_of.push_back(std::int32_t(profile_count()));
    discard_code = double(codes);
  }
};

// Per-thread scratch of one reference's neighbour pass. A neighbour's radius bins in the scanned
// dimensions form a "profile" (r_d per dimension d, nondecreasing, `radii` = beyond the largest);
// neighbours with the same profile are summed together, so each neighbour costs one history sum
// whatever the number of dimensions.
struct NeighbourSums {
  std::vector<double*> targets;          // the bins a profile adds to
  std::vector<double> own;               // the reference's delay coordinates
  std::vector<std::uint32_t> near;       // slots: candidate window rows, four per block
  std::vector<std::uint32_t> near_code;  // their profile code (discard: no neighbour)
  std::vector<std::int32_t> next;        // the next slot of the same profile, -1: none
  std::vector<std::int32_t> head;        // per profile (and discard): its first slot, -1: none
  std::vector<std::uint32_t> profile_count;  // per profile: its neighbours
  std::vector<std::uint32_t> present;    // the profiles of the reference's neighbours
  std::size_t used = 0;                  // how many
};

// The points of a grid row and the reach_rows rows on either side (rows: boxes of the first
// axis), each row sorted along the second axis (one-axis grid: the first) and copied in that
// order: their separation histories x_{j + t stride} (t < history, zero padded), their delay
// coordinates x_{j + l delay}, one column per coordinate (structure of arrays: the distance pass
// takes four consecutive candidates per vector), and their time indices. Sorted rows make a
// reference's candidates in a row one contiguous stretch of +-eps along the sort axis (the three
// boxes of the previous search spanned 3 eps on average). Rows are the unit of work of a thread.
// History samples are stored in single precision, as x - centre: half the bytes per neighbour
// and eight samples per vector made the scan 0.65-0.75 of its time with doubles (Lorenz and
// Henon benchmarks); the neighbour sets and radius bins are still decided in double precision.
// Each stored sample is off by at most 2^-24 of half the data range, so the rms separation of a
// reference's neighbours by at most sqrt(m) 2^-24 x range, and S(k) by that over the rms
// (lyapunov_test checks this bound against the double-precision definition). Samples are
// stored in planes of plane_width (every point's samples 0..55, then 56..111, ...), and the
// history sums of a group of consecutive references run plane by plane: the neighbour
// histories in use while a group is summed are then a plane's share of the whole. With the
// benchmarks' 51 steps one plane holds the whole history.
constexpr std::size_t plane_width = 56;  // seven vectors of eight: add_separations' blocking
struct RowWindow {
  // Plane c: x_{j + t}, t = c * plane_width + u, at [c * plane_width * count + w * width(c) + u].
  std::vector<float> histories;
  std::vector<double> columns;           // x_{j + l delay} at [l * stride + w]
  std::vector<std::uint32_t> index;      // j at [w]
  std::vector<double> time;              // j at [w] as a double (vector Theiler test)
  std::size_t stride = 0;                // points + 4 (zero slack for the last vector)
  std::size_t count = 0, padded = 0;
  // The points' coordinates, indices and times; their histories too unless `with_histories` is
  // false (sampled references: fill_histories later stores only those a group needs).
  void fill(const ScanShape& s, const double* x, const std::uint32_t* points, std::size_t n,
            bool with_histories = true) {
    const std::size_t coordinates = std::size_t(s.min_dimension) + s.dims - 1;
    count = n;
    padded = s.padded;
    stride = count + 4;
    columns.assign(coordinates * stride, 0.0);
    index.assign(stride, 0);
    time.assign(stride, 0.0);
    for (std::size_t w = 0; w < count; ++w) {
      const std::size_t j = points[w];
      index[w] = std::uint32_t(j);
      time[w] = double(j);
      for (std::size_t l = 0; l < coordinates; ++l) columns[l * stride + w] = x[j + l * s.step];
    }
    if (with_histories) fill_histories(s, x, points, n);
  }
  // The separation histories of points[0..n), at positions 0..n-1.
  void fill_histories(const ScanShape& s, const double* x, const std::uint32_t* points,
                      std::size_t n) {
    count = n;
    padded = s.padded;
    histories.resize(count * s.padded);
    for (std::size_t w = 0; w < count; ++w) {
      const std::size_t j = points[w];
      for (std::size_t c = 0; c < planes(); ++c) {
        // Samples t < history exist for every stored point (j < limit); zeros beyond.
        float* to = histories.data() + c * plane_width * count + w * width(c);
        const std::size_t t0 = c * plane_width;
        const std::size_t valid = t0 < s.history ? std::min(width(c), s.history - t0) : 0;
        const double* from = x + j + t0 * s.history_stride;
        for (std::size_t u = 0; u < valid; ++u) to[u] = float(from[u * s.history_stride] - s.centre);
        std::fill(to + valid, to + width(c), 0.0f);
      }
    }
  }
  std::size_t planes() const { return (padded + plane_width - 1) / plane_width; }
  std::size_t width(std::size_t c) const { return std::min(plane_width, padded - c * plane_width); }
  const float* plane(std::size_t c) const { return histories.data() + c * plane_width * count; }
};

// (Out parameter: returning a 32-byte vector by value changes the ABI of the non-AVX clone.)
inline void load4(Vector4& v, const double* p) { std::memcpy(&v, p, sizeof v); }
using Float8 = float __attribute__((vector_size(32)));  // eight floats (history samples)
inline void load8(Float8& v, const float* p) { std::memcpy(&v, p, sizeof v); }

// sum[offset + t] += sum over the members of (xi - xj)^2 for `Vectors` x 8 consecutive history
// samples t: the partial sums stay in registers (single precision) while the members stream by,
// and are added to the double-precision bins at the end. The members are a
// list: neighbour `first`, then next[first], ... up to -1; neighbour p is window row near[p],
// its samples at histories + near[p] * width.
template <std::size_t Vectors>
[[gnu::always_inline]] inline void add_separations(const float* xi, const float* histories,
                                                   std::size_t width, std::int32_t first,
                                                   const std::int32_t* next,
                                                   const std::uint32_t* near, std::size_t offset,
                                                   double* const* targets,
                                                   std::size_t target_count) {
  Float8 acc[Vectors] = {};
  Float8 reference[Vectors];
  for (std::size_t v = 0; v < Vectors; ++v) load8(reference[v], xi + offset + 8 * v);
  for (std::int32_t p = first; p >= 0; p = next[p]) {
    const float* xj = histories + std::size_t(near[p]) * width + offset;
    for (std::size_t v = 0; v < Vectors; ++v) {
      Float8 other;
      load8(other, xj + 8 * v);
      const Float8 d = reference[v] - other;
      acc[v] += d * d;
    }
  }
  // The single-precision sums widened, four at a time.
  Vector4 wide[2 * Vectors];
  for (std::size_t v = 0; v < Vectors; ++v) {
    const Float8& a = acc[v];
    wide[2 * v] = __builtin_convertvector(__builtin_shufflevector(a, a, 0, 1, 2, 3), Vector4);
    wide[2 * v + 1] = __builtin_convertvector(__builtin_shufflevector(a, a, 4, 5, 6, 7), Vector4);
  }
  for (std::size_t target = 0; target < target_count; ++target)
    for (std::size_t v = 0; v < 2 * Vectors; ++v) {
      double* sum = targets[target] + offset + 4 * v;
      Vector4 total;
      load4(total, sum);
      total += wide[v];
      std::memcpy(sum, &total, sizeof total);
    }
}

// The slots grouped by profile as linked lists (in order of p): head[k] = first slot of profile k
// (-1: none; all -1 on entry), next[p] = the one after p, count[k] = their number (0 on entry),
// the profiles present in `present` (ascending, the discard profile dropped). Returns how many
// are present. One pass and no scatter: a counting sort's scatter (position loaded, incremented
// and stored, then the slot stored at it) stalled on store forwarding, and a counting sort into
// contiguous per-profile arrays made the whole scan 1.3 x slower (2026-11-22). Kept out of line:
// inlined into the vector passes its pointers were spilled to the stack and reloaded.
[[gnu::noinline]] std::size_t group_by_profile(const std::uint32_t* __restrict code,
                                               std::size_t kept,
                                               const std::int32_t* __restrict profile_of,
                                               std::int32_t* __restrict head,
                                               std::int32_t* __restrict next,
                                               std::uint32_t* __restrict count,
                                               std::uint32_t* __restrict present,
                                               std::size_t discard) {
  std::size_t used = 0;
  for (std::size_t p = kept; p-- > 0;) {
    const auto k = std::size_t(profile_of[code[p]]);
    if (head[k] < 0) present[used++] = std::uint32_t(k);
    next[p] = head[k];
    head[k] = std::int32_t(p);
    ++count[k];
  }
  std::sort(present, present + used);
  // The discard profile sorts last: drop it and reset its list.
  if (used > 0 && present[used - 1] == discard) --used;
  head[discard] = -1;
  count[discard] = 0;
  return used;
}

// Grid rows are a fraction 1 / reach_rows of the largest radius wide: a reference's candidates
// lie in reach_rows rows on either side. Narrower rows mean fewer candidates (the stretches
// cover (1 + 2 / reach_rows) x 2 eps^2 instead of 3 x 2 eps^2 around the eps disk) and a
// smaller set of neighbour histories in use while a row is swept.
constexpr std::size_t reach_rows = 2;

// References whose history sums run together, plane by plane (RowWindow).
constexpr std::size_t reference_group = 16;

// A reference's candidates: stretches [first, last) of window positions, one per row.
struct Candidates {
  std::size_t first[2 * reach_rows + 1] = {}, last[2 * reach_rows + 1] = {};
  std::size_t runs = 0;
};

// The neighbours of the reference at window position `own` within the largest radius, grouped
// by profile (in `sums`, for add_histories). Two passes: four candidates at a time, the
// distance in min_dimension and, for blocks with a neighbour, the profile codes of all four
// lanes (the discard code for lanes that are no neighbour); then the grouping. Compiled for
// AVX2 as well (chosen at run time).
// Radii: the number of radii as a compile-time constant (0: s.radii at run time). With the
// radius loop unrolled the scan took 0.91 of its time (Lorenz benchmark, 5 radii, median of 10
// alternating rounds).
template <std::size_t Radii>
[[gnu::always_inline]] inline void find_neighbours_with(const ScanShape& s,
                                                        const RowWindow& window, std::size_t own,
                                                        const Candidates& candidates,
                                                        NeighbourSums& sums) {
  const std::size_t radii = Radii > 0 ? Radii : s.radii;
  const std::size_t i = window.index[own];
  const double eps2 = s.radii2[s.radii - 1];
  std::size_t count = 0;
  for (std::size_t run = 0; run < candidates.runs; ++run)
    count += candidates.last[run] - candidates.first[run];
  const std::size_t slots = count + 4 * candidates.runs;  // whole blocks of four
  if (sums.near.size() < slots) {
    sums.near.resize(slots);
    sums.near_code.resize(slots);
    sums.next.resize(slots);
    sums.present.resize(slots);
  }
  // Pass 1, four consecutive candidates per vector: the squared distance in min_dimension
  // (coordinates summed in order, as in the definition); neighbours are within the largest
  // radius, not coincident, outside the Theiler window. Every lane of a block with a neighbour
  // takes a slot (near, near_code): no per-lane compaction.
  const std::size_t m0 = std::size_t(s.min_dimension);
  const std::size_t coordinates = m0 + s.dims - 1;
  const std::size_t stride = window.stride;
  const double* columns = window.columns.data();
  sums.own.resize(coordinates);
  double* ci = sums.own.data();
  for (std::size_t l = 0; l < coordinates; ++l) ci[l] = columns[l * stride + own];
  std::uint32_t* __restrict near = sums.near.data();
  std::uint32_t* __restrict near_code = sums.near_code.data();
  const double* times = window.time.data();
  const double late = double(i) + double(s.theiler), early = double(i) - double(s.theiler);
  const Vector4 lane_number = {0, 1, 2, 3};
  const Mask4 every_lane = lane_number >= 0.0;
  std::size_t kept = 0;
  // Candidates c .. c + 3, those of lanes `valid` in the run.
  auto block = [&](std::size_t c, const Mask4& valid) __attribute__((always_inline)) {
    Vector4 distance = {};
    for (std::size_t l = 0; l < m0; ++l) {
      Vector4 other;
      load4(other, columns + l * stride + c);
      const Vector4 difference = ci[l] - other;
      distance += difference * difference;
    }
    // Skip blocks of four with no candidate within the largest radius.
    const Mask4 within = (distance <= eps2) & (distance > s.floor2) & valid;
    if (!(within[0] | within[1] | within[2] | within[3])) return;
    // The radius bins of the scanned dimensions as a code (the sum of the place values
    // (radii + 1)^d for every radius below the distance in dimension min_dimension + d), the
    // distance growing coordinate by coordinate; compares summed as a tree. Coding the lanes
    // of a block here instead of in a pass over the compacted neighbours saves gathering
    // their further coordinates.
    Vector4 code = {};
    for (std::size_t d = 0;; ++d) {
      const double place = s.places[d];
      const Vector4 zero = {}, places = {place, place, place, place};
      Vector4 even = {}, odd = {};
      std::size_t k = 0;
      for (; k + 1 < radii; k += 2) {
        even += distance > s.radii2[k] ? places : zero;
        odd += distance > s.radii2[k + 1] ? places : zero;
      }
      if (k < radii) even += distance > s.radii2[k] ? places : zero;
      code += even + odd;
      if (d + 1 == s.dims) break;
      Vector4 other;
      load4(other, columns + (m0 + d) * stride + c);
      const Vector4 difference = ci[m0 + d] - other;
      distance += difference * difference;
    }
    // All four lanes stored; those that are no neighbour (or inside the Theiler window)
    // get the discard code, so no lane is extracted (codes < 2^24 convert exactly).
    Mask4 keep = within;
    if (s.theiler > 0) {  // else only the reference itself is in the window: not within
      Vector4 time;
      load4(time, times + c);
      keep &= (time > late) | (time < early);
    }
    const Vector4 discard = {s.discard_code, s.discard_code, s.discard_code, s.discard_code};
    const Code4 codes = __builtin_convertvector(keep ? code : discard, Code4);
    const Code4 positions = {std::int32_t(c), std::int32_t(c + 1), std::int32_t(c + 2),
                             std::int32_t(c + 3)};
    std::memcpy(near_code + kept, &codes, sizeof codes);
    std::memcpy(near + kept, &positions, sizeof positions);
    kept += 4;
  };
  for (std::size_t run = 0; run < candidates.runs; ++run) {
    const std::size_t run_end = candidates.last[run];
    std::size_t c = candidates.first[run];
    for (; c + 4 <= run_end; c += 4) block(c, every_lane);
    if (c < run_end) block(c, lane_number < double(run_end - c));
  }
  // Pass 2: the neighbours profile by profile.
  sums.used = group_by_profile(near_code, kept, s.profile_of.data(), sums.head.data(),
                               sums.next.data(), sums.profile_count.data(), sums.present.data(),
                               s.profile_count());
}

[[gnu::target_clones("avx2", "default")]] void find_neighbours(const ScanShape& s,
                                                               const RowWindow& window,
                                                               std::size_t own,
                                                               const Candidates& candidates,
                                                               NeighbourSums& sums) {
  switch (s.radii) {
    case 1: return find_neighbours_with<1>(s, window, own, candidates, sums);
    case 2: return find_neighbours_with<2>(s, window, own, candidates, sums);
    case 3: return find_neighbours_with<3>(s, window, own, candidates, sums);
    case 4: return find_neighbours_with<4>(s, window, own, candidates, sums);
    case 5: return find_neighbours_with<5>(s, window, own, candidates, sums);
    case 6: return find_neighbours_with<6>(s, window, own, candidates, sums);
    case 7: return find_neighbours_with<7>(s, window, own, candidates, sums);
    case 8: return find_neighbours_with<8>(s, window, own, candidates, sums);
    default: return find_neighbours_with<0>(s, window, own, candidates, sums);
  }
}

// For each profile of the neighbours found by find_neighbours, the summed squared differences
// of history plane c (samples c * plane_width + u), which go straight to the bin of its radius
// in every dimension where it is within the largest radius, with the sums held in registers
// (one load per history sample and neighbour, no stores). The last plane resets the groups.
[[gnu::target_clones("avx2", "default")]] void add_histories(const ScanShape& s,
                                                             const RowWindow& window,
                                                             std::size_t own, std::size_t c,
                                                             NeighbourSums& sums, double* bins,
                                                             double* bin_count) {
  const float* plane = window.plane(c);
  const std::size_t width = window.width(c), start = c * plane_width, vectors = width / 8;
  const bool last = c + 1 == window.planes();
  const float* xi = plane + own * width;
  const std::int32_t* next = sums.next.data();
  const std::uint32_t* near = sums.near.data();
  std::vector<double*>& targets = sums.targets;
  targets.resize(s.dims);
  for (std::size_t u = 0; u < sums.used; ++u) {
    const std::size_t k = sums.present[u];
    const std::int32_t front = sums.head[k];
    std::size_t target_count = 0;
    for (std::size_t b = s.bins_begin[k]; b < s.bins_begin[k + 1]; ++b) {
      targets[target_count++] = bins + s.bin_of[b] * s.padded + start;
      if (c == 0) bin_count[s.bin_of[b]] += double(sums.profile_count[k]);
    }
    if (last) {
      sums.head[k] = -1;
      sums.profile_count[k] = 0;
    }
    // Seven vectors at a time: seven sums and seven reference vectors fill the 16 registers.
    std::size_t v = 0;
    for (; v + 7 <= vectors; v += 7)
      add_separations<7>(xi, plane, width, front, next, near, 8 * v, targets.data(), target_count);
    if (v + 4 <= vectors) {
      add_separations<4>(xi, plane, width, front, next, near, 8 * v, targets.data(), target_count);
      v += 4;
    }
    switch (vectors - v) {
      case 3: add_separations<3>(xi, plane, width, front, next, near, 8 * v, targets.data(), target_count); break;
      case 2: add_separations<2>(xi, plane, width, front, next, near, 8 * v, targets.data(), target_count); break;
      case 1: add_separations<1>(xi, plane, width, front, next, near, 8 * v, targets.data(), target_count); break;
      default: break;
    }
  }
}

// One reference's table: the summed histories of its neighbours binned by radius and dimension
// (bins[(r * dims + d) * padded + t], counts[r * dims + d]) turned into mean square distances
// within each radius, multiplied into `product` (row `row` of the per-block table) and counted in
// `factors`. Returns whether a product approaches under/overflow.
[[gnu::target_clones("avx2", "default")]] bool multiply_mean_squares(
    const ScanShape& s, std::size_t steps, const double* bins, const double* counts,
    double* mean_square, double* product, double* factors) {
  bool extreme = false;
  for (std::size_t d = 0; d < s.dims; ++d) {
    const std::size_t m = std::size_t(s.min_dimension) + d;
    double n = 0;
    for (std::size_t ri = 0; ri < s.radii; ++ri) {
      // Neighbours within radius r are those of bins 0..r: the m-dimensional sums
      // sum_j |X_{i+k} - X_{j+k}|^2 of each bin added up over the radii. An empty bin leaves them
      // as they are (few neighbours: most bins of a reference are empty).
      const double added = counts[ri * s.dims + d];
      if (added > 0) {
        const double* bin = bins + (ri * s.dims + d) * s.padded;
        if (n == 0) std::fill_n(mean_square, steps, 0.0);
        for (std::size_t l = 0; l < m; ++l) {
          const double* shifted = bin + l * s.history_step;
          for (std::size_t k = 0; k < steps; ++k) mean_square[k] += shifted[k];
        }
        n += added;
      }
      if (n == 0) continue;
      const double inverse = 1.0 / n;
      double* __restrict p = product + (ri * s.dims + d) * steps;
      double* __restrict f = factors + (ri * s.dims + d) * steps;
      const double* __restrict ms = mean_square;
      // Four steps per vector, without running min/max (which kept this loop scalar).
      const Vector4 one = {1, 1, 1, 1}, zero = {}, scale = {inverse, inverse, inverse, inverse};
      const Vector4 tiny = {1e-200, 1e-200, 1e-200, 1e-200}, huge = {1e200, 1e200, 1e200, 1e200};
      Mask4 outside4 = {};
      std::size_t k = 0;
      for (; k + 4 <= steps; k += 4) {
        Vector4 v, pk, fk;
        load4(v, ms + k);
        load4(pk, p + k);
        load4(fk, f + k);
        v *= scale;
        const Mask4 positive = v > zero;
        pk *= positive ? v : one;
        fk += positive ? one : zero;
        std::memcpy(p + k, &pk, sizeof pk);
        std::memcpy(f + k, &fk, sizeof fk);
        outside4 |= (pk < tiny) | (pk > huge);
      }
      int outside = int((outside4[0] | outside4[1] | outside4[2] | outside4[3]) != 0);
      for (; k < steps; ++k) {
        const double v = ms[k] * inverse;
        const bool positive = v > 0;
        const double next = p[k] * (positive ? v : 1.0);
        p[k] = next;
        f[k] += positive ? 1.0 : 0.0;
        outside |= int(next < 1e-200) | int(next > 1e200);
      }
      extreme = extreme || outside != 0;
    }
  }
  return extreme;
}

}  // namespace

KantzScan kantz_scan(std::span<const double> x, int min_dimension, int max_dimension, int delay,
                     std::size_t theiler, std::size_t steps, std::size_t references,
                     std::vector<double> radii, std::size_t stride) {
  KantzScan out;
  if (min_dimension < 1 || max_dimension < min_dimension || delay < 1 || steps < 1 ||
      radii.empty() || stride < 1 || std::size_t(delay) % stride != 0)
    throw PointFailure("kantz_scan: needs 1 <= min_dimension <= max_dimension, delay >= 1, "
                       "steps >= 1, at least one radius and a stride that divides the delay");
  std::sort(radii.begin(), radii.end());
  if (!(radii.front() > 0)) throw PointFailure("kantz_scan: radii must be positive");
  const std::size_t history_step = std::size_t(delay) / stride;
  // History samples (every `stride` samples) of a separation history: steps, then the further
  // delay coordinates of the last step.
  const std::size_t history = steps + std::size_t(max_dimension - 1) * history_step;
  const std::size_t reach_samples = (history - 1) * stride + 1;  // samples a history covers
  if (x.size() < reach_samples + minimum_pairs_margin)
    throw PointFailure(fmt::format("kantz_scan: {} samples are too few for {} steps of {} "
                                   "samples in {} dimensions (need at least {})",
                                   x.size(), steps, stride, max_dimension,
                                   reach_samples + minimum_pairs_margin));
  // Vectors with `steps` of future in max_dimension: references and neighbours alike.
  const std::size_t limit = x.size() - reach_samples + 1;
  references = references == 0 ? limit : std::min(references, limit);
  out.min_dimension = min_dimension;
  out.max_dimension = max_dimension;
  out.radii = radii;
  out.steps = steps;
  out.stride = stride;
  out.references = references;
  const std::size_t dims = out.dimensions(), nr = radii.size();
  const std::size_t row_size = nr * dims * steps;  // one reference's (radius, dimension, k) table
  std::vector<double> radii2(nr);
  for (std::size_t r = 0; r < nr; ++r) radii2[r] = radii[r] * radii[r];
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  ScanShape shape;
  shape.min_dimension = min_dimension;
  shape.axes = std::min(min_dimension, 2);
  shape.dims = dims;
  shape.radii = nr;
  shape.step = std::size_t(delay);
  shape.history_stride = stride;
  shape.history_step = history_step;
  shape.history = history;
  shape.padded = (history + 7) / 8 * 8;
  shape.theiler = theiler;
  shape.radii2 = radii2.data();
  shape.floor2 = std::pow(1e-9 * (*hi - *lo), 2);
  shape.centre = 0.5 * (*hi + *lo);
  shape.places.assign(dims, 0.0);
  double place = 1;
  for (std::size_t d = 0; d < dims; ++d, place *= double(nr + 1)) shape.places[d] = place;
  nonlinear::BoxGrid grid(x, delay, shape.axes, limit, radii.back() / double(reach_rows));
  std::size_t profile_codes = 1;
  for (std::size_t d = 0; d < dims; ++d) profile_codes *= nr + 1;
  if (profile_codes > (std::size_t(1) << 24))
    throw PointFailure(fmt::format("kantz_scan: {} radii x {} dimensions are too many (at most "
                                   "(radii + 1)^dimensions = 2^24 combinations)",
                                   nr, dims));
  shape.number_profiles();

  // References and neighbours are visited row by row of the grid, each row in the order of its
  // sort axis, so that consecutive references share their neighbours; each reference keeps the
  // bootstrap block of its time index. sorted: the time indices of the grid's points, row by
  // row, each row sorted along its sort axis (ties by time: one order for every window).
  std::vector<std::uint8_t> is_reference(limit, references == limit ? 1 : 0);
  if (references < limit)
    for (std::size_t r = 0; r < references; ++r)
      is_reference[std::size_t(double(r) * double(limit) / double(references))] = 1;
  auto block_of = [&](std::size_t i) { return i * kantz_blocks / limit; };
  const std::size_t rows = grid.rows();
  // The sort axis: the second delay coordinate x_{j + delay} (one-axis grid: x_j).
  const double* along_axis = x.data() + (shape.axes == 2 ? shape.step : 0);
  grid.sort_rows_by(along_axis);
  const std::uint32_t* sorted = grid.entries();
  const bool every_reference = references == limit;
  const std::vector<std::size_t> row_order = grid.rows_most_work_first();
  // A candidate's sort-axis coordinate is at most eps from the reference's (the margin keeps
  // every pair whose rounded distance is within eps).
  const double reach = radii.back() * (1 + 1e-6);

  out.sum.assign(kantz_blocks * row_size, 0.0);
  out.count.assign(kantz_blocks * row_size, 0.0);
  // ln rms = ln(mean square) / 2 is summed over the references as the log of products of
  // per-reference mean squares, one product per block and table entry: a log per reference and
  // entry would cost as much as the neighbours. A product is logged every `flush` references of
  // its block within a grid row, or when it approaches under/overflow: every product is checked
  // against 1e-200 / 1e200 after each factor, whatever the interval.
  //
  // Reproducible whatever the thread count (ordered_sum.hpp): a grid row is one unit of work.
  // Its logs and the products left over at its end (RowSums) depend on the row alone, and the
  // rows are merged in row_order, one at a time: the leftover products multiplied into running
  // products (a product logged first when the two would leave [1e-200, 1e200]), the logs added.
  // The counts are integers (exact in any order): per thread, added at the end.
  constexpr std::size_t flush = 32;
  constexpr double tiny = 1e-200, huge = 1e200;
  struct RowSums {
    std::vector<double> sum, product;  // per block and table entry: logs, product left over
    std::vector<std::uint8_t> touched;    // per block: a reference of the row is in it
  };
  std::vector<double> running(out.sum.size(), 1.0);
  nonlinear::OrderedMerge<RowSums> merger(
      [&] {
        return RowSums{std::vector<double>(out.sum.size(), 0.0),
                       std::vector<double>(out.sum.size(), 1.0),
                       std::vector<std::uint8_t>(kantz_blocks, 0)};
      },
      [&](RowSums& row) {
        for (std::size_t b = 0; b < kantz_blocks; ++b) {
          if (!row.touched[b]) continue;
          row.touched[b] = 0;
          for (std::size_t q = b * row_size; q < (b + 1) * row_size; ++q) {
            out.sum[q] += row.sum[q];
            row.sum[q] = 0.0;
            const double p = row.product[q];
            if (p == 1.0) continue;
            row.product[q] = 1.0;
            const double joined = running[q] * p;
            if (joined < tiny || joined > huge) {
              out.sum[q] += 0.5 * std::log(running[q]);
              running[q] = p;
            } else {
              running[q] = joined;
            }
          }
        }
      });
#pragma omp parallel
  {
    // Per-thread counts, merged once at the end: no shared writes in the loop.
    std::vector<double> count(out.count.size(), 0.0);
    std::vector<std::size_t> pending(kantz_blocks, 0);
    // A group of consecutive references: their neighbours and their tables of binned sums.
    const std::size_t table = nr * dims * shape.padded;
    std::vector<NeighbourSums> group(reference_group);
    std::vector<double> bins(reference_group * table), bin_count(reference_group * nr * dims);
    std::vector<double> mean_square(steps);
    std::size_t members = 0, member_own[reference_group] = {};
    RowWindow window;
    // The window's row boundaries (positions of rows low..high in it), and with sparse
    // references the points it holds.
    std::size_t row_first[2 * reach_rows + 2] = {};
    std::vector<std::uint32_t> selected;
    std::vector<double> reference_along;
    // Sparse references (a sample of a long series): the window holds only the points of rows
    // low..high within reach of one of the row's references along the sort axis, the union of
    // their candidate stretches (the test below is the stretch's, so no candidate is lost and
    // the candidates keep their order: the sums are the same), without their histories (see
    // gather_histories). False when the row holds no reference.
    auto select_candidates = [&](std::size_t row, std::size_t low, std::size_t high) {
      reference_along.clear();
      for (std::size_t q = grid.row_begin(row); q < grid.row_begin(row + 1); ++q)
        if (is_reference[sorted[q]]) reference_along.push_back(along_axis[sorted[q]]);
      if (reference_along.empty()) return false;
      selected.clear();
      for (std::size_t u = low; u < high; ++u) {
        row_first[u - low] = selected.size();
        std::size_t k = 0;  // the first reference whose stretch does not end below the point
        for (std::size_t q = grid.row_begin(u); q < grid.row_begin(u + 1); ++q) {
          const double v = along_axis[sorted[q]];
          while (k < reference_along.size() && !(v <= reference_along[k] + reach)) ++k;
          if (k == reference_along.size()) break;
          if (!(v < reference_along[k] - reach)) selected.push_back(sorted[q]);
        }
      }
      row_first[high - low] = selected.size();
      return true;
    };
    for (NeighbourSums& sums : group) {
      sums.head.assign(shape.profile_count() + 1, -1);
      sums.profile_count.assign(shape.profile_count() + 1, 0);
    }
    RowSums row_sums;
    auto log_products = [&](std::size_t block) {
      for (std::size_t q = block * row_size; q < (block + 1) * row_size; ++q) {
        if (row_sums.product[q] == 1.0) continue;  // no factor (or ln 1 = 0)
        row_sums.sum[q] += 0.5 * std::log(row_sums.product[q]);  // ln rms = ln(mean square) / 2
        row_sums.product[q] = 1.0;
      }
      pending[block] = 0;
    };
    // Sampled references: the histories of one reference and its neighbours only, copied into
    // `store` (a whole window's histories, a few per cent of a long series' points at ~4 bytes
    // a history sample, were most of the scan's memory; a group's were still ~100 MB per thread
    // at 10^6 samples). The neighbour lists are renumbered to store positions; their order, and
    // so the sums, stay the same. Returns the reference's store position.
    RowWindow store;
    constexpr std::uint32_t not_stored = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> store_slot;  // per window position: its store position
    std::vector<std::uint32_t> store_points, stored_positions;
    auto gather_histories = [&](std::size_t own, NeighbourSums& sums) {
      if (store_slot.size() < window.count) store_slot.resize(window.count, not_stored);
      store_points.clear();
      stored_positions.clear();
      auto store_position = [&](std::uint32_t w) {
        if (store_slot[w] == not_stored) {
          store_slot[w] = std::uint32_t(store_points.size());
          store_points.push_back(window.index[w]);
          stored_positions.push_back(w);
        }
        return store_slot[w];
      };
      const std::size_t own_position = store_position(std::uint32_t(own));
      for (std::size_t u = 0; u < sums.used; ++u)
        for (std::int32_t p = sums.head[sums.present[u]]; p >= 0; p = sums.next[std::size_t(p)])
          sums.near[std::size_t(p)] = store_position(sums.near[std::size_t(p)]);
      store.fill_histories(shape, x.data(), store_points.data(), store_points.size());
      for (const std::uint32_t w : stored_positions) store_slot[w] = not_stored;
      return own_position;
    };
    // The group's history sums plane by plane (sampled references: reference by reference, each
    // from its own store; each reference's sums are its own, so the order changes nothing),
    // then its tables into the products.
    auto sum_group = [&]() {
      if (every_reference) {
        for (std::size_t c = 0; c < window.planes(); ++c)
          for (std::size_t g = 0; g < members; ++g)
            add_histories(shape, window, member_own[g], c, group[g], bins.data() + g * table,
                          bin_count.data() + g * nr * dims);
      } else {
        for (std::size_t g = 0; g < members; ++g) {
          const std::size_t own = gather_histories(member_own[g], group[g]);
          for (std::size_t c = 0; c < store.planes(); ++c)
            add_histories(shape, store, own, c, group[g], bins.data() + g * table,
                          bin_count.data() + g * nr * dims);
        }
      }
      for (std::size_t g = 0; g < members; ++g) {
        const std::size_t block = block_of(window.index[member_own[g]]);
        row_sums.touched[block] = 1;
        const bool extreme = multiply_mean_squares(
            shape, steps, bins.data() + g * table, bin_count.data() + g * nr * dims,
            mean_square.data(), row_sums.product.data() + block * row_size,
            count.data() + block * row_size);
        if (extreme || ++pending[block] == flush) log_products(block);
      }
      members = 0;
    };
#pragma omp for schedule(dynamic, 1)
    for (std::size_t rank = 0; rank < row_order.size(); ++rank) {
      row_sums = merger.take();
      std::fill(pending.begin(), pending.end(), 0);
      const std::size_t row = row_order[rank];
      // The window: reach_rows rows on either side.
      const std::size_t low = row > reach_rows ? row - reach_rows : 0;
      const std::size_t high = std::min(row + reach_rows + 1, rows);
      const std::size_t base = grid.row_begin(low);
      if (every_reference) {
        window.fill(shape, x.data(), sorted + base, grid.row_begin(high) - base);
        for (std::size_t u = low; u <= high; ++u) row_first[u - low] = grid.row_begin(u) - base;
      } else if (!select_candidates(row, low, high)) {
        merger.give(rank, std::move(row_sums));  // no reference in this row: nothing to add,
        continue;                                // but every unit is given (in-order merge)
      } else {
        window.fill(shape, x.data(), selected.data(), selected.size(), false);
      }
      auto first_of = [&](std::size_t u) { return row_first[u - low]; };
      const double* along = window.columns.data() + std::size_t(shape.axes - 1) * window.stride;
      // Each row's stretch [first, last): the points within reach of the reference along the
      // sort axis; both ends only move forward as the references do.
      Candidates candidates;
      candidates.runs = high - low;
      for (std::size_t u = low; u < high; ++u)
        candidates.first[u - low] = candidates.last[u - low] = first_of(u);
      for (std::size_t own = first_of(row); own < first_of(row + 1); ++own) {
        const double v = along[own];
        for (std::size_t u = low; u < high; ++u) {
          std::size_t& first = candidates.first[u - low];
          std::size_t& last = candidates.last[u - low];
          const std::size_t end = first_of(u + 1);
          while (first < end && along[first] < v - reach) ++first;
          if (last < first) last = first;
          while (last < end && along[last] <= v + reach) ++last;
        }
        if (!is_reference[window.index[own]]) continue;
        std::fill_n(bins.data() + members * table, table, 0.0);
        std::fill_n(bin_count.data() + members * nr * dims, nr * dims, 0.0);
        find_neighbours(shape, window, own, candidates, group[members]);
        member_own[members++] = own;
        if (members == reference_group) sum_group();
      }
      sum_group();
      merger.give(rank, std::move(row_sums));
    }
#pragma omp critical
    for (std::size_t q = 0; q < count.size(); ++q) out.count[q] += count[q];
  }
  // The products left over after the last row.
  for (std::size_t q = 0; q < running.size(); ++q)
    if (running[q] != 1.0) out.sum[q] += 0.5 * std::log(running[q]);
  return out;
}

}  // namespace chatterlab
