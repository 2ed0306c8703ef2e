#include "analysis/lyapunov/lyapunov.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include "analysis/embedding/embedding.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"

namespace chatterlab {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
// Embedding dimensions m, m + 1, m + 2: deterministic divergence has the same slope in all of
// them (m embeds the attractor), so their spread is part of the uncertainty.
constexpr int scanned_dimensions = 3;
// Neighbourhood sizes: the median distance (dimension m + 1) to the k-th nearest neighbour for
// these k, a factor 2.5 in neighbour count apart (for D2 = 1.2 a factor 2.1 in eps, for D2 = 2 a
// factor 1.6): from a few neighbours to a few hundred, so that some lie above a noise scale.
constexpr std::size_t radius_neighbours[] = {4, 10, 25, 60, 150, 400};
// The exponent comes from the smallest admissible sizes of each dimension (the longest linear
// regions; larger neighbourhoods are there to rise above noise): this many of them.
constexpr std::size_t estimate_radii = 2;
constexpr std::size_t radius_count = std::size(radius_neighbours);
constexpr std::size_t radius_sample = 300;  // references whose neighbour distances set the radii
// Nearest-neighbour (Rosenstein) curves follow at most this many references: their search is a
// k-d tree query per reference, nearly a linear scan in 8 or more dimensions, and they are the
// second method beside Kantz's (whose scan does not need it).
constexpr std::size_t rosenstein_references = 2000;
constexpr std::size_t min_curve_points = 96;  // points per curve when the stride is chosen
// Two curves of neighbouring sizes are parallel when, in the middle of their common linear
// region, at least half of their initial separation remains (deterministic divergence keeps
// it; noise, which separates neighbours within a step whatever their distance, does not).
constexpr double parallel_fraction = 0.5;
// A neighbourhood scale whose local dimension exceeds that in fewer dimensions, or that at larger
// scales, by more than this is dominated by noise (which fills every direction).
constexpr double noise_dimension_excess = 0.5;
// Admissible slopes further apart than this fraction of their median: no common exponent.
constexpr double max_relative_spread = 0.5;
// "good" needs a 95 % interval no wider than +-25 % of the value, ...
constexpr double good_relative_half_width = 0.25;
// ... at least this many reference points with neighbours at every admissible radius, ...
constexpr double good_references = 500;
// ... and a series covering at least this many e-folding times 1 / lambda.
constexpr double good_e_foldings = 100;

// A curve that is usable needs neighbours for at least this share of the references.
constexpr double usable_reference_share = 0.2;
constexpr double usable_references = 50;
}  // namespace

