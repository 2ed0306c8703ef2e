#include "analysis/rbf_density/rbf_density.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {
constexpr std::size_t max_lloyd_iterations = 100;
constexpr std::size_t density_grid_points = 801;
}  // namespace

double RbfDensity::operator()(double x) const {
  double p = 0.0;
  for (std::size_t k = 0; k < centre.size(); ++k) {
    const double u = (x - centre[k]) / width[k];
    p += weight[k] * std::exp(-0.5 * u * u) / (width[k] * std::sqrt(2.0 * std::numbers::pi));
  }
  return p;
}

RbfDensity fit_rbf_density(std::span<const double> samples, std::size_t nodes) {
  std::vector<double> x(samples.begin(), samples.end());
  std::sort(x.begin(), x.end());
  const std::size_t n = x.size();
  nodes = std::max<std::size_t>(1, std::min(nodes, n));
  // Start: evenly spaced quantiles; then Lloyd iterations. In 1-D with sorted samples the
  // clusters are contiguous runs, split at the midpoints between neighbouring centres.
  std::vector<double> c(nodes);
  for (std::size_t k = 0; k < nodes; ++k)
    c[k] = x[std::min(n - 1, (2 * k + 1) * n / (2 * nodes))];
  c.erase(std::unique(c.begin(), c.end()), c.end());
  std::vector<std::size_t> count;
  for (std::size_t it = 0; it < max_lloyd_iterations; ++it) {
    std::vector<double> sum(c.size(), 0.0);
    count.assign(c.size(), 0);
    std::size_t k = 0;
    for (double v : x) {
      while (k + 1 < c.size() && v > 0.5 * (c[k] + c[k + 1])) ++k;
      sum[k] += v;
      ++count[k];
    }
    std::vector<double> next;
    std::vector<std::size_t> next_count;
    for (std::size_t j = 0; j < c.size(); ++j)
      if (count[j] > 0) {
        const double m = sum[j] / static_cast<double>(count[j]);
        if (!next.empty() && m == next.back()) {
          next_count.back() += count[j];
        } else {
          next.push_back(m);
          next_count.push_back(count[j]);
        }
      }
    const bool converged = next == c;
    c = std::move(next);
    count = std::move(next_count);
    if (converged) break;
  }
  RbfDensity d;
  d.centre = c;
  for (std::size_t k = 0; k < c.size(); ++k) {
    d.weight.push_back(static_cast<double>(count[k]) / static_cast<double>(n));
    double nearest = std::numeric_limits<double>::infinity();
    if (k > 0) nearest = std::min(nearest, c[k] - c[k - 1]);
    if (k + 1 < c.size()) nearest = std::min(nearest, c[k + 1] - c[k]);
    d.width.push_back(0.5 * nearest);
  }
  if (c.size() == 1) {
    // One centre has no neighbour: the sample spread stands in (a constant window: any width).
    double var = 0.0;
    for (double v : x) var += (v - c[0]) * (v - c[0]);
    var /= static_cast<double>(n);
    d.width[0] = var > 0.0 ? std::sqrt(var) : 1.0;
  }
  return d;
}

DensityCriterion density_criterion(std::span<const double> samples, const RbfDensity& density) {
  DensityCriterion out;
  const auto [lo, hi] = std::minmax_element(samples.begin(), samples.end());
  double sum = 0.0;
  for (double v : samples) sum += v;
  out.mean = sum / static_cast<double>(samples.size());
  out.x_max = *hi;
  auto best = [&, best_p = -1.0](double x) mutable {
    const double p = density(x);
    if (p > best_p) {
      best_p = p;
      out.x_at_max_density = x;
    }
  };
  for (std::size_t i = 0; i < density_grid_points; ++i)
    best(*lo + (*hi - *lo) * static_cast<double>(i) / static_cast<double>(density_grid_points - 1));
  for (double c : density.centre) best(c);
  const double spread = std::abs(out.x_max - out.mean);
  out.ratio = spread > 0.0 ? std::abs(out.x_at_max_density - out.mean) / spread : 0.0;
  return out;
}

PluginInfo RbfDensityAnalysis::info() {
  const ParamSpec window = monitor::count_spec(
      "window_samples", "latest samples the density is estimated from (book: 50)", 50, 5);
  const ParamSpec hop =
      monitor::count_spec("hop_samples", "samples between evaluations of the criterion", 10, 1);
  ParamSpec nodes = monitor::count_spec(
      "nodes",
      "RBF centres (network nodes) per window; odd keeps a centre at the mode of a unimodal "
      "density, more make a 50-sample estimate noisier",
      3, 2);
  nodes.max = 1000;
  ParamSpec rho = param_spec("rho", ValueKind::real, "1",
                             "chatter when |x_at_max_density - mean| / |x_max - mean| >= rho "
                             "(book: 0.2)");
  rho.default_value = 0.2;
  rho.min = 0.0;
  rho.max = 1.0;
  rho.min_exclusive = true;
  return plugin_info("rbf_density", "C3",
                     {window, hop, nodes, rho, monitor::persistence_spec(10)},
                     {{"window_samples", 50}, {"rho", 0.2}},
                     "amplitude-density chatter criterion (5-22) on a Gaussian RBF density estimate of the "
                     "latest samples",
                     ThreadSafety::shareable);
}

