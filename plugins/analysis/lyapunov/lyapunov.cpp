#include "analysis/lyapunov/lyapunov.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>

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
const std::vector<std::size_t> radius_neighbours{4, 10, 25, 60, 150, 400};
// The exponent comes from the smallest admissible sizes of each dimension (the longest linear
// regions; larger neighbourhoods are there to rise above noise): this many of them.
constexpr std::size_t estimate_radii = 2;
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

namespace {

// The scan's shape: dimensions m0..m_max, the curve points (every `stride` samples), and the
// neighbourhood sizes with the index into radius_neighbours each came from.
struct ScanPlan {
  int m0 = 2, m_max = 2, delay = 1;
  std::size_t theiler = 0, stride = 1, steps = 0, limit = 0;
  std::vector<double> radii;
  std::vector<std::size_t> radius_scale;  // empty for a given radius
};

ScanPlan plan_scan(const std::vector<double>& x, const EmbeddingParameters& embedding,
                   std::optional<std::int64_t> given_steps, std::optional<double> given_radius,
                   const std::string& name) {
  ScanPlan p;
  p.m0 = embedding.dimension;
  p.delay = embedding.delay;
  p.theiler = embedding.theiler;
  const std::size_t samples = x.size();
  // The dimensions the series can hold with a horizon of at least 30 samples: minimum_vectors
  // vectors beyond the embedding window and four horizons.
  auto room = [&](int m) {
    const std::size_t window =
        std::size_t(m - 1) * std::size_t(p.delay) + nonlinear::minimum_vectors;
    return samples > window ? samples - window : 0;
  };
  p.m_max = p.m0 + scanned_dimensions - 1;
  while (p.m_max > p.m0 && room(p.m_max) < 4 * 30) --p.m_max;
  std::size_t horizon = given_steps ? std::size_t(*given_steps)
                                    : std::min<std::size_t>(std::max(30, 100 * p.delay),
                                                            room(p.m_max) / 4);
  if (given_steps && horizon > room(p.m_max))
    throw InputError(fmt::format(
        "{}: max_steps = {}: {} samples leave only {} vectors beyond the embedding window of "
        "dimension {} with delay {} samples; at most {} steps",
        name, horizon, samples, room(p.m_max), p.m_max, p.delay, room(p.m_max)));
  horizon = std::max<std::size_t>(horizon, 4);
  if (!given_steps)
    horizon = saturation_horizon(x, p.m0, p.delay, p.theiler, horizon, min_curve_points);
  p.stride = curve_stride(p.delay, horizon, min_curve_points);
  p.steps = horizon / p.stride + 1;
  const std::size_t history =
      (p.steps - 1) * p.stride + std::size_t(p.m_max - 1) * std::size_t(p.delay);
  p.limit = samples - history;
  if (given_radius) {
    for (int q = -2; q <= 2; ++q) p.radii.push_back(*given_radius * std::ldexp(1.0, q));
  } else {
    const auto distances =
        neighbour_distances(x, std::min(p.m0 + 1, p.m_max), p.delay, p.theiler, p.limit,
                            radius_neighbours, radius_sample);
    for (std::size_t q = 0; q < distances.size(); ++q)
      if (std::isfinite(distances[q]) && distances[q] > 0 &&
          (p.radii.empty() || distances[q] > p.radii.back() * 1.05)) {
        p.radii.push_back(distances[q]);
        p.radius_scale.push_back(q);
      }
  }
  if (p.radii.empty())
    throw PointFailure(fmt::format("{}: no neighbours outside the Theiler window ({} samples)",
                                   name, p.theiler));
  return p;
}

// Every curve of the scan, classified.
struct CurveSet {
  std::size_t dims = 0, sizes = 0;
  std::vector<CurveResult> kantz;  // [r * dims + d]
  std::vector<CurveResult> rosenstein;  // [d]
  CurveResult& at(std::size_t r, std::size_t d) { return kantz[r * dims + d]; }
  const CurveResult& at(std::size_t r, std::size_t d) const { return kantz[r * dims + d]; }
  // The smallest size with a usable curve in dimension d (sizes if none).
  std::size_t first_usable(std::size_t d) const {
    for (std::size_t r = 0; r < sizes; ++r)
      if (at(r, d).usable) return r;
    return sizes;
  }
};

// Parallel pairs, admissible and selected curves (the estimate_radii smallest admissible sizes of
// each dimension), and the notes of the others.
void classify(CurveSet& set) {
  for (std::size_t d = 0; d < set.dims; ++d)
    for (std::size_t r = 0; r + 1 < set.sizes; ++r) {
      if (!set.at(r, d).usable || !set.at(r + 1, d).usable) continue;
      const double kept = separation_kept(set.at(r, d), set.at(r + 1, d));
      if (kept >= parallel_fraction)
        set.at(r, d).parallel = set.at(r + 1, d).parallel = true;
      else if (kept < parallel_fraction)
        set.at(r, d).collapsed = true;
    }
  for (std::size_t d = 0; d < set.dims; ++d) {
    std::size_t selected = 0;
    for (std::size_t r = 0; r < set.sizes; ++r) {
      CurveResult& c = set.at(r, d);
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
        c.selected = selected++ < estimate_radii;
        if (!c.selected) c.note = "admissible; larger than the sizes the estimate uses";
      }
    }
  }
  // Rosenstein's nearest neighbours are closer than every Kantz size: they count unless a
  // collapse (noise) lies between them and the admissible sizes.
  for (std::size_t d = 0; d < set.dims; ++d) {
    CurveResult& c = set.rosenstein[d];
    if (!c.usable || !c.fit.found) continue;
    const std::size_t first = set.first_usable(d);
    bool floor_below = false;
    for (std::size_t r = first; r < set.sizes && !set.at(r, d).admissible; ++r)
      floor_below = floor_below || set.at(r, d).collapsed;
    if (!c.fit.diverging)
      c.note = "rises by less than ln 2";
    else if (first == set.sizes || floor_below)
      c.note = "nearest neighbours lie below the noise scale of the Kantz curves";
    else
      c.admissible = c.selected = true;
  }
}

