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

#include "shared/nonlinear/correlation_sums.hpp"
#include "shared/nonlinear/embedding_choice.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
}  // namespace

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

template <>
PluginInfo CorrelationDimension::info() {
  using nonlinear::numeric_spec;
  return plugin_info("correlation_dimension", "N2",
                     {
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
                     },
                     {{"max_dimension", 4}, {"max_reference_points", 200}},
                     "correlation dimension D2 (Grassberger-Procaccia, Theiler window) from an automatically "
                     "detected scaling region, versus embedding dimension until saturation",
                     ThreadSafety::shareable);
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

template <>
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

template <>
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