RbfDensityAnalysis::RbfDensityAnalysis(const ParamValues& params)
    : window_(static_cast<std::size_t>(params.integer("window_samples"))),
      hop_(static_cast<std::size_t>(params.integer("hop_samples"))),
      nodes_(static_cast<std::size_t>(params.integer("nodes"))),
      persistence_(static_cast<std::size_t>(params.integer("persistence_windows"))),
      rho_(params.real("rho")) {}

void RbfDensityAnalysis::check(const SampledSeries& series) const {
  monitor::require_samples(series, window_,
                           fmt::format("rbf_density.window_samples = {}", window_));
}

monitor::ScoreTrack RbfDensityAnalysis::scores(const SampledSeries& series, Json& details) const {
  monitor::ScoreTrack track{"rbf_density", "density criterion (5-22)", {}, {}, rho_};
  const std::span<const double> values(series.values);
  const std::size_t evaluations = values.size() >= window_ ? (values.size() - window_) / hop_ + 1 : 0;
  track.t_s.reserve(evaluations);  // exact: 10^6 evaluations of a long signal without slack
  track.score.reserve(evaluations);
  for (std::size_t last = window_ - 1; last < values.size(); last += hop_) {
    const auto window = values.subspan(last + 1 - window_, window_);
    track.t_s.push_back(static_cast<double>(last) * series.sample_interval);
    track.score.push_back(density_criterion(window, fit_rbf_density(window, nodes_)).ratio);
  }
  details["window_samples"] = window_;
  details["hop_samples"] = hop_;
  details["nodes"] = nodes_;
  return track;
}

Json RbfDensityAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  return analyse_with_arrays(series, context).merged();
}

ResultWithArrays RbfDensityAnalysis::analyse_with_arrays(const SampledSeries& series,
                                                         const Json& /*context*/) const {
  ResultWithArrays out = monitor::detector_result(*this, series);
  Json& result = out.result;
  // Snapshots for plot(): the first window, the window that raised the first alarm, the last one.
  Json snapshots = Json::array();
  snapshots.push_back(snapshot(series, window_ - 1));
  const Json& first = result["alarms"]["first_alarm_s"];
  if (first.is_number())
    snapshots.push_back(snapshot(
        series, static_cast<std::size_t>(std::llround(first.get<double>() / series.sample_interval))));
  snapshots.push_back(snapshot(series, series.values.size() - 1));
  result["snapshots"] = std::move(snapshots);
  return out;
}

Json RbfDensityAnalysis::snapshot(const SampledSeries& series, std::size_t last_sample) const {
  const auto window =
      std::span<const double>(series.values).subspan(last_sample + 1 - window_, window_);
  const RbfDensity d = fit_rbf_density(window, nodes_);
  const DensityCriterion c = density_criterion(window, d);
  const auto [lo, hi] = std::minmax_element(window.begin(), window.end());
  const double margin = 0.15 * std::max(*hi - *lo, 1e-300);
  std::vector<double> x, p;
  for (std::size_t i = 0; i < 201; ++i) {
    x.push_back(*lo - margin + (*hi - *lo + 2 * margin) * static_cast<double>(i) / 200.0);
    p.push_back(d(x.back()));
  }
  return {{"t_s", static_cast<double>(last_sample) * series.sample_interval},
          {"x", x},
          {"density", p},
          {"x_at_max_density", c.x_at_max_density},
          {"mean", c.mean},
          {"x_max", c.x_max},
          {"ratio", c.ratio},
          {"flagged", c.ratio >= rho_}};
}

void RbfDensityAnalysis::plot(const Json& result, const SampledSeries& /*series*/,
                              const std::filesystem::path& out_dir) const {
  monitor::plot_scores(result, fmt::format("C3 density criterion (5-22), latest {} samples", window_),
                       "|x_at_max_density - mean| / |x_max - mean|", out_dir,
                       "rbf_density_criterion");
  monitor::plot_density_snapshots(result.at("snapshots").get<std::vector<Json>>(),
                                 "C3 RBF amplitude densities", "signal unit", out_dir, "rbf_density_snapshots");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::RbfDensityAnalysis);