// Slopes and the envelope of the bootstrap intervals of the selected curves.
struct Envelope {
  std::vector<double> slopes;
  double low = std::numeric_limits<double>::infinity(), high = -low;
  double min_references = std::numeric_limits<double>::infinity();
  void add(const CurveResult& c) {
    slopes.push_back(c.fit.slope);
    low = std::min(low, std::isfinite(c.ci.low) ? c.ci.low : c.fit.slope);
    high = std::max(high, std::isfinite(c.ci.high) ? c.ci.high : c.fit.slope);
    min_references = std::min(min_references, c.references);
  }
};

// An estimate per sample with its reason, written for either unit (per sample, or per unit of
// the series) so that no reason mixes units.
struct Estimate {
  double value = nan, low = nan, high = nan;
  std::string quality = "failed";
  std::function<std::string(bool)> reason;
  Json json(bool in_unit, double dt) const {
    const double f = in_unit ? 1.0 / dt : 1.0;
    return nonlinear::estimate(value * f, low * f, high * f, quality,
                               reason ? reason(in_unit) : std::string());
  }
};

Estimate not_determined(std::string why) {
  Estimate e;
  e.reason = [why = std::move(why)](bool) { return why; };
  return e;
}

}  // namespace

Json LyapunovAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const std::string name = series.name.empty() ? std::string("series") : series.name;
  const ScanPlan plan = plan_scan(x, embedding, nonlinear::given_integer(params_, "max_steps"),
                                  nonlinear::given_real(params_, "radius"), name);
  const auto references = std::size_t(params_.integer("max_reference_points"));
  const auto replicates = std::size_t(params_.integer("bootstrap_replicates"));
  const auto seed = std::uint64_t(params_.integer("seed"));
  const double dt = series.sample_interval;
  const std::string unit = series.sample_unit;

  // Kantz's curves for every size and dimension at once, Rosenstein's per dimension.
  const auto scan = kantz_scan(x, plan.m0, plan.m_max, plan.delay, plan.theiler, plan.steps,
                               references, plan.radii, plan.stride);
  const double min_references =
      std::max(usable_references, usable_reference_share * double(scan.references));
  CurveSet set;
  set.dims = std::size_t(plan.m_max - plan.m0 + 1);
  set.sizes = plan.radii.size();
  for (std::size_t r = 0; r < set.sizes; ++r)
    for (int m = plan.m0; m <= plan.m_max; ++m) {
      CurveResult c;
      c.method = "Kantz";
      c.dimension = m;
      c.radius = plan.radii[r];
      c.data = scan.block_curve(r, m);
      fit_curve(c, plan.stride, replicates, seed + set.kantz.size(), min_references);
      set.kantz.push_back(std::move(c));
    }
  for (int m = plan.m0; m <= plan.m_max; ++m) {
    CurveResult c;
    c.method = "Rosenstein";
    c.dimension = m;
    c.data = rosenstein_curve(x, m, plan.delay, plan.theiler, plan.steps, plan.stride,
                              std::min(references, rosenstein_references));
    fit_curve(c, plan.stride, replicates, seed + 1000 + std::size_t(m),
              std::min(min_references, usable_reference_share * double(rosenstein_references)));
    set.rosenstein.push_back(std::move(c));
  }
  classify(set);

  // Noise: a floor (the smallest sizes of a dimension collapse below an admissible one), or a
  // noise-dominated scale among those used (local dimensions in m0 and m_max).
  bool noise_floor = false;
  double noise_radius = nan;
  for (std::size_t d = 0; d < set.dims; ++d) {
    std::size_t first_admissible = set.sizes;
    for (std::size_t r = 0; r < set.sizes && first_admissible == set.sizes; ++r)
      if (set.at(r, d).admissible) first_admissible = r;
    for (std::size_t r = 0; r < first_admissible && first_admissible < set.sizes; ++r)
      if (set.at(r, d).collapsed) {
        noise_floor = true;
        noise_radius = std::isfinite(noise_radius) ? std::max(noise_radius, plan.radii[r])
                                                   : plan.radii[r];
      }
  }
  auto local_dimensions_in = [&](int m) {
    return local_dimensions(neighbour_distances(x, m, plan.delay, plan.theiler, plan.limit,
                                                radius_neighbours, radius_sample),
                            radius_neighbours);
  };
  const auto low_dims = local_dimensions_in(plan.m0);
  const auto high_dims = plan.m_max > plan.m0 ? local_dimensions_in(plan.m_max) : low_dims;
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
  bool noise_scale = false;
  double noise_scale_radius = nan, noise_scale_dimension = nan;
  for (std::size_t r = 0; r < plan.radius_scale.size() && !noise_scale; ++r) {
    bool used = false;
    for (std::size_t d = 0; d < set.dims; ++d) used = used || set.at(r, d).selected;
    if (used && noisy_scale(plan.radius_scale[r])) {
      noise_scale = true;
      noise_scale_radius = plan.radii[r];
      noise_scale_dimension = low_dims[plan.radius_scale[r]];
    }
  }

  auto rate = [&](double per_sample, bool in_unit) {
    return in_unit ? fmt::format("{:.4g} per {}", per_sample / dt, unit)
                   : fmt::format("{:.4g} per sample", per_sample);
  };
  std::size_t usable = 0, diverging = 0;
  for (const auto& c : set.kantz) {
    usable += c.usable;
    diverging += c.usable && c.fit.found && c.fit.diverging;
  }
  // No divergence: in every dimension the curve of the smallest usable neighbourhood rises by
  // less than ln 2 over the whole horizon (larger neighbourhoods may wobble: a too small
  // dimension folds the attractor, and the curvature of a torus moves their mean distance).
  bool flat = usable > 0;
  for (std::size_t d = 0; d < set.dims; ++d) {
    const std::size_t r = set.first_usable(d);
    if (r < set.sizes) flat = flat && set.at(r, d).fit.found && !set.at(r, d).fit.diverging;
  }
  Envelope kantz, rosenstein;
  std::vector<int> dims_used;
  std::size_t sizes_used_mask = 0;
  for (std::size_t r = 0; r < set.sizes; ++r)
    for (std::size_t d = 0; d < set.dims; ++d)
      if (set.at(r, d).selected) {
        kantz.add(set.at(r, d));
        if (std::find(dims_used.begin(), dims_used.end(), set.at(r, d).dimension) ==
            dims_used.end())
          dims_used.push_back(set.at(r, d).dimension);
        sizes_used_mask |= std::size_t(1) << r;
      }
  for (const auto& c : set.rosenstein)
    if (c.selected) rosenstein.add(c);
  const int sizes_used = std::popcount(sizes_used_mask);
  const double horizon_samples = double(plan.steps - 1) * double(plan.stride);

  Estimate head, kantz_estimate, rosenstein_estimate;
  std::string divergence = "undetermined";
  if (usable == 0) {
    head = not_determined(fmt::format(
        "not determined: too few neighbours (fewer than {:.0f} of {} reference points have a "
        "neighbour within the largest radius {:.3g})",
        min_references, scan.references, plan.radii.back()));
    kantz_estimate = rosenstein_estimate = head;
  } else if (flat) {
    divergence = "none";
    Envelope trends, rosenstein_trends;
    for (const auto& c : set.kantz)
      if (c.usable && c.fit.found && !c.fit.diverging) trends.add(c);
    for (const auto& c : set.rosenstein)
      if (c.usable && c.fit.found && !c.fit.diverging) rosenstein_trends.add(c);
    head.value = median_of(trends.slopes);
    head.low = std::min(trends.low, 0.0);
    head.high = std::max(trends.high, 0.0);
    head.quality = "good";
    const std::size_t count = trends.slopes.size();
    const double value = head.value;
    head.reason = [=, &rate](bool in_unit) {
      return fmt::format(
          "no exponential divergence: the curves of the smallest neighbourhoods rise by less "
          "than ln 2 over {:.0f} samples (periodic or quasi-periodic motion: largest exponent "
          "0); mean trend of {} flat curves {}",
          horizon_samples, count, rate(value, in_unit));
    };
    kantz_estimate = rosenstein_estimate = head;
    rosenstein_estimate.value = median_of(rosenstein_trends.slopes);
  } else if (kantz.slopes.empty()) {
    head = not_determined(
        "not determined: no exponential divergence common to neighbourhood sizes" +
        (diverging > 0
             ? fmt::format(" ({} of {} usable Kantz curves have a linear region, none stays "
                           "parallel to the curve of a neighbouring size: neighbours separate "
                           "within the first steps whatever their distance, as in noise or a "
                           "linear stochastic process)",
                           diverging, usable)
             : fmt::format(" (none of the {} usable Kantz curves has a linear region)", usable)));
    kantz_estimate = rosenstein_estimate = head;
  } else {
    const double median = median_of(kantz.slopes);
    const auto [lo_it, hi_it] = std::minmax_element(kantz.slopes.begin(), kantz.slopes.end());
    const double lo = *lo_it, hi = *hi_it;
    const std::size_t n_slopes = kantz.slopes.size(), n_dims = dims_used.size(),
                      dims = set.dims;
    if (n_dims < std::min<std::size_t>(2, dims) || (hi - lo) / std::abs(median) > max_relative_spread) {
      head.reason = [=, &rate](bool in_unit) {
        return fmt::format(
            "not determined: the admissible Kantz slopes range from {} to {} ({} curves in {} "
            "of {} embedding dimensions): no exponent common to dimensions and neighbourhood "
            "sizes",
            rate(lo, in_unit), rate(hi, in_unit), n_slopes, n_dims, dims);
      };
      kantz_estimate = rosenstein_estimate = head;
    } else {
      divergence = "exponential";
      kantz_estimate.value = head.value = median;
      kantz_estimate.low = kantz.low;
      kantz_estimate.high = kantz.high;
      // The headline interval also spans Rosenstein's admissible estimates.
      head.low = std::min(kantz.low, rosenstein.low);
      head.high = std::max(kantz.high, rosenstein.high);
      // Quality: consistent, precise, noise-free at the sizes used and a long enough series.
      std::vector<std::string> doubts;
      const double half_width = 0.5 * (head.high - head.low) / std::abs(median);
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
      if (kantz.min_references < good_references)
        doubts.push_back(fmt::format("only {:.0f} reference points have neighbours",
                                     kantz.min_references));
      const double samples = double(x.size());
      if (median > 0 && samples * median < good_e_foldings)
        doubts.push_back(fmt::format(
            "the series covers only {:.0f} e-folding times 1/lambda (at least {:.0f} wanted)",
            samples * median, good_e_foldings));
      if (n_dims < dims)
        doubts.push_back(fmt::format("only {} of {} embedding dimensions show it", n_dims, dims));
      head.quality = kantz_estimate.quality = doubts.empty() ? "good" : "uncertain";
      const std::string doubt_text =
          doubts.empty() ? "" : fmt::format("; uncertain: {}", fmt::join(doubts, "; "));
      const CurveResult* central = nullptr;  // the selected curve closest to the median
      for (const auto& c : set.kantz)
        if (c.selected &&
            (!central || std::abs(c.fit.slope - median) < std::abs(central->fit.slope - median)))
          central = &c;
      const std::string region =
          fmt::format("samples {:.0f}-{:.0f}", double(central->fit.begin * plan.stride),
                      double((central->fit.end - 1) * plan.stride));
      const double r_median = median_of(rosenstein.slopes);
      const std::size_t n_rosenstein = rosenstein.slopes.size();
      head.reason = [=, &rate](bool in_unit) {
        std::string text = fmt::format(
            "exponential divergence: median slope of {} parallel Kantz curves (the smallest "
            "admissible neighbourhood sizes, {} dimensions x {} sizes; slopes {} to {}; linear "
            "region e.g. {})",
            n_slopes, n_dims, sizes_used, rate(lo, in_unit), rate(hi, in_unit), region);
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
        rosenstein_estimate.value = r_median;
        rosenstein_estimate.low = rosenstein.low;
        rosenstein_estimate.high = rosenstein.high;
        rosenstein_estimate.quality = "uncertain";
        rosenstein_estimate.reason = [=, &rate](bool in_unit) {
          return fmt::format("median slope of {} nearest-neighbour curves: {}", n_rosenstein,
                             rate(r_median, in_unit));
        };
      } else {
        rosenstein_estimate = not_determined(
            "not admissible: nearest neighbours below the noise scale or no linear region");
      }
    }
  }

  Json out;
  out["lyapunov_max_per_sample"] = head.json(false, dt);
  if (unit != "sample") out["lyapunov_max_per_" + unit] = head.json(true, dt);
  out["kantz_per_sample"] = kantz_estimate.json(false, dt);
  out["rosenstein_per_sample"] = rosenstein_estimate.json(false, dt);
  out["divergence"] = divergence;
  out["noise_radius"] = noise_floor ? Json(noise_radius) : Json();
  out["noise_dominated_radius"] = noise_scale ? Json(noise_scale_radius) : Json();
  out["sample_interval"] = dt;
  out["delay_samples"] = plan.delay;
  out["embedding_dimension"] = plan.m0;
  out["dimensions"] = {plan.m0, plan.m_max};
  out["theiler_window_samples"] = plan.theiler;
  out["embedding_source"] = embedding.source;
  out["radii"] = plan.radii;
  out["reference_points"] = scan.references;
  out["step_samples"] = plan.stride;
  Json curves = Json::array();
  for (const auto* group : {&set.kantz, &set.rosenstein})
    for (const auto& c : *group) {
      Json curve = Json::array();
      for (double v : c.curve) curve.push_back(std::isfinite(v) ? Json(v) : Json());
      const bool fitted = c.usable && c.fit.found;
      auto number = [](double v) { return std::isfinite(v) ? Json(v) : Json(); };
      curves.push_back(Json{{"method", c.method},
                            {"dimension", c.dimension},
                            {"radius", number(c.radius)},
                            {"references", c.references},
                            {"divergence", curve},
                            {"fit_begin_step", fitted ? Json(c.fit.begin) : Json()},
                            {"fit_end_step", fitted ? Json(c.fit.end - 1) : Json()},
                            // per curve point (step_samples samples)
                            {"fit_intercept", fitted ? Json(c.fit.intercept) : Json()},
                            {"slope_per_sample", fitted ? Json(c.fit.slope) : Json()},
                            {"ci_low_per_sample", number(c.ci.low)},
                            {"ci_high_per_sample", number(c.ci.high)},
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
  slopes.title = fmt::format("{}: Kantz slopes by neighbourhood size and dimension", title);
  slopes.x_label = "neighbourhood size eps [signal units]";
  slopes.log_x = true;
  slopes.y_label = fmt::format("slope [1/{}]", unit);
  std::map<int, plot::Series> by_dimension;
  plot::Series used{"used by the estimate", {}, {}, "points"};
  bool fit_labelled = false;
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
      if (curve["selected"].get<bool>()) {
        used.x.push_back(eps);
        used.y.push_back(s);
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
    if (curve["selected"].get<bool>()) {
      const double k0 = curve["fit_begin_step"].get<double>(), k1 = curve["fit_end_step"].get<double>();
      const double b = curve["fit_intercept"].get<double>();
      // Slope per curve point (step_samples samples).
      const double slope = curve["slope_per_sample"].get<double>() * result["step_samples"].get<double>();
      c.series.push_back({fit_labelled ? "" : "linear fits (curves used)",
                          {k0 * step, k1 * step},
                          {b + slope * k0, b + slope * k1},
                          "dashes"});
      fit_labelled = true;
    }
  }
  plot::render(c, out_dir, "lyapunov_divergence");
  for (auto& [m, s] : by_dimension) slopes.series.push_back(s);
  if (!used.x.empty()) slopes.series.push_back(used);
  const Json& head = result["lyapunov_max_per_sample"];
  if (head["value"].is_number() && !slopes.series.empty()) {
    slopes.reference_y = head["value"].get<double>() / dt;
    slopes.reference_label = fmt::format("lambda_1 = {:.4g} per {}", *slopes.reference_y, unit);
  }
  if (!slopes.series.empty()) plot::render(slopes, out_dir, "lyapunov_slopes");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::LyapunovAnalysis);
