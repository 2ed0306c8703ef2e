#include "analysis/lyapunov/lyapunov.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <span>
#include <bit>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>

#include "shared/nonlinear/embedding_choice.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

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

template <>
PluginInfo LyapunovAnalysis::info() {
  using nonlinear::numeric_spec;
  return plugin_info("lyapunov", "N3, N4",
                     {
                         nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
                         numeric_spec("max_steps", ValueKind::integer, "samples",
                                      "how far the divergence curves follow the neighbours (absent: max(30, 100 x "
                                      "delay), at most a quarter of the series)",
                                      Json(), 4),
                         numeric_spec("max_reference_points", ValueKind::integer, "1",
                                      "reference vectors whose neighbours are followed (evenly spread)", 5000, 20),
                         numeric_spec("radius", ValueKind::real, "signal unit",
                                      "middle of five Kantz neighbourhood sizes eps, a factor 2 apart (absent: six "
                                      "sizes, the median distances to the 4th, 10th, 25th, 60th, 150th and 400th "
                                      "nearest neighbour)",
                                      Json(), 0, std::numeric_limits<double>::infinity(), true),
                         nonlinear::bootstrap_spec(), nonlinear::seed_spec()},
                     {{"max_reference_points", 200}},
                     "largest Lyapunov exponent from Kantz's and Rosenstein's divergence curves over three "
                     "embedding dimensions and six neighbourhood sizes; reported only where they show a "
                     "common exponential divergence; per sample and per second",
                     ThreadSafety::shareable);
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

ScanPlan plan_scan(std::span<const double> x, const EmbeddingParameters& embedding,
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
  std::size_t references = 0;  // of the Kantz scan
  double min_references = 0;   // a usable curve has neighbours for this many references
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

// A rate written per sample, or per unit of the series (dt of them per sample): reasons are
// written for either unit so that none mixes them.
struct RateText {
  double dt = 1;
  std::string unit;
  std::string operator()(double per_sample, bool in_unit) const {
    return in_unit ? fmt::format("{:.4g} per {}", per_sample / dt, unit)
                   : fmt::format("{:.4g} per sample", per_sample);
  }
};

// An estimate per sample with its reason, written for either unit.
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

// Kantz's curves for every size and dimension at once (one scan), Rosenstein's per dimension,
// fitted and classified.
CurveSet scan_curves(std::span<const double> x, const ScanPlan& plan, std::size_t references,
                     std::size_t replicates, std::uint64_t seed) {
  const auto scan = kantz_scan(x, plan.m0, plan.m_max, plan.delay, plan.theiler, plan.steps,
                               references, plan.radii, plan.stride);
  CurveSet set;
  set.references = scan.references;
  set.min_references = std::max(usable_references, usable_reference_share * double(scan.references));
  set.dims = std::size_t(plan.m_max - plan.m0 + 1);
  set.sizes = plan.radii.size();
  for (std::size_t r = 0; r < set.sizes; ++r)
    for (int m = plan.m0; m <= plan.m_max; ++m) {
      CurveResult c;
      c.method = "Kantz";
      c.dimension = m;
      c.radius = plan.radii[r];
      c.data = scan.block_curve(r, m);
      fit_curve(c, plan.stride, replicates, seed + set.kantz.size(), set.min_references);
      set.kantz.push_back(std::move(c));
    }
  for (int m = plan.m0; m <= plan.m_max; ++m) {
    CurveResult c;
    c.method = "Rosenstein";
    c.dimension = m;
    c.data = rosenstein_curve(x, m, plan.delay, plan.theiler, plan.steps, plan.stride,
                              std::min(references, rosenstein_references));
    fit_curve(c, plan.stride, replicates, seed + 1000 + std::size_t(m),
              std::min(set.min_references,
                       usable_reference_share * double(rosenstein_references)));
    set.rosenstein.push_back(std::move(c));
  }
  classify(set);
  return set;
}

// What noise does to the curves: a floor (the smallest sizes of a dimension collapse below an
// admissible one), or a noise-dominated scale among those used (from the local dimensions of
// the neighbour distances in m0 and m_max).
struct NoiseEvidence {
  bool floor = false;
  double floor_radius = nan;
  bool scale = false;
  double scale_radius = nan, scale_dimension = nan;
  std::vector<double> low_dims, high_dims;  // local dimensions per scale in m0 and m_max
};

void find_noise_floor(const CurveSet& set, const ScanPlan& plan, NoiseEvidence& noise) {
  for (std::size_t d = 0; d < set.dims; ++d) {
    std::size_t first_admissible = set.sizes;
    for (std::size_t r = 0; r < set.sizes && first_admissible == set.sizes; ++r)
      if (set.at(r, d).admissible) first_admissible = r;
    for (std::size_t r = 0; r < first_admissible && first_admissible < set.sizes; ++r)
      if (set.at(r, d).collapsed) {
        noise.floor = true;
        noise.floor_radius = std::isfinite(noise.floor_radius)
                                 ? std::max(noise.floor_radius, plan.radii[r])
                                 : plan.radii[r];
      }
  }
}

// Scale q is noise-dominated when its local dimension grows with the embedding dimension or
// exceeds that of every larger scale by more than noise_dimension_excess.
bool noisy_scale(const NoiseEvidence& noise, std::size_t q) {
  const auto& low = noise.low_dims;
  const auto& high = noise.high_dims;
  if (q >= low.size() || !std::isfinite(low[q])) return false;
  double larger = std::numeric_limits<double>::infinity();
  for (std::size_t p = q + 1; p < low.size(); ++p)
    if (std::isfinite(low[p])) larger = std::min(larger, low[p]);
  const double growth = std::isfinite(high[q]) ? high[q] - low[q] : 0.0;
  return growth > noise_dimension_excess ||
         (std::isfinite(larger) && low[q] - larger > noise_dimension_excess);
}

NoiseEvidence detect_noise(std::span<const double> x, const ScanPlan& plan,
                           const CurveSet& set) {
  NoiseEvidence noise;
  find_noise_floor(set, plan, noise);
  auto local_dimensions_in = [&](int m) {
    return local_dimensions(neighbour_distances(x, m, plan.delay, plan.theiler, plan.limit,
                                                radius_neighbours, radius_sample),
                            radius_neighbours);
  };
  noise.low_dims = local_dimensions_in(plan.m0);
  noise.high_dims = plan.m_max > plan.m0 ? local_dimensions_in(plan.m_max) : noise.low_dims;
  for (std::size_t r = 0; r < plan.radius_scale.size() && !noise.scale; ++r) {
    bool used = false;
    for (std::size_t d = 0; d < set.dims; ++d) used = used || set.at(r, d).selected;
    if (used && noisy_scale(noise, plan.radius_scale[r])) {
      noise.scale = true;
      noise.scale_radius = plan.radii[r];
      noise.scale_dimension = noise.low_dims[plan.radius_scale[r]];
    }
  }
  return noise;
}

// The selected curves: their slopes and intervals, and the dimensions and sizes they cover.
struct Selection {
  Envelope kantz, rosenstein;
  std::vector<int> dims;
  int sizes = 0;
};

Selection selected_curves(const CurveSet& set) {
  Selection s;
  std::size_t sizes_mask = 0;
  for (std::size_t r = 0; r < set.sizes; ++r)
    for (std::size_t d = 0; d < set.dims; ++d) {
      const CurveResult& c = set.at(r, d);
      if (!c.selected) continue;
      s.kantz.add(c);
      if (std::find(s.dims.begin(), s.dims.end(), c.dimension) == s.dims.end())
        s.dims.push_back(c.dimension);
      sizes_mask |= std::size_t(1) << r;
    }
  for (const auto& c : set.rosenstein)
    if (c.selected) s.rosenstein.add(c);
  s.sizes = std::popcount(sizes_mask);
  return s;
}

// The exponent and its interval, per method, and the divergence found.
struct Decision {
  Estimate head, kantz, rosenstein;
  std::string divergence = "undetermined";
};

// No divergence: the flat curves' mean trend, an interval including 0.
Decision no_divergence(const CurveSet& set, const ScanPlan& plan, const RateText& rate) {
  Decision out;
  out.divergence = "none";
  Envelope trends, rosenstein_trends;
  for (const auto& c : set.kantz)
    if (c.usable && c.fit.found && !c.fit.diverging) trends.add(c);
  for (const auto& c : set.rosenstein)
    if (c.usable && c.fit.found && !c.fit.diverging) rosenstein_trends.add(c);
  Estimate& head = out.head;
  head.value = median_of(trends.slopes);
  head.low = std::min(trends.low, 0.0);
  head.high = std::max(trends.high, 0.0);
  head.quality = "good";
  const std::size_t count = trends.slopes.size();
  const double value = head.value;
  const double horizon_samples = double(plan.steps - 1) * double(plan.stride);
  head.reason = [=](bool in_unit) {
    return fmt::format(
        "no exponential divergence: the curves of the smallest neighbourhoods rise by less "
        "than ln 2 over {:.0f} samples (periodic or quasi-periodic motion: largest exponent "
        "0); mean trend of {} flat curves {}",
        horizon_samples, count, rate(value, in_unit));
  };
  out.kantz = out.rosenstein = head;
  out.rosenstein.value = median_of(rosenstein_trends.slopes);
  return out;
}

Decision undetermined(Estimate why) {
  Decision out;
  out.head = out.kantz = out.rosenstein = std::move(why);
  return out;
}

// Why an estimate that showed exponential divergence is not "good" (empty: it is).
std::vector<std::string> doubts_about(double median, const Estimate& head,
                                      const Selection& selected, std::size_t dims,
                                      const NoiseEvidence& noise, std::size_t samples) {
  std::vector<std::string> doubts;
  const double half_width = 0.5 * (head.high - head.low) / std::abs(median);
  if (!(median > 0)) doubts.push_back("the slope is not positive");
  if (half_width > good_relative_half_width)
    doubts.push_back(fmt::format("the interval is +-{:.0f} % wide", 100 * half_width));
  if (noise.floor)
    doubts.push_back(fmt::format(
        "neighbours closer than {:.3g} separate at once (measurement or dynamical noise), "
        "which biases the slope of the larger neighbourhoods low",
        noise.floor_radius));
  if (noise.scale)
    doubts.push_back(fmt::format(
        "at the neighbourhood size {:.3g} the local dimension is {:.2g} and grows with the "
        "embedding dimension or towards smaller scales: noise dominates there, which biases "
        "the slope low",
        noise.scale_radius, noise.scale_dimension));
  if (selected.kantz.min_references < good_references)
    doubts.push_back(fmt::format("only {:.0f} reference points have neighbours",
                                 selected.kantz.min_references));
  if (median > 0 && double(samples) * median < good_e_foldings)
    doubts.push_back(fmt::format(
        "the series covers only {:.0f} e-folding times 1/lambda (at least {:.0f} wanted)",
        double(samples) * median, good_e_foldings));
  if (selected.dims.size() < dims)
    doubts.push_back(
        fmt::format("only {} of {} embedding dimensions show it", selected.dims.size(), dims));
  return doubts;
}

// The linear region of the selected curve closest to the median, in samples.
std::string central_region(const CurveSet& set, const ScanPlan& plan, double median) {
  // With an even number of slopes the median lies halfway between the two middle ones, so two
  // curves are equally close; their slopes differ in the last bits with the threads' summation
  // order. Closeness within 1e-9 relative counts as a tie, and a tie keeps the curve that comes
  // first (smallest dimension, then size), so the text is the same on every run.
  const double tie = 1e-9 * std::max(std::abs(median), 1e-300);
  const CurveResult* central = nullptr;
  for (const auto& c : set.kantz)
    if (c.selected &&
        (!central || std::abs(c.fit.slope - median) < std::abs(central->fit.slope - median) - tie))
      central = &c;
  return fmt::format("samples {:.0f}-{:.0f}", double(central->fit.begin * plan.stride),
                     double((central->fit.end - 1) * plan.stride));
}

Estimate rosenstein_estimate(const Selection& selected, const RateText& rate) {
  const std::size_t n = selected.rosenstein.slopes.size();
  if (n == 0)
    return not_determined(
        "not admissible: nearest neighbours below the noise scale or no linear region");
  Estimate e;
  e.value = median_of(selected.rosenstein.slopes);
  e.low = selected.rosenstein.low;
  e.high = selected.rosenstein.high;
  e.quality = "uncertain";
  const double value = e.value;
  e.reason = [=](bool in_unit) {
    return fmt::format("median slope of {} nearest-neighbour curves: {}", n, rate(value, in_unit));
  };
  return e;
}

// Exponential divergence: the median slope of the selected Kantz curves, the interval spanning
// every admissible curve of both methods.
Decision exponential(const CurveSet& set, const ScanPlan& plan, const Selection& selected,
                     const NoiseEvidence& noise, std::size_t samples, const RateText& rate) {
  const auto& slopes = selected.kantz.slopes;
  const double median = median_of(slopes);
  const auto [lo_it, hi_it] = std::minmax_element(slopes.begin(), slopes.end());
  const double lo = *lo_it, hi = *hi_it;
  const std::size_t n_slopes = slopes.size(), n_dims = selected.dims.size(), dims = set.dims;
  if (n_dims < std::min<std::size_t>(2, dims) ||
      (hi - lo) / std::abs(median) > max_relative_spread) {
    Estimate why;
    why.reason = [=](bool in_unit) {
      return fmt::format(
          "not determined: the admissible Kantz slopes range from {} to {} ({} curves in {} of "
          "{} embedding dimensions): no exponent common to dimensions and neighbourhood sizes",
          rate(lo, in_unit), rate(hi, in_unit), n_slopes, n_dims, dims);
    };
    return undetermined(why);
  }
  Decision out;
  out.divergence = "exponential";
  Estimate& head = out.head;
  out.kantz.value = head.value = median;
  out.kantz.low = selected.kantz.low;
  out.kantz.high = selected.kantz.high;
  // The headline interval also spans Rosenstein's admissible estimates.
  head.low = std::min(selected.kantz.low, selected.rosenstein.low);
  head.high = std::max(selected.kantz.high, selected.rosenstein.high);
  const auto doubts = doubts_about(median, head, selected, dims, noise, samples);
  head.quality = out.kantz.quality = doubts.empty() ? "good" : "uncertain";
  const std::string doubt_text =
      doubts.empty() ? "" : fmt::format("; uncertain: {}", fmt::join(doubts, "; "));
  const std::string region = central_region(set, plan, median);
  const double r_median = median_of(selected.rosenstein.slopes);
  const std::size_t n_rosenstein = selected.rosenstein.slopes.size();
  const int sizes_used = selected.sizes;
  head.reason = [=](bool in_unit) {
    std::string text = fmt::format(
        "exponential divergence: median slope of {} parallel Kantz curves (the smallest "
        "admissible neighbourhood sizes, {} dimensions x {} sizes; slopes {} to {}; linear "
        "region e.g. {})",
        n_slopes, n_dims, sizes_used, rate(lo, in_unit), rate(hi, in_unit), region);
    text += n_rosenstein > 0 ? fmt::format("; Rosenstein {} (median of {} dimensions)",
                                           rate(r_median, in_unit), n_rosenstein)
                             : "; Rosenstein not admissible";
    text += "; interval: all admissible curves' 95 % bootstrap intervals (dimensions, sizes, "
            "regions, methods)";
    return text + doubt_text;
  };
  out.kantz.reason = head.reason;
  out.rosenstein = rosenstein_estimate(selected, rate);
  return out;
}

// The decision over the classified curves: too few neighbours, no divergence (flat curves),
// no divergence common to sizes and dimensions, or exponential divergence.
Decision decide(const CurveSet& set, const ScanPlan& plan, const NoiseEvidence& noise,
                std::size_t samples, const RateText& rate) {
  std::size_t usable = 0, diverging = 0;
  for (const auto& c : set.kantz) {
    usable += c.usable;
    diverging += c.usable && c.fit.found && c.fit.diverging;
  }
  if (usable == 0)
    return undetermined(not_determined(fmt::format(
        "not determined: too few neighbours (fewer than {:.0f} of {} reference points have a "
        "neighbour within the largest radius {:.3g})",
        set.min_references, set.references, plan.radii.back())));
  // No divergence: in every dimension the curve of the smallest usable neighbourhood rises by
  // less than ln 2 over the whole horizon (larger neighbourhoods may wobble: a too small
  // dimension folds the attractor, and the curvature of a torus moves their mean distance).
  bool flat = true;
  for (std::size_t d = 0; d < set.dims; ++d) {
    const std::size_t r = set.first_usable(d);
    if (r < set.sizes) flat = flat && set.at(r, d).fit.found && !set.at(r, d).fit.diverging;
  }
  if (flat) return no_divergence(set, plan, rate);
  const Selection selected = selected_curves(set);
  if (selected.kantz.slopes.empty())
    return undetermined(not_determined(
        "not determined: no exponential divergence common to neighbourhood sizes" +
        (diverging > 0
             ? fmt::format(" ({} of {} usable Kantz curves have a linear region, none stays "
                           "parallel to the curve of a neighbouring size: neighbours separate "
                           "within the first steps whatever their distance, as in noise or a "
                           "linear stochastic process)",
                           diverging, usable)
             : fmt::format(" (none of the {} usable Kantz curves has a linear region)", usable))));
  return exponential(set, plan, selected, noise, samples, rate);
}

Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(); }

// Every curve with its fit and why it counts or not.
Json curves_json(const CurveSet& set) {
  Json curves = Json::array();
  for (const auto* group : {&set.kantz, &set.rosenstein})
    for (const auto& c : *group) {
      Json curve = Json::array();
      for (double v : c.curve) curve.push_back(number_or_null(v));
      const bool fitted = c.usable && c.fit.found;
      curves.push_back(Json{{"method", c.method},
                            {"dimension", c.dimension},
                            {"radius", number_or_null(c.radius)},
                            {"references", c.references},
                            {"divergence", curve},
                            {"fit_begin_step", fitted ? Json(c.fit.begin) : Json()},
                            {"fit_end_step", fitted ? Json(c.fit.end - 1) : Json()},
                            // per curve point (step_samples samples)
                            {"fit_intercept", fitted ? Json(c.fit.intercept) : Json()},
                            {"slope_per_sample", fitted ? Json(c.fit.slope) : Json()},
                            {"ci_low_per_sample", number_or_null(c.ci.low)},
                            {"ci_high_per_sample", number_or_null(c.ci.high)},
                            {"admissible", c.admissible},
                            {"selected", c.selected},
                            {"note", c.note}});
    }
  return curves;
}

}  // namespace