// ---------------------------------------------------------------- curves and regions
BlockCurve rosenstein_curve(const std::vector<double>& x, int dimension, int delay,
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
#pragma omp parallel
  {
    std::vector<double> sum(out.sum.size(), 0.0), count(out.count.size(), 0.0);
#pragma omp for schedule(dynamic, 16)
    for (std::size_t r = 0; r < references; ++r) {
      const std::size_t i = std::size_t(double(r) * double(limit) / double(references));
      const std::size_t offset = (i * kantz_blocks / limit) * steps;
      const auto nn = search.nearest(i, 1, theiler, limit);
      if (nn.empty() || !(nn[0].distance > 0)) continue;
      const std::size_t j = nn[0].index;
      for (std::size_t k = 0; k < steps; ++k) {
        const double d = e.distance(i + k * stride, j + k * stride);
        if (d > 0) {
          sum[offset + k] += std::log(d);
          count[offset + k] += 1;
        }
      }
    }
#pragma omp critical
    for (std::size_t k = 0; k < sum.size(); ++k) {
      out.sum[k] += sum[k];
      out.count[k] += count[k];
    }
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

namespace {

// One divergence curve of the scan with its fit and why it counts or not.
struct CurveResult {
  std::string method;  // "Kantz" or "Rosenstein"
  int dimension = 0;
  double radius = nan;  // Kantz: eps; Rosenstein: none
  BlockCurve data;
  std::vector<double> curve;
  LinearRegionFit fit;
  nonlinear::Interval ci{nan, nan};  // bootstrap of the slope over the fixed region
  double references = 0;             // with a neighbour at k = 0
  bool usable = false;               // enough references with neighbours, a complete curve
  bool parallel = false;             // Kantz: stays apart from a neighbouring radius
  bool collapsed = false;            // Kantz: joins the curve of the next radius (noise)
  bool admissible = false;
  bool selected = false;             // one of the curves the estimate is taken from
  std::string note;                  // why not admissible
};

// Fits the linear region of c's mean curve and bootstraps its slope (region fixed). Slopes and
// their interval are converted to per sample (a curve point is `stride` samples).
void fit_curve(CurveResult& c, std::size_t stride, std::size_t replicates, std::uint64_t seed,
               double min_references) {
  c.curve = c.data.mean();
  c.references = c.data.references_at_start();
  const bool complete =
      std::all_of(c.curve.begin(), c.curve.end(), [](double v) { return std::isfinite(v); });
  c.usable = complete && c.references >= min_references;
  if (!c.usable) {
    c.note = complete ? fmt::format("neighbours for only {:.0f} reference points", c.references)
                      : "no neighbours at some step";
    return;
  }
  c.fit = linear_region(c.curve);
  if (!c.fit.found) {
    c.note = "no linear region";
    return;
  }
  std::vector<double> k(c.curve.size());
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = double(i);
  const auto& fit = c.fit;
  const BlockCurve& data = c.data;
  c.ci = nonlinear::block_bootstrap(kantz_blocks, replicates, seed,
                                    [&](const std::vector<double>& w) {
                                      const auto y = data.mean(w);
                                      return nonlinear::fit_line(k, y, fit.begin, fit.end).slope;
                                    });
  c.fit.slope /= double(stride);
  c.ci.low /= double(stride);
  c.ci.high /= double(stride);
}

double median_of(std::vector<double> v) {
  if (v.empty()) return nan;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// Kantz curves of neighbouring radii (same dimension) are parallel over their common linear
// region: the separation between them at its middle keeps at least parallel_fraction of the
// initial one.
// Returns the remaining fraction of the initial separation (NaN when the two have no common
// diverging linear region).
double separation_kept(const CurveResult& a, const CurveResult& b) {
  const auto& fa = a.fit;
  const auto& fb = b.fit;
  if (!(fa.found && fb.found && fa.diverging && fb.diverging)) return nan;
  const std::size_t begin = std::max(fa.begin, fb.begin), end = std::min(fa.end, fb.end);
  if (end <= begin) return nan;
  const std::size_t mid = (begin + end - 1) / 2;
  const double initial = b.curve[0] - a.curve[0];
  return initial > 0 ? (b.curve[mid] - a.curve[mid]) / initial : nan;
}

// Median distance (Euclidean, dimension `dimension`) to the k-th nearest neighbour for each k of
// radius_neighbours (NaN where fewer neighbours exist), over radius_sample references.
std::vector<double> neighbour_distances(const std::vector<double>& x, int dimension, int delay,
                                        std::size_t theiler, std::size_t limit) {
  const nonlinear::Embedding e(x, dimension, delay, limit);
  const nonlinear::NeighbourSearch search(e);
  const std::size_t n = e.size();
  // Ask for no more neighbours than a quarter of the vectors.
  const std::size_t kmax = std::min(radius_neighbours[radius_count - 1], n / 4);
  const std::size_t sample = std::min(radius_sample, n);
  std::vector<std::vector<double>> distances(radius_count);
#pragma omp parallel for schedule(dynamic, 8)
  for (std::size_t r = 0; r < sample; ++r) {
    if (kmax == 0) continue;
    const auto nn = search.nearest(std::size_t(double(r) * double(n) / double(sample)), kmax,
                                   theiler, n);
#pragma omp critical
    for (std::size_t q = 0; q < radius_count; ++q) {
      const std::size_t k = radius_neighbours[q];
      if (k <= kmax && nn.size() >= k) distances[q].push_back(nn[k - 1].distance);
    }
  }
  std::vector<double> out;
  for (auto& d : distances) out.push_back(d.size() * 2 >= sample ? median_of(d) : nan);
  return out;
}

// Local dimension between neighbour counts k_q and k_{q+1}: ln(k ratio) / ln(distance ratio).
std::vector<double> local_dimensions(const std::vector<double>& distances) {
  std::vector<double> out;
  for (std::size_t q = 0; q + 1 < distances.size(); ++q)
    out.push_back(distances[q + 1] > distances[q]
                      ? std::log(double(radius_neighbours[q + 1]) / double(radius_neighbours[q])) /
                            std::log(distances[q + 1] / distances[q])
                      : nan);
  return out;
}

// The horizon the curves need: 1.5 x the time the nearest-neighbour (Rosenstein) curve takes to
// make 90 % of its rise, from a quick pass over `pilot_references` references up to `horizon`
// (at least 30 samples). The smallest Kantz neighbourhoods saturate about as late; a longer
// horizon only coarsens the curves (a fixed number of points).
std::size_t saturation_horizon(const std::vector<double>& x, int dimension, int delay,
                               std::size_t theiler, std::size_t horizon) {
  constexpr std::size_t pilot_references = 500;
  const std::size_t stride = curve_stride(delay, horizon, min_curve_points);
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

}  // namespace

PluginInfo LyapunovAnalysis::info() {
  PluginInfo info;
  info.name = "lyapunov";
  info.description =
      "largest Lyapunov exponent from Kantz's and Rosenstein's divergence curves over three "
      "embedding dimensions and five neighbourhood sizes; reported only where they show a "
      "common exponential divergence; per sample and per second";
  info.models_md_ids = "N3, N4";
  using nonlinear::numeric_spec;
  info.params = {
      nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
      numeric_spec("max_steps", ValueKind::integer, "samples",
                   "how far the divergence curves follow the neighbours (absent: max(30, 100 x "
                   "delay), at most a quarter of the series)",
                   Json(), 4),
      numeric_spec("max_reference_points", ValueKind::integer, "1",
                   "reference vectors whose neighbours are followed (evenly spread)", 5000, 20),
      numeric_spec("radius", ValueKind::real, "signal unit",
                   "middle of the five Kantz neighbourhood sizes eps (factor 2 apart; absent: "
                   "median distances to the 4th, 12th, 36th, 108th and 324th nearest neighbour)",
                   Json(), 0, std::numeric_limits<double>::infinity(), true),
      nonlinear::bootstrap_spec(), nonlinear::seed_spec()};
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_reference_points", 200}};
  return info;
}

Json LyapunovAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const std::string name = series.name.empty() ? std::string("series") : series.name;
  const int m0 = embedding.dimension, tau = embedding.delay;
  const std::size_t samples = x.size();
  // The divergence horizon in samples and the dimensions the series can hold with it: at least
  // minimum_vectors vectors beyond the embedding window and the horizon.
  const auto given_steps = nonlinear::given_integer(params_, "max_steps");
  int m_max = m0 + scanned_dimensions - 1;
  auto room = [&](int m) {  // samples left for references after the embedding window
    const std::size_t window = std::size_t(m - 1) * std::size_t(tau) + nonlinear::minimum_vectors;
    return samples > window ? samples - window : 0;
  };
  while (m_max > m0 && room(m_max) < 4 * 30) --m_max;
  std::size_t horizon = given_steps ? std::size_t(*given_steps)
                                    : std::min<std::size_t>(std::max(30, 100 * tau),
                                                            room(m_max) / 4);
  if (given_steps && horizon > room(m_max))
    throw InputError(fmt::format(
        "{}: max_steps = {}: {} samples leave only {} vectors beyond the embedding window of "
        "dimension {} with delay {} samples; at most {} steps",
        name, horizon, samples, room(m_max), m_max, tau, room(m_max)));
  horizon = std::max<std::size_t>(horizon, 4);
  if (!given_steps) horizon = saturation_horizon(x, m0, tau, embedding.theiler, horizon);
  const std::size_t stride = curve_stride(tau, horizon, min_curve_points);
  const std::size_t steps = horizon / stride + 1;
  const auto references = std::size_t(params_.integer("max_reference_points"));
  const auto replicates = std::size_t(params_.integer("bootstrap_replicates"));
  const auto seed = std::uint64_t(params_.integer("seed"));
  const double dt = series.sample_interval;
  const std::string unit = series.sample_unit;

  // Neighbourhood sizes, then Kantz's curves for all of them and the dimensions at once.
  const std::size_t history = (steps - 1) * stride + std::size_t(m_max - 1) * std::size_t(tau);
  const std::size_t limit = samples - history;
  std::vector<double> radii;
  std::vector<std::size_t> radius_scale;  // index into radius_neighbours of each radius
  if (const auto given = nonlinear::given_real(params_, "radius")) {
    for (int q = -2; q <= 2; ++q) radii.push_back(*given * std::ldexp(1.0, q));
  } else {
    const auto distances =
        neighbour_distances(x, std::min(m0 + 1, m_max), tau, embedding.theiler, limit);
    for (std::size_t q = 0; q < distances.size(); ++q)
      if (std::isfinite(distances[q]) && distances[q] > 0 &&
          (radii.empty() || distances[q] > radii.back() * 1.05)) {
        radii.push_back(distances[q]);
        radius_scale.push_back(q);
      }
  }
  if (radii.empty())
    throw PointFailure(fmt::format("{}: no neighbours outside the Theiler window ({} samples)",
                                   name, embedding.theiler));
  const auto scan =
      kantz_scan(x, m0, m_max, tau, embedding.theiler, steps, references, radii, stride);
  // Local dimensions at the scan's scales in the lowest and highest dimension: noise fills every
  // added dimension (the local dimension grows with m), a deterministic attractor does not.
  const auto low_dims = local_dimensions(neighbour_distances(x, m0, tau, embedding.theiler, limit));
  const auto high_dims =
      m_max > m0 ? local_dimensions(neighbour_distances(x, m_max, tau, embedding.theiler, limit))
                 : low_dims;
  // Scale q is noise-dominated when its local dimension grows with the embedding dimension or
  // exceeds that of every larger scale by more than noise_dimension_excess.
  auto noisy_scale = [&](std::size_t q) {
    if (q >= low_dims.size() || !std::isfinite(low_dims[q])) return false;
    double larger = std::numeric_limits<double>::infinity();
    for (std::size_t p = q + 1; p < low_dims.size(); ++p)
      if (std::isfinite(low_dims[p])) larger = std::min(larger, low_dims[p]);
    const double growth = std::isfinite(high_dims[q]) ? high_dims[q] - low_dims[q] : 0.0;
    return growth > noise_dimension_excess ||
           (std::isfinite(larger) && low_dims[q] - larger > noise_dimension_excess);
  };
  const double min_references =
      std::max(usable_references, usable_reference_share * double(scan.references));

  std::vector<CurveResult> kantz;  // [r * dims + d]
  const std::size_t dims = std::size_t(m_max - m0 + 1);
  for (std::size_t r = 0; r < radii.size(); ++r)
    for (int m = m0; m <= m_max; ++m) {
      CurveResult c;
      c.method = "Kantz";
      c.dimension = m;
      c.radius = radii[r];
      c.data = scan.block_curve(r, m);
      fit_curve(c, stride, replicates, seed + kantz.size(), min_references);
      kantz.push_back(std::move(c));
    }
  auto at = [&](std::size_t r, std::size_t d) -> CurveResult& { return kantz[r * dims + d]; };
  for (std::size_t d = 0; d < dims; ++d)
    for (std::size_t r = 0; r + 1 < radii.size(); ++r) {
      if (!at(r, d).usable || !at(r + 1, d).usable) continue;
      const double kept = separation_kept(at(r, d), at(r + 1, d));
      if (kept >= parallel_fraction)
        at(r, d).parallel = at(r + 1, d).parallel = true;
      else if (kept < parallel_fraction)
        at(r, d).collapsed = true;
    }
  std::vector<CurveResult> rosenstein;
  for (int m = m0; m <= m_max; ++m) {
    CurveResult c;
    c.method = "Rosenstein";
    c.dimension = m;
    c.data = rosenstein_curve(x, m, tau, embedding.theiler, steps, stride,
                              std::min(references, rosenstein_references));
    fit_curve(c, stride, replicates, seed + 1000 + std::size_t(m),
              std::min(min_references, usable_reference_share * double(rosenstein_references)));
    rosenstein.push_back(std::move(c));
  }

  // What the curves show. "none": every usable curve rises by less than ln 2 (no exponential
  // separation); "exponential": parallel curves with a common slope; else undetermined.
  std::size_t usable = 0, diverging = 0;
  for (const auto& c : kantz) {
    usable += c.usable;
    diverging += c.usable && c.fit.found && c.fit.diverging;
  }
  // No divergence: in every dimension the curve of the smallest usable neighbourhood rises by
  // less than ln 2 over the whole horizon (larger neighbourhoods may wobble: a too small
  // dimension folds the attractor, and the curvature of a torus moves their mean distance).
  bool flat = usable > 0;
  for (std::size_t d = 0; d < dims; ++d)
    for (std::size_t r = 0; r < radii.size(); ++r)
      if (at(r, d).usable) {
        flat = flat && at(r, d).fit.found && !at(r, d).fit.diverging;
        break;
      }
  std::vector<double> slopes;  // of the selected curves
  std::vector<int> admissible_dims;
  std::size_t admissible_radii_mask = 0;
  for (std::size_t d = 0; d < dims; ++d) {
    std::size_t selected = 0;
    for (std::size_t r = 0; r < radii.size(); ++r) {
      CurveResult& c = at(r, d);
      if (!c.usable || !c.fit.found) continue;
      if (!c.fit.diverging) {
        c.note = "rises by less than ln 2";
      } else if (!c.parallel) {
        c.note = c.collapsed ? "joins the curve of the next neighbourhood size (noise scale)"
                             : "not parallel to the curve of a neighbouring size";
      } else if (c.fit.end - c.fit.begin < 3) {
        c.note = "linear region shorter than 3 points";
      } else {
        c.admissible = true;
        if (selected++ < estimate_radii) {
          c.selected = true;
          slopes.push_back(c.fit.slope);
          if (std::find(admissible_dims.begin(), admissible_dims.end(), c.dimension) ==
              admissible_dims.end())
            admissible_dims.push_back(c.dimension);
          admissible_radii_mask |= std::size_t(1) << r;
        } else {
          c.note = "admissible; larger than the sizes the estimate uses";
        }
      }
    }
  }
  // A noise floor: in some dimension the curves of the smallest sizes join those of the next
  // size, while a larger size shows parallel divergence (neighbours closer than the noise
  // separate at once).
  bool noise_floor = false;
  double noise_radius = nan;
  // Local dimensions at the selected scales.
  bool noise_scale = false;
  double noise_scale_radius = nan, noise_scale_dimension = nan;
  for (std::size_t r = 0; r < radius_scale.size(); ++r) {
    bool used = false;
    for (std::size_t d = 0; d < dims; ++d) used = used || at(r, d).selected;
    if (used && noisy_scale(radius_scale[r]) && !noise_scale) {
      noise_scale = true;
      noise_scale_radius = radii[r];
      noise_scale_dimension = low_dims[radius_scale[r]];
    }
  }
  for (std::size_t d = 0; d < dims; ++d) {
    std::size_t first_admissible = radii.size();
    for (std::size_t r = 0; r < radii.size(); ++r)
      if (at(r, d).admissible) {
        first_admissible = r;
        break;
      }
    for (std::size_t r = 0; r < first_admissible && first_admissible < radii.size(); ++r)
      if (at(r, d).collapsed) {
        noise_floor = true;
        noise_radius = std::isfinite(noise_radius) ? std::max(noise_radius, radii[r]) : radii[r];
      }
  }
  for (std::size_t d = 0; d < dims; ++d) {
    CurveResult& c = rosenstein[d];
    if (!c.usable || !c.fit.found) continue;
    std::size_t first = radii.size();
    for (std::size_t r = 0; r < radii.size(); ++r)
      if (at(r, d).usable) {
        first = r;
        break;
      }
    bool floor_below = false;
    for (std::size_t r = first; r < radii.size() && !at(r, d).admissible; ++r)
      floor_below = floor_below || at(r, d).collapsed;
    if (!c.fit.diverging)
      c.note = "rises by less than ln 2";
    else if (first == radii.size() || floor_below)
      c.note = "nearest neighbours lie below the noise scale of the Kantz curves";
    else
      c.admissible = c.selected = true;
  }

  auto per_unit = [&](double v) { return v / dt; };
  auto rate = [&](double per_sample, bool in_unit) {
    return in_unit ? fmt::format("{:.4g} per {}", per_unit(per_sample), unit)
                   : fmt::format("{:.4g} per sample", per_sample);
  };
  int admissible_radius_count = 0;
  for (std::size_t r = 0; r < radii.size(); ++r)
    admissible_radius_count += (admissible_radii_mask >> r) & 1;

  // The headline and the per-method estimates, each as (value, low, high, quality, reason) per
  // sample; the reasons are built twice, once per unit, so that no reason mixes units.
  struct Estimate {
    double value = nan, low = nan, high = nan;
    std::string quality = "failed";
    std::function<std::string(bool)> reason;
  };
  Estimate head, kantz_estimate, rosenstein_estimate;
  std::string divergence = "undetermined";
  std::vector<double> rosenstein_slopes;
  for (const auto& c : rosenstein)
    if (c.admissible) rosenstein_slopes.push_back(c.fit.slope);
  const double steps_samples = double(stride);
  auto region_text = [&](const CurveResult& c) {
    return fmt::format("samples {:.0f}-{:.0f}", double(c.fit.begin) * steps_samples,
                       double(c.fit.end - 1) * steps_samples);
  };
  if (usable == 0) {
    const std::string why = fmt::format(
        "not determined: too few neighbours (fewer than {:.0f} of {} reference points have a "
        "neighbour within the largest radius {:.3g})",
        min_references, scan.references, radii.back());
    head.reason = [why](bool) { return why; };
    kantz_estimate = rosenstein_estimate = head;
  } else if (flat) {
    // No exponential separation anywhere: the largest exponent is not positive.
    divergence = "none";
    std::vector<double> trends;
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (const auto& c : kantz)
      if (c.usable && c.fit.found && !c.fit.diverging) {
        trends.push_back(c.fit.slope);
        low = std::min(low, std::isfinite(c.ci.low) ? c.ci.low : c.fit.slope);
        high = std::max(high, std::isfinite(c.ci.high) ? c.ci.high : c.fit.slope);
      }
    head.value = median_of(trends);
    head.low = std::min(low, 0.0);
    head.high = std::max(high, 0.0);
    head.quality = "good";
    const std::size_t n_trends = trends.size();
    head.reason = [=, &rate](bool in_unit) {
      return fmt::format(
          "no exponential divergence: the curves of the smallest neighbourhoods rise by less "
          "than ln 2 over {:.0f} samples (periodic or quasi-periodic motion: largest exponent "
          "0); mean trend of {} flat curves {}",
          double(steps - 1) * steps_samples, n_trends, rate(head.value, in_unit));
    };
    kantz_estimate = head;
    rosenstein_estimate = head;
    std::vector<double> rtrends;
    for (const auto& c : rosenstein)
      if (c.usable && c.fit.found) rtrends.push_back(c.fit.slope);
    rosenstein_estimate.value = median_of(rtrends);
  } else if (slopes.empty()) {
    std::string why = "not determined: no exponential divergence common to neighbourhood sizes";
    why += diverging > 0
               ? fmt::format(
                     " ({} of {} usable Kantz curves have a linear region, none stays parallel to "
                     "the curve of a neighbouring size: neighbours separate within the first "
                     "steps whatever their distance, as in noise or a linear stochastic process)",
                     diverging, usable)
               : fmt::format(" (none of the {} usable Kantz curves has a linear region)", usable);
    head.reason = [why](bool) { return why; };
    kantz_estimate = rosenstein_estimate = head;
  } else {
    const double median = median_of(slopes);
    const auto [lo_it, hi_it] = std::minmax_element(slopes.begin(), slopes.end());
    const double spread = (*hi_it - *lo_it) / std::abs(median);
    if (admissible_dims.size() < std::min<std::size_t>(2, dims) || spread > max_relative_spread) {
      const double lo = *lo_it, hi = *hi_it;
      const std::size_t n_dims = admissible_dims.size();
      head.reason = [=, &rate](bool in_unit) {
        return fmt::format(
            "not determined: the admissible Kantz slopes range from {} to {} ({} curves in {} "
            "of {} embedding dimensions): no exponent common to dimensions and neighbourhood "
            "sizes",
            rate(lo, in_unit), rate(hi, in_unit), slopes.size(), n_dims, dims);
      };
      kantz_estimate = rosenstein_estimate = head;
    } else {
      divergence = "exponential";
      double low = std::numeric_limits<double>::infinity(), high = -low;
      double min_refs = std::numeric_limits<double>::infinity();
      std::size_t region_begin = 0, region_end = 0;
      for (const auto& c : kantz)
        if (c.selected) {
          low = std::min(low, std::isfinite(c.ci.low) ? c.ci.low : c.fit.slope);
          high = std::max(high, std::isfinite(c.ci.high) ? c.ci.high : c.fit.slope);
          min_refs = std::min(min_refs, c.references);
        }
      const CurveResult* central = nullptr;  // the selected curve closest to the median
      for (const auto& c : kantz)
        if (c.selected &&
            (!central || std::abs(c.fit.slope - median) < std::abs(central->fit.slope - median)))
          central = &c;
      region_begin = central->fit.begin;
      region_end = central->fit.end;
      kantz_estimate.value = median;
      kantz_estimate.low = low;
      kantz_estimate.high = high;
      // The headline interval also spans Rosenstein's admissible estimates.
      double all_low = low, all_high = high;
      for (const auto& c : rosenstein)
        if (c.admissible) {
          all_low = std::min(all_low, std::isfinite(c.ci.low) ? c.ci.low : c.fit.slope);
          all_high = std::max(all_high, std::isfinite(c.ci.high) ? c.ci.high : c.fit.slope);
        }
      head.value = median;
      head.low = all_low;
      head.high = all_high;
      // Quality: consistent, precise, noise-free down to the smallest neighbourhood and long
      // enough a series.
      std::vector<std::string> doubts;
      const double half_width = 0.5 * (all_high - all_low) / std::abs(median);
      if (!(median > 0)) doubts.push_back("the slope is not positive");
      if (half_width > good_relative_half_width)
        doubts.push_back(fmt::format("the interval is +-{:.0f} % wide", 100 * half_width));
      if (noise_floor)
        doubts.push_back(fmt::format(
            "neighbours closer than {:.3g} separate at once (measurement or dynamical noise), "
            "which biases the slope of the larger neighbourhoods low",
            noise_radius));
      if (noise_scale)
        doubts.push_back(fmt::format(
            "at the neighbourhood size {:.3g} the local dimension is {:.2g} and grows with the "
            "embedding dimension or towards smaller scales: noise dominates there, which biases "
            "the slope low",
            noise_scale_radius, noise_scale_dimension));
      if (min_refs < good_references)
        doubts.push_back(fmt::format("only {:.0f} reference points have neighbours", min_refs));
      if (median > 0 && double(samples) * median < good_e_foldings)
        doubts.push_back(fmt::format(
            "the series covers only {:.0f} e-folding times 1/lambda (at least {:.0f} wanted)",
            double(samples) * median, good_e_foldings));
      if (admissible_dims.size() < dims)
        doubts.push_back(fmt::format("only {} of {} embedding dimensions show it",
                                     admissible_dims.size(), dims));
      head.quality = doubts.empty() ? "good" : "uncertain";
      kantz_estimate.quality = head.quality;
      const std::string doubt_text =
          doubts.empty() ? "" : fmt::format("; uncertain: {}", fmt::join(doubts, "; "));
      const std::size_t n_slopes = slopes.size();
      const double lo = *lo_it, hi = *hi_it;
      const std::string region = region_text(*central);
      const int radius_count_admissible = admissible_radius_count;
      const std::size_t n_dims = admissible_dims.size();
      const auto r_median = median_of(rosenstein_slopes);
      const std::size_t n_rosenstein = rosenstein_slopes.size();
      head.reason = [=, &rate](bool in_unit) {
        std::string text = fmt::format(
            "exponential divergence: median slope of {} parallel Kantz curves (the smallest "
            "admissible neighbourhood sizes, {} dimensions x {} sizes; slopes {} to {}; linear "
            "region e.g. {})",
            n_slopes, n_dims, radius_count_admissible, rate(lo, in_unit), rate(hi, in_unit),
            region);
        text += n_rosenstein > 0
                    ? fmt::format("; Rosenstein {} (median of {} dimensions)",
                                  rate(r_median, in_unit), n_rosenstein)
                    : "; Rosenstein not admissible";
        text += "; interval: all admissible curves' 95 % bootstrap intervals (dimensions, sizes, "
                "regions, methods)";
        return text + doubt_text;
      };
      kantz_estimate.reason = head.reason;
      if (n_rosenstein > 0) {
        double rl = std::numeric_limits<double>::infinity(), rh = -rl;
        for (const auto& c : rosenstein)
          if (c.admissible) {
            rl = std::min(rl, std::isfinite(c.ci.low) ? c.ci.low : c.fit.slope);
            rh = std::max(rh, std::isfinite(c.ci.high) ? c.ci.high : c.fit.slope);
          }
        rosenstein_estimate.value = r_median;
        rosenstein_estimate.low = rl;
        rosenstein_estimate.high = rh;
        rosenstein_estimate.quality = "uncertain";
        rosenstein_estimate.reason = [=, &rate](bool in_unit) {
          return fmt::format("median slope of {} nearest-neighbour curves: {}", n_rosenstein,
                             rate(r_median, in_unit));
        };
      } else {
        rosenstein_estimate.reason = [](bool) {
          return std::string("not admissible: nearest neighbours below the noise scale or no "
                             "linear region");
        };
      }
      (void)region_begin;
      (void)region_end;
    }
  }

  auto to_json = [&](const Estimate& e, bool in_unit) {
    const double f = in_unit ? 1.0 / dt : 1.0;
    return nonlinear::estimate(e.value * f, e.low * f, e.high * f, e.quality,
                               e.reason ? e.reason(in_unit) : std::string());
  };
  Json out;
  out["lyapunov_max_per_sample"] = to_json(head, false);
  if (unit != "sample") out["lyapunov_max_per_" + unit] = to_json(head, true);
  out["kantz_per_sample"] = to_json(kantz_estimate, false);
  out["rosenstein_per_sample"] = to_json(rosenstein_estimate, false);
  out["divergence"] = divergence;
  out["noise_radius"] = noise_floor ? Json(noise_radius) : Json();
  out["noise_dominated_radius"] = noise_scale ? Json(noise_scale_radius) : Json();
  out["sample_interval"] = dt;
  out["delay_samples"] = tau;
  out["embedding_dimension"] = m0;
  out["dimensions"] = {m0, m_max};
  out["theiler_window_samples"] = embedding.theiler;
  out["embedding_source"] = embedding.source;
  out["radii"] = radii;
  out["reference_points"] = scan.references;
  out["step_samples"] = stride;
  Json curves = Json::array();
  for (const auto* group : {&kantz, &rosenstein})
    for (const auto& c : *group) {
      Json curve = Json::array();
      for (double v : c.curve) curve.push_back(std::isfinite(v) ? Json(v) : Json());
      const bool fitted = c.usable && c.fit.found;
      curves.push_back(Json{{"method", c.method},
                            {"dimension", c.dimension},
                            {"radius", std::isfinite(c.radius) ? Json(c.radius) : Json()},
                            {"references", c.references},
                            {"divergence", curve},
                            {"fit_begin_step", fitted ? Json(c.fit.begin) : Json()},
                            {"fit_end_step", fitted ? Json(c.fit.end - 1) : Json()},
                            {"fit_intercept", fitted ? Json(c.fit.intercept) : Json()},  // per point
                            {"slope_per_sample", fitted ? Json(c.fit.slope) : Json()},
                            {"ci_low_per_sample", std::isfinite(c.ci.low) ? Json(c.ci.low) : Json()},
                            {"ci_high_per_sample", std::isfinite(c.ci.high) ? Json(c.ci.high) : Json()},
                            {"admissible", c.admissible},
                            {"selected", c.selected},
                            {"note", c.note}});
    }
  out["curves"] = curves;
  out["local_dimension_low"] = low_dims;
  out["local_dimension_high"] = high_dims;
  return out;
}

void LyapunovAnalysis::plot(const Json& result, const SampledSeries& series,
                            const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  const double dt = series.sample_interval;
  const std::string unit = series.sample_unit;
  const double step = result["step_samples"].get<double>() * dt;
  const int m0 = result["embedding_dimension"].get<int>();
  plot::Curves c;
  c.title = fmt::format("{}: divergence of neighbouring trajectories (dimension {})", title, m0);
  c.x_label = unit == "sample" ? "time after start [samples]"
                               : fmt::format("time after start [{}]", unit);
  c.y_label = "< ln distance > (mean log separation)";
  plot::Curves slopes;
  slopes.title = fmt::format("{}: Kantz slopes by neighbourhood size (points: admissible)", title);
  slopes.x_label = "neighbourhood size eps [signal units]";
  slopes.log_x = true;
  slopes.y_label = fmt::format("slope [1/{}]", unit);
  std::map<int, plot::Series> by_dimension, admissible_points;
  for (const Json& curve : result["curves"]) {
    const bool kantz = curve["method"] == "Kantz";
    const int m = curve["dimension"].get<int>();
    if (kantz && curve["slope_per_sample"].is_number() && curve["fit_end_step"].get<double>() > 0 &&
        curve["radius"].is_number()) {
      const double eps = curve["radius"].get<double>();
      const double s = curve["slope_per_sample"].get<double>() / dt;
      auto& line = by_dimension.try_emplace(m, plot::Series{fmt::format("m = {}", m), {}, {}, "linespoints"}).first->second;
      line.x.push_back(eps);
      line.y.push_back(s);
      if (curve["admissible"].get<bool>()) {
        auto& pts = admissible_points.try_emplace(m, plot::Series{"", {}, {}, "points"}).first->second;
        pts.x.push_back(eps);
        pts.y.push_back(s);
      }
    }
    if (m != m0) continue;
    const std::string label =
        kantz ? fmt::format("Kantz eps = {:.3g}", curve["radius"].get<double>()) : "Rosenstein";
    plot::Series s{label, {}, {}, "lines"};
    const Json& d = curve["divergence"];
    for (std::size_t k = 0; k < d.size(); ++k)
      if (d[k].is_number()) {
        s.x.push_back(double(k) * step);
        s.y.push_back(d[k].get<double>());
      }
    if (s.x.empty()) continue;
    c.series.push_back(s);
    if (curve["admissible"].get<bool>()) {
      const double k0 = curve["fit_begin_step"].get<double>(), k1 = curve["fit_end_step"].get<double>();
      const double b = curve["fit_intercept"].get<double>();
      // Slope per curve point (step_samples samples).
      const double slope = curve["slope_per_sample"].get<double>() * result["step_samples"].get<double>();
      c.series.push_back({"", {k0 * step, k1 * step}, {b + slope * k0, b + slope * k1}, "dashes"});
    }
  }
  plot::render(c, out_dir, "lyapunov_divergence");
  for (auto& [m, s] : by_dimension) slopes.series.push_back(s);
  for (auto& [m, s] : admissible_points) slopes.series.push_back(s);
  const Json& head = result["lyapunov_max_per_sample"];
  if (head["value"].is_number() && !slopes.series.empty()) {
    slopes.reference_y = head["value"].get<double>() / dt;
    slopes.reference_label = fmt::format("lambda_1 = {:.4g} per {}", *slopes.reference_y, unit);
  }
  if (!slopes.series.empty()) plot::render(slopes, out_dir, "lyapunov_slopes");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::LyapunovAnalysis);
