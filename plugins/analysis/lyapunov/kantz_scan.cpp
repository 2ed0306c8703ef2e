#include "analysis/lyapunov/kantz_scan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "analysis/nonlinear_common/box_grid.hpp"
#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t minimum_pairs_margin = 100;  // vectors beyond one separation history

}  // namespace

std::vector<double> KantzScan::curve(std::size_t r, int m) const {
  const std::size_t dims = dimensions(), nr = radii.size();
  const std::size_t d = std::size_t(m - min_dimension);
  std::vector<double> y(steps, 0.0), c(steps, 0.0);
  for (std::size_t b = 0; b < kantz_blocks; ++b) {
    const std::size_t row = (b * nr + r) * dims + d;
    for (std::size_t k = 0; k < steps; ++k) {
      y[k] += sum[row * steps + k];
      c[k] += count[row * steps + k];
    }
  }
  for (std::size_t k = 0; k < steps; ++k) y[k] = c[k] > 0 ? y[k] / c[k] : nan;
  return y;
}

namespace {

// What one reference's neighbour pass needs to know about the scan.
struct ScanShape {
  int min_dimension = 1, axes = 1;
  std::size_t dims = 1, radii = 1, step = 1, history = 0, padded = 0, theiler = 0;
  const double* radii2 = nullptr;  // squared radii, ascending
  double floor2 = 0;               // coincident vectors (closer than this) are skipped
};

// Per-thread scratch of one reference's neighbour pass. A neighbour's radius bins in the scanned
// dimensions form a "profile" (r_d per dimension d, nondecreasing, `radii` = beyond the largest);
// neighbours with the same profile are summed into one slot, so each neighbour costs one vector
// add whatever the number of dimensions.
struct NeighbourSums {
  std::vector<std::int32_t> slot_of;     // profile code -> slot, -1 when unused
  std::vector<std::uint32_t> profiles;   // code of each used slot
  std::vector<float> slots;              // slot * padded + t
  std::vector<double> slot_count;
  std::vector<float> separation;         // padded
};

// The neighbours of reference i within the largest radius: each one's squared coordinate
// differences along the whole separation history are added to the slot of its profile. The
// distance in any dimension at any step is a sum of these differences. Single precision: a slot
// sums at most a few thousand positive terms. Compiled for AVX2 as well (chosen at run time),
// which does eight of these adds at once.
[[gnu::target_clones("avx2", "default")]] void gather_neighbours(const ScanShape& s,
                                                                 const nonlinear::BoxGrid& grid,
                                                                 const double* x, std::size_t i,
                                                                 NeighbourSums& sums) {
  const double* xi = x + i;
  const double eps2 = s.radii2[s.radii - 1];
  float* __restrict separation = sums.separation.data();
  std::size_t first[3], last[3];
  const std::size_t runs = grid.runs_near(xi[0], s.axes == 2 ? xi[s.step] : 0.0, first, last);
  const nonlinear::BoxGrid::Entry* entries = grid.entries();
  for (std::size_t run = 0; run < runs; ++run)
    for (std::size_t q = first[run]; q < last[run]; ++q) {
      const nonlinear::BoxGrid::Entry& e = entries[q];
      const std::size_t j = e.index;
      if ((j > i ? j - i : i - j) <= s.theiler) continue;
      double d0 = (e.a - xi[0]) * (e.a - xi[0]);
      if (s.axes == 2) d0 += (e.b - xi[s.step]) * (e.b - xi[s.step]);
      if (d0 > eps2) continue;
      const double* xj = x + j;
      for (int l = s.axes; l < s.min_dimension; ++l) {
        const double dl = xi[std::size_t(l) * s.step] - xj[std::size_t(l) * s.step];
        d0 += dl * dl;
      }
      if (d0 > eps2 || d0 <= s.floor2) continue;
      // Profile: the radius bin in each dimension (distances only grow with the dimension).
      std::uint32_t code = 0, scale = 1;
      std::size_t r = 0;
      for (std::size_t d = 0; d < s.dims; ++d) {
        if (d > 0) {
          const std::size_t extra = (std::size_t(s.min_dimension) + d - 1) * s.step;
          d0 += (xi[extra] - xj[extra]) * (xi[extra] - xj[extra]);
        }
        while (r < s.radii && d0 > s.radii2[r]) ++r;
        code += std::uint32_t(r) * scale;
        scale *= std::uint32_t(s.radii + 1);
      }
      std::int32_t slot = sums.slot_of[code];
      if (slot < 0) {
        slot = std::int32_t(sums.profiles.size());
        sums.slot_of[code] = slot;
        sums.profiles.push_back(code);
        if (sums.slots.size() < sums.profiles.size() * s.padded)
          sums.slots.resize(sums.profiles.size() * s.padded);  // grows to its peak once per thread
        std::fill_n(sums.slots.begin() + std::ptrdiff_t(std::size_t(slot) * s.padded), s.padded,
                    0.0f);
        if (sums.slot_count.size() < sums.profiles.size()) sums.slot_count.resize(sums.profiles.size());
        sums.slot_count[std::size_t(slot)] = 0;
      }
      for (std::size_t t = 0; t < s.history; ++t) {
        const double dt = xi[t] - xj[t];
        separation[t] = float(dt * dt);
      }
      float* __restrict bin = sums.slots.data() + std::size_t(slot) * s.padded;
      for (std::size_t t = 0; t < s.padded; ++t) bin[t] += separation[t];
      sums.slot_count[std::size_t(slot)] += 1;
    }
}

}  // namespace