template <>
Json LyapunovAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const std::string name = series.name.empty() ? std::string("series") : series.name;
  const ScanPlan plan = plan_scan(x, embedding, nonlinear::given_integer(params_, "max_steps"),
                                  nonlinear::given_real(params_, "radius"), name);
  const CurveSet set =
      scan_curves(x, plan, std::size_t(params_.integer("max_reference_points")),
                  std::size_t(params_.integer("bootstrap_replicates")),
                  std::uint64_t(params_.integer("seed")));
  const NoiseEvidence noise = detect_noise(x, plan, set);
  const double dt = series.sample_interval;
  const std::string unit = series.sample_unit;
  const Decision decision = decide(set, plan, noise, x.size(), RateText{dt, unit});

  Json out;
  out["lyapunov_max_per_sample"] = decision.head.json(false, dt);
  if (unit != "sample") out["lyapunov_max_per_" + unit] = decision.head.json(true, dt);
  out["kantz_per_sample"] = decision.kantz.json(false, dt);
  out["rosenstein_per_sample"] = decision.rosenstein.json(false, dt);
  out["divergence"] = decision.divergence;
  out["noise_radius"] = noise.floor ? Json(noise.floor_radius) : Json();
  out["noise_dominated_radius"] = noise.scale ? Json(noise.scale_radius) : Json();
  out["sample_interval"] = dt;
  out["delay_samples"] = plan.delay;
  out["embedding_dimension"] = plan.m0;
  out["dimensions"] = {plan.m0, plan.m_max};
  out["theiler_window_samples"] = plan.theiler;
  out["embedding_source"] = embedding.source;
  out["radii"] = plan.radii;
  out["reference_points"] = set.references;
  out["step_samples"] = plan.stride;
  out["curves"] = curves_json(set);
  out["local_dimension_low"] = noise.low_dims;
  out["local_dimension_high"] = noise.high_dims;
  return out;
}

