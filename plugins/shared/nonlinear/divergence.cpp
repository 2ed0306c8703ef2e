#include "shared/nonlinear/divergence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "shared/nonlinear/ordered_sum.hpp"

namespace chatterlab {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

double median_of(std::vector<double> v) {
  if (v.empty()) return nan;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}
}  // namespace

BlockCurve rosenstein_curve(std::span<const double> x, int dimension, int delay,
                            std::size_t theiler, std::size_t steps, std::size_t stride,
                            std::size_t references) {
  using nonlinear::Embedding;
  const Embedding e(x, dimension, delay);
  const nonlinear::NeighbourSearch search(e);
  const std::size_t n = e.size();
  BlockCurve out;
  out.steps = steps;
  out.sum.assign(kantz_blocks * steps, 0.0);
  out.count.assign(kantz_blocks * steps, 0.0);
  const std::size_t future = (steps - 1) * stride;
  if (n <= future + 10) return out;
  const std::size_t limit = n - future;  // references and neighbours keep the horizon
  references = std::max<std::size_t>(1, std::min(references, limit));
  // References in fixed blocks, merged in block order (ordered_sum.hpp): the same curve
  // whatever the thread count. A block of consecutive references adds to one or two bootstrap
  // blocks' rows: [first, last) of the table, the only part merged and reset.
  struct Partial {
    std::vector<double> sum, count;
    std::size_t first = 0, last = 0;
  };
  nonlinear::OrderedMerge<Partial> merger(
      [&] {
        return Partial{std::vector<double>(out.sum.size(), 0.0),
                       std::vector<double>(out.count.size(), 0.0)};
      },
      [&](Partial& p) {
        for (std::size_t q = p.first; q < p.last; ++q) {
          out.sum[q] += p.sum[q];
          out.count[q] += p.count[q];
          p.sum[q] = p.count[q] = 0;
        }
        p.first = p.last = 0;
      });
  constexpr std::size_t reference_block = 16;
  const std::size_t units = (references + reference_block - 1) / reference_block;
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t unit = 0; unit < units; ++unit) {
    Partial p = merger.take();
    const std::size_t end = std::min(references, (unit + 1) * reference_block);
    for (std::size_t r = unit * reference_block; r < end; ++r) {
      const std::size_t i = std::size_t(double(r) * double(limit) / double(references));
      const std::size_t offset = (i * kantz_blocks / limit) * steps;
      const auto nn = search.nearest(i, 1, theiler, limit);
      if (nn.empty() || !(nn[0].distance > 0)) continue;
      const std::size_t j = nn[0].index;
      if (p.first == p.last) p.first = offset;
      p.last = offset + steps;  // offsets grow with r
      for (std::size_t k = 0; k < steps; ++k) {
        const double d = e.distance(i + k * stride, j + k * stride);
        if (d > 0) {
          p.sum[offset + k] += std::log(d);
          p.count[offset + k] += 1;
        }
      }
    }
    merger.give(unit, std::move(p));
  }
  return out;
}

LinearRegionFit linear_region(const std::vector<double>& y) {
  LinearRegionFit f;
  const std::size_t n = y.size();
  if (n < 4) return f;
  std::vector<double> k(n);
  for (std::size_t i = 0; i < n; ++i) k[i] = double(i);
  const std::size_t tail = std::max<std::size_t>(1, n / 5);
  double saturation = 0;
  for (std::size_t i = n - tail; i < n; ++i) saturation += y[i] / double(tail);
  const double rise = std::max(saturation, *std::max_element(y.begin(), y.end())) - y[0];
  if (!(rise >= std::log(2.0))) {
    // No exponential separation: the exponent is the mean trend, ~0 for quasi-periodic signals.
    f.found = true;
    f.diverging = false;
    f.begin = 0;
    f.end = n;
    const auto line = nonlinear::fit_line(k, y, 0, n);
    f.slope = line.slope;
    f.intercept = line.intercept;
    return f;
  }
  std::size_t stop = n;
  for (std::size_t i = 1; i < n; ++i)
    if (y[i] >= y[0] + 0.8 * rise) {
      stop = i + 1;
      break;
    }
  stop = std::max<std::size_t>(stop, 4);
  // Local slopes over a fifth of the pre-saturation range: flows modulate the divergence rate
  // around each orbit (Lorenz: period ~ 70 samples at dt = 0.01), which a shorter window would
  // mistake for the end of the linear region.
  const std::size_t half = std::max<std::size_t>(1, stop / 10);
  std::vector<bool> usable(n, false);
  for (std::size_t i = 0; i < stop; ++i) usable[i] = true;
  const auto slopes = nonlinear::local_slopes(k, y, usable, half);
  std::vector<double> finite;
  for (double s : slopes)
    if (std::isfinite(s)) finite.push_back(s);
  if (finite.empty()) return f;
  std::nth_element(finite.begin(), finite.begin() + std::ptrdiff_t(finite.size() / 2),
                   finite.end());
  const double median = finite[finite.size() / 2];
  const auto region = nonlinear::find_plateau(k, slopes, 0.1 * std::abs(median),
                                              std::max(2.0, 0.15 * double(stop)));
  if (!region.found) return f;
  f.found = true;
  f.begin = region.begin - half;
  f.end = region.end + half;
  const auto line = nonlinear::fit_line(k, y, f.begin, f.end);
  f.slope = line.slope;
  f.intercept = line.intercept;
  return f;
}