KantzScan kantz_scan(const std::vector<double>& x, int min_dimension, int max_dimension, int delay,
                     std::size_t theiler, std::size_t steps, std::size_t references,
                     std::vector<double> radii) {
  KantzScan out;
  if (min_dimension < 1 || max_dimension < min_dimension || delay < 1 || steps < 1 ||
      radii.empty())
    throw PointFailure("kantz_scan: needs 1 <= min_dimension <= max_dimension, delay >= 1, "
                       "steps >= 1 and at least one radius");
  std::sort(radii.begin(), radii.end());
  if (!(radii.front() > 0)) throw PointFailure("kantz_scan: radii must be positive");
  const std::size_t span = std::size_t(max_dimension - 1) * std::size_t(delay);
  const std::size_t history = steps + span;  // samples of a separation history
  if (x.size() < history + minimum_pairs_margin)
    throw PointFailure(fmt::format("kantz_scan: {} samples are too few for {} steps in {} "
                                   "dimensions (need at least {})",
                                   x.size(), steps, max_dimension, history + minimum_pairs_margin));
  // Vectors with `steps` of future in max_dimension: references and neighbours alike.
  const std::size_t limit = x.size() - history + 1;
  references = references == 0 ? limit : std::min(references, limit);
  out.min_dimension = min_dimension;
  out.max_dimension = max_dimension;
  out.radii = radii;
  out.steps = steps;
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
  shape.history = history;
  shape.padded = (history + 7) / 8 * 8;
  shape.theiler = theiler;
  shape.radii2 = radii2.data();
  shape.floor2 = std::pow(1e-9 * (*hi - *lo), 2);
  const nonlinear::BoxGrid grid(x, delay, shape.axes, limit, radii.back());
  std::size_t profile_codes = 1;
  for (std::size_t d = 0; d < dims; ++d) profile_codes *= nr + 1;
  if (profile_codes > (std::size_t(1) << 24))
    throw PointFailure(fmt::format("kantz_scan: {} radii x {} dimensions are too many (at most "
                                   "(radii + 1)^dimensions = 2^24 combinations)",
                                   nr, dims));

  // References are visited box by box, so that consecutive ones share their neighbours (which
  // then stay in cache); each keeps the bootstrap block of its time index.
  std::vector<std::uint32_t> order(references);
  std::vector<std::uint64_t> keyed(references);
  for (std::size_t r = 0; r < references; ++r) {
    const std::size_t i =
        references == limit ? r : std::size_t(double(r) * double(limit) / double(references));
    const std::size_t box = grid.cell(x[i], shape.axes == 2 ? x[i + shape.step] : 0.0);
    keyed[r] = (std::uint64_t(box) << 32) | std::uint64_t(i);
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t r = 0; r < references; ++r) order[r] = std::uint32_t(keyed[r] & 0xffffffffu);
  auto block_of = [&](std::size_t i) { return i * kantz_blocks / limit; };

  out.sum.assign(kantz_blocks * row_size, 0.0);
  out.count.assign(kantz_blocks * row_size, 0.0);
  // Products of per-reference mean square distances, one per block and table entry, are logged
  // every `flush` references of the block (a log per reference and entry would cost as much as
  // the neighbours) or when they approach under/overflow.
  constexpr std::size_t flush = 8;
#pragma omp parallel
  {
    // Per-thread accumulators, merged once at the end: no shared writes in the loop.
    std::vector<double> sum(out.sum.size(), 0.0), count(out.count.size(), 0.0);
    std::vector<double> product(out.sum.size(), 1.0), factors(out.sum.size(), 0.0);
    std::vector<std::size_t> pending(kantz_blocks, 0);
    std::vector<float> bins(nr * dims * shape.padded);
    std::vector<double> bin_count(nr * dims), running(shape.padded);
    NeighbourSums sums;
    sums.slot_of.assign(profile_codes, -1);
    sums.separation.assign(shape.padded, 0.0f);
    auto log_products = [&](std::size_t block) {
      for (std::size_t q = block * row_size; q < (block + 1) * row_size; ++q) {
        if (factors[q] == 0) continue;
        sum[q] += 0.5 * std::log(product[q]);  // ln rms = ln(mean square) / 2
        count[q] += factors[q];
        product[q] = 1.0;
        factors[q] = 0.0;
      }
      pending[block] = 0;
    };
#pragma omp for schedule(dynamic, 32)
    for (std::size_t r = 0; r < references; ++r) {
      const std::size_t i = order[r];
      const std::size_t block = block_of(i);
      std::fill(bins.begin(), bins.end(), 0.0f);
      std::fill(bin_count.begin(), bin_count.end(), 0.0);
      gather_neighbours(shape, grid, x.data(), i, sums);
      // Each profile's sums go to the bin of its radius in every dimension where it is within the
      // largest radius.
      for (std::size_t slot = 0; slot < sums.profiles.size(); ++slot) {
        std::uint32_t code = sums.profiles[slot];
        sums.slot_of[code] = -1;
        const float* from = sums.slots.data() + slot * shape.padded;
        for (std::size_t d = 0; d < dims; ++d, code /= std::uint32_t(nr + 1)) {
          const std::size_t ri = code % (nr + 1);
          if (ri == nr) break;
          float* to = bins.data() + (ri * dims + d) * shape.padded;
          for (std::size_t t = 0; t < shape.padded; ++t) to[t] += from[t];
          bin_count[ri * dims + d] += sums.slot_count[slot];
        }
      }
      sums.profiles.clear();
      // Neighbours within radius r are those of bins 0..r: running sums over the radii.
      bool extreme = false;
      for (std::size_t d = 0; d < dims; ++d) {
        const std::size_t m = std::size_t(min_dimension) + d;
        std::fill(running.begin(), running.end(), 0.0);
        double n = 0;
        for (std::size_t ri = 0; ri < nr; ++ri) {
          const float* bin = bins.data() + (ri * dims + d) * shape.padded;
          for (std::size_t t = 0; t < history; ++t) running[t] += double(bin[t]);
          n += bin_count[ri * dims + d];
          if (n == 0) continue;
          const std::size_t row = block * row_size + (ri * dims + d) * steps;
          for (std::size_t k = 0; k < steps; ++k) {
            double mean_square = 0;  // < |X_{i+k} - X_{j+k}|^2 >_j in m dimensions
            for (std::size_t l = 0; l < m; ++l) mean_square += running[k + l * shape.step];
            mean_square /= n;
            if (!(mean_square > 0)) continue;
            product[row + k] *= mean_square;
            factors[row + k] += 1;
            extreme = extreme || product[row + k] < 1e-200 || product[row + k] > 1e200;
          }
        }
      }
      if (extreme || ++pending[block] == flush) log_products(block);
    }
    for (std::size_t b = 0; b < kantz_blocks; ++b) log_products(b);
#pragma omp critical
    for (std::size_t q = 0; q < sum.size(); ++q) {
      out.sum[q] += sum[q];
      out.count[q] += count[q];
    }
  }
  return out;
}

}  // namespace chatterlab