namespace {

// The Kantz curves of dimension m0 for every size and Rosenstein's, with the linear fits of the
// curves the estimate uses (dashed).
void plot_divergence(const Json& result, const std::string& title, double dt,
                     const std::string& unit, const std::filesystem::path& out_dir) {
  const double step_samples = result["step_samples"].get<double>();
  const double step = step_samples * dt;
  const int m0 = result["embedding_dimension"].get<int>();
  plot::Curves c;
  c.title = fmt::format("{}: divergence of neighbouring trajectories (dimension {})", title, m0);
  c.x_label = unit == "sample" ? "time after start [samples]"
                               : fmt::format("time after start [{}]", unit);
  c.y_label = "< ln distance > (mean log separation)";
  bool fit_labelled = false;
  for (const Json& curve : result["curves"]) {
    if (curve["dimension"].get<int>() != m0) continue;
    const bool kantz = curve["method"] == "Kantz";
    // Rosenstein's curve with markers: the palette repeats after seven curves.
    plot::Series s{kantz ? fmt::format("Kantz eps = {:.3g}", curve["radius"].get<double>())
                         : "Rosenstein (nearest neighbour)",
                   {}, {}, kantz ? "lines" : "linespoints"};
    const Json& d = curve["divergence"];
    for (std::size_t k = 0; k < d.size(); ++k)
      if (d[k].is_number()) {
        s.x.push_back(double(k) * step);
        s.y.push_back(d[k].get<double>());
      }
    if (s.x.empty()) continue;
    c.series.push_back(s);
    if (!curve["selected"].get<bool>()) continue;
    const double k0 = curve["fit_begin_step"].get<double>(), k1 = curve["fit_end_step"].get<double>();
    const double b = curve["fit_intercept"].get<double>();
    // Slope per curve point (step_samples samples).
    const double slope = curve["slope_per_sample"].get<double>() * step_samples;
    c.series.push_back({fit_labelled ? "" : "linear fits (curves used)",
                        {k0 * step, k1 * step},
                        {b + slope * k0, b + slope * k1},
                        "dashes"});
    fit_labelled = true;
  }
  plot::render(c, out_dir, "lyapunov_divergence");
}

// Slope of every fitted Kantz curve by neighbourhood size, one line per dimension, the curves the
// estimate uses marked, and the estimate as a horizontal line.
void plot_slopes(const Json& result, const std::string& title, double dt, const std::string& unit,
                 const std::filesystem::path& out_dir) {
  plot::Curves slopes;
  slopes.title = fmt::format("{}: Kantz slopes by neighbourhood size and dimension", title);
  slopes.x_label = "neighbourhood size eps [signal units]";
  slopes.log_x = true;
  slopes.y_label = fmt::format("slope [1/{}]", unit);
  std::map<int, plot::Series> by_dimension;
  plot::Series used{"used by the estimate", {}, {}, "points"};
  for (const Json& curve : result["curves"]) {
    if (curve["method"] != "Kantz" || !curve["slope_per_sample"].is_number() ||
        !(curve["fit_end_step"].get<double>() > 0) || !curve["radius"].is_number())
      continue;
    const int m = curve["dimension"].get<int>();
    const double eps = curve["radius"].get<double>();
    const double s = curve["slope_per_sample"].get<double>() / dt;
    auto& line =
        by_dimension.try_emplace(m, plot::Series{fmt::format("m = {}", m), {}, {}, "linespoints"})
            .first->second;
    line.x.push_back(eps);
    line.y.push_back(s);
    if (curve["selected"].get<bool>()) {
      used.x.push_back(eps);
      used.y.push_back(s);
    }
  }
  for (auto& [m, s] : by_dimension) slopes.series.push_back(s);
  if (!used.x.empty()) slopes.series.push_back(used);
  if (slopes.series.empty()) return;
  const Json& head = result["lyapunov_max_per_sample"];
  if (head["value"].is_number()) {
    slopes.reference_y = head["value"].get<double>() / dt;
    slopes.reference_label = fmt::format("lambda_1 = {:.4g} per {}", *slopes.reference_y, unit);
  }
  plot::render(slopes, out_dir, "lyapunov_slopes");
}

}  // namespace

template <>
void LyapunovAnalysis::plot(const Json& result, const SampledSeries& series,
                            const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  plot_divergence(result, title, series.sample_interval, series.sample_unit, out_dir);
  plot_slopes(result, title, series.sample_interval, series.sample_unit, out_dir);
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::LyapunovAnalysis);