std::size_t curve_stride(int delay, std::size_t horizon, std::size_t min_points) {
  std::size_t best = 1;
  for (std::size_t s = 1; s <= std::size_t(delay); ++s)
    if (std::size_t(delay) % s == 0 && horizon / s >= min_points) best = s;
  return best;
}

std::vector<double> neighbour_distances(std::span<const double> x, int dimension, int delay,
                                        std::size_t theiler, std::size_t limit,
                                        const std::vector<std::size_t>& ks, std::size_t sample) {
  const nonlinear::Embedding e(x, dimension, delay, limit);
  const nonlinear::NeighbourSearch search(e);
  const std::size_t n = e.size();
  // Ask for no more neighbours than a quarter of the vectors.
  const std::size_t kmax = std::min(ks.back(), n / 4);
  sample = std::min(sample, n);
  std::vector<std::vector<double>> distances(ks.size());
#pragma omp parallel for schedule(dynamic, 8)
  for (std::size_t r = 0; r < sample; ++r) {
    if (kmax == 0) continue;
    const auto nn = search.nearest(std::size_t(double(r) * double(n) / double(sample)), kmax,
                                   theiler, n);
#pragma omp critical
    for (std::size_t q = 0; q < ks.size(); ++q) {
      const std::size_t k = ks[q];
      if (k <= kmax && nn.size() >= k) distances[q].push_back(nn[k - 1].distance);
    }
  }
  std::vector<double> out;
  for (auto& d : distances) out.push_back(d.size() * 2 >= sample ? median_of(d) : nan);
  return out;
}

std::vector<double> local_dimensions(const std::vector<double>& distances,
                                     const std::vector<std::size_t>& ks) {
  std::vector<double> out;
  for (std::size_t q = 0; q + 1 < distances.size(); ++q)
    out.push_back(distances[q + 1] > distances[q]
                      ? std::log(double(ks[q + 1]) / double(ks[q])) /
                            std::log(distances[q + 1] / distances[q])
                      : nan);
  return out;
}

std::size_t saturation_horizon(std::span<const double> x, int dimension, int delay,
                               std::size_t theiler, std::size_t horizon, std::size_t min_points) {
  constexpr std::size_t pilot_references = 500;
  const std::size_t stride = curve_stride(delay, horizon, min_points);
  const std::size_t steps = horizon / stride + 1;
  const auto y = rosenstein_curve(x, dimension, delay, theiler, steps, stride, pilot_references)
                     .mean();
  if (!std::all_of(y.begin(), y.end(), [](double v) { return std::isfinite(v); })) return horizon;
  const std::size_t tail = std::max<std::size_t>(1, steps / 5);
  double saturation = 0;
  for (std::size_t k = steps - tail; k < steps; ++k) saturation += y[k] / double(tail);
  // A curve that does not rise by ln 2 saturates nowhere: keep the whole horizon (quasi-periodic
  // motion must show no divergence over a long time, not over 30 samples).
  if (!(saturation - y[0] >= std::log(2.0))) return horizon;
  for (std::size_t k = 1; k < steps; ++k)
    if (y[k] >= y[0] + 0.9 * (saturation - y[0]))
      return std::clamp<std::size_t>(3 * k * stride / 2, 30, horizon);
  return horizon;
}

}  // namespace chatterlab
