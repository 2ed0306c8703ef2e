#include "analysis/lyapunov/lyapunov.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/embedding/embedding.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"

namespace chatterlab {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t radius_neighbours = 8;    // eps = median distance to the 8th neighbour
constexpr std::size_t max_kantz_neighbours = 64;  // neighbours used inside eps (cost bound)
}  // namespace

DivergenceCurves divergence_curves(const std::vector<double>& x, int dimension, int delay,
                                   std::size_t theiler, std::size_t steps, std::size_t references,
                                   double radius) {
  using nonlinear::Embedding;
  DivergenceCurves out;
  const Embedding e(x, dimension, delay);
  const nonlinear::NeighbourSearch search(e);
  const std::size_t n = e.size();
  if (n <= steps + 10) steps = n / 2;
  out.steps = steps;
  const std::size_t limit = n - steps;  // references and neighbours keep `steps` of future
  references = std::max<std::size_t>(1, std::min(references, limit));
  out.references = references;
  auto reference = [&](std::size_t r) {
    return std::size_t(double(r) * double(limit) / double(references));
  };
  if (!(radius > 0)) {
    std::vector<double> kth;
    const std::size_t sample = std::min<std::size_t>(references, 1000);
    for (std::size_t r = 0; r < sample; ++r) {
      const auto nn = search.nearest(reference(r * references / sample), radius_neighbours,
                                     theiler, limit);
      if (!nn.empty()) kth.push_back(nn.back().distance);
    }
    if (kth.empty()) throw PointFailure("no neighbours outside the Theiler window");
    std::nth_element(kth.begin(), kth.begin() + std::ptrdiff_t(kth.size() / 2), kth.end());
    radius = kth[kth.size() / 2];
  }
  out.radius = radius;
  const std::size_t size = DivergenceCurves::blocks * steps;
  out.rosenstein_sum.assign(size, 0.0);
  out.rosenstein_count.assign(size, 0.0);
  out.kantz_sum.assign(size, 0.0);
  out.kantz_count.assign(size, 0.0);
#pragma omp parallel
  {
    std::vector<double> rs(size, 0.0), rc(size, 0.0), ks(size, 0.0), kc(size, 0.0);
#pragma omp for schedule(dynamic, 16)
    for (std::size_t r = 0; r < references; ++r) {
      const std::size_t i = reference(r);
      const std::size_t offset = (r * DivergenceCurves::blocks / references) * steps;
      const auto nn = search.nearest(i, 1, theiler, limit);
      if (!nn.empty() && nn[0].distance > 0) {
        const std::size_t j = nn[0].index;
        for (std::size_t k = 0; k < steps; ++k) {
          const double d = e.distance(i + k, j + k);
          if (d > 0) {
            rs[offset + k] += std::log(d);
            rc[offset + k] += 1;
          }
        }
      }
      // At most max_kantz_neighbours of the neighbours within eps: the search stops there.
      const auto near = search.within(i, radius, theiler, limit, max_kantz_neighbours);
      if (near.empty()) continue;
      for (std::size_t k = 0; k < steps; ++k) {
        double mean = 0;
        for (const auto& m : near) mean += e.distance(i + k, m.index + k);
        mean /= double(near.size());
        if (mean > 0) {
          ks[offset + k] += std::log(mean);
          kc[offset + k] += 1;
        }
      }
    }
#pragma omp critical
    for (std::size_t k = 0; k < size; ++k) {
      out.rosenstein_sum[k] += rs[k];
      out.rosenstein_count[k] += rc[k];
      out.kantz_sum[k] += ks[k];
      out.kantz_count[k] += kc[k];
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

namespace {

std::vector<double> mean_curve(const std::vector<double>& sum, const std::vector<double>& count,
                               std::size_t steps, const std::vector<double>& weights) {
  std::vector<double> y(steps, 0.0), c(steps, 0.0);
  for (std::size_t b = 0; b < DivergenceCurves::blocks; ++b)
    for (std::size_t k = 0; k < steps; ++k) {
      y[k] += weights[b] * sum[b * steps + k];
      c[k] += weights[b] * count[b * steps + k];
    }
  for (std::size_t k = 0; k < steps; ++k) y[k] = c[k] > 0 ? y[k] / c[k] : nan;
  return y;
}

struct MethodResult {
  std::vector<double> curve;
  LinearRegionFit fit;
  nonlinear::Interval ci{nan, nan};
};

MethodResult evaluate(const std::vector<double>& sum, const std::vector<double>& count,
                      std::size_t steps, std::size_t replicates, std::uint64_t seed) {
  MethodResult m;
  m.curve = mean_curve(sum, count, steps, std::vector<double>(DivergenceCurves::blocks, 1.0));
  for (double v : m.curve)
    if (!std::isfinite(v)) return m;
  m.fit = linear_region(m.curve);
  if (!m.fit.found) return m;
  std::vector<double> k(steps);
  for (std::size_t i = 0; i < steps; ++i) k[i] = double(i);
  m.ci = nonlinear::block_bootstrap(DivergenceCurves::blocks, replicates, seed,
                                    [&](const std::vector<double>& w) {
                                      const auto y = mean_curve(sum, count, steps, w);
                                      return nonlinear::fit_line(k, y, m.fit.begin, m.fit.end)
                                          .slope;
                                    });
  return m;
}

Json curve_json(const MethodResult& m) {
  Json c = Json::array();
  for (double v : m.curve) c.push_back(std::isfinite(v) ? Json(v) : Json());
  return Json{{"divergence", c},
              {"fit_begin_step", m.fit.found ? Json(m.fit.begin) : Json()},
              {"fit_end_step", m.fit.found ? Json(m.fit.end - 1) : Json()},
              {"fit_intercept", m.fit.found ? Json(m.fit.intercept) : Json()}};
}

// The radius x dimension scan of the `radius_scan_count` parameter: the slope of each Kantz curve
// (TISEAN lyap_k statistic) and the spread of the slopes.
Json radius_scan(const std::vector<double>& x, const EmbeddingParameters& embedding,
                 std::size_t steps, std::size_t references, std::size_t count) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  std::vector<double> radii;
  for (std::size_t r = 0; r < count; ++r)
    radii.push_back((*hi - *lo) * 1e-3 * std::pow(10.0, double(r) / double(count - 1)));
  const int m0 = std::max(1, embedding.dimension - 1), m1 = embedding.dimension + 1;
  const auto scan = kantz_scan(x, m0, m1, embedding.delay, embedding.theiler, steps, references,
                               radii);
  Json slopes = Json::array(), dimensions = Json::array();
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (int m = m0; m <= m1; ++m) {
    dimensions.push_back(m);
    Json row = Json::array();
    for (std::size_t r = 0; r < radii.size(); ++r) {
      const auto curve = scan.curve(r, m);
      const bool complete = std::all_of(curve.begin(), curve.end(),
                                        [](double v) { return std::isfinite(v); });
      const auto fit = complete ? linear_region(curve) : LinearRegionFit{};
      if (!fit.found) {
        row.push_back(Json());
        continue;
      }
      row.push_back(fit.slope);
      low = std::min(low, fit.slope);
      high = std::max(high, fit.slope);
    }
    slopes.push_back(row);
  }
  return Json{{"radii", radii},
              {"dimensions", dimensions},
              {"reference_points", scan.references},
              {"slopes_per_sample", slopes},
              {"slope_spread_per_sample", high >= low ? Json(high - low) : Json()}};
}

}  // namespace

PluginInfo LyapunovAnalysis::info() {
  PluginInfo info;
  info.name = "lyapunov";
  info.description =
      "largest Lyapunov exponent by Rosenstein's and Kantz's divergence methods with automatic "
      "linear-region detection, per sample and per second";
  info.models_md_ids = "N3, N4";
  using nonlinear::numeric_spec;
  info.params = {
      nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
      numeric_spec("max_steps", ValueKind::integer, "samples",
                   "length of the divergence curves (absent: max(30, 50 x delay), at most a fifth "
                   "of the series)",
                   Json(), 4),
      numeric_spec("max_reference_points", ValueKind::integer, "1",
                   "reference vectors whose neighbours are followed (evenly spread)", 5000, 20),
      numeric_spec("radius", ValueKind::real, "signal unit",
                   "Kantz neighbourhood radius eps (absent: median distance to the 8th nearest "
                   "neighbour)",
                   Json(), 0, std::numeric_limits<double>::infinity(), true),
      numeric_spec("radius_scan_count", ValueKind::integer, "1",
                   "when given: Kantz curves also as TISEAN's lyap_k computes them (rms distance of "
                   "all neighbours within eps) for embedding dimensions m-1..m+1 x this many radii "
                   "(geometric, 1/1000 to 1/100 of the signal range: lyap_k's defaults), each "
                   "with the slope of its linear region; their spread shows how much the exponent "
                   "depends on eps and m",
                   Json(), 2, 20),
      nonlinear::bootstrap_spec(), nonlinear::seed_spec()};
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_reference_points", 200}};
  return info;
}

Json LyapunovAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const std::size_t n = nonlinear::vector_count(x.size(), embedding.dimension, embedding.delay);
  const auto given_steps = nonlinear::given_integer(params_, "max_steps");
  const std::size_t steps =
      given_steps ? std::size_t(*given_steps)
                  : std::min(std::max<std::size_t>(30, 50 * std::size_t(embedding.delay)), n / 5);
  const double radius = nonlinear::given_real(params_, "radius").value_or(0.0);
  const auto curves = divergence_curves(x, embedding.dimension, embedding.delay,
                                        embedding.theiler, steps,
                                        std::size_t(params_.integer("max_reference_points")),
                                        radius);
  const auto replicates = std::size_t(params_.integer("bootstrap_replicates"));
  const auto seed = std::uint64_t(params_.integer("seed"));
  const MethodResult kantz =
      evaluate(curves.kantz_sum, curves.kantz_count, curves.steps, replicates, seed);
  const MethodResult rosenstein =
      evaluate(curves.rosenstein_sum, curves.rosenstein_count, curves.steps, replicates, seed + 1);

  const double dt = series.sample_interval;
  auto method_estimate = [&](const MethodResult& m, const char* name) {
    if (!m.fit.found)
      return nonlinear::estimate(nan, nan, nan, "failed",
                                 fmt::format("{}: no linear region in the divergence curve", name));
    std::string reason =
        m.fit.diverging
            ? fmt::format("{}: slope of the divergence curve over steps {}-{}", name, m.fit.begin,
                          m.fit.end - 1)
            : fmt::format("{}: neighbours do not separate exponentially (rise < ln 2): mean trend",
                          name);
    const double width = m.ci.high - m.ci.low;
    const std::string quality =
        m.fit.end - m.fit.begin >= 4 && std::isfinite(width) ? "good" : "uncertain";
    return nonlinear::estimate(m.fit.slope, m.ci.low, m.ci.high, quality, reason);
  };
  Json k_est = method_estimate(kantz, "Kantz");
  Json r_est = method_estimate(rosenstein, "Rosenstein");

  // Headline: Kantz (averaging over all neighbours within eps is the less noisy route);
  // Rosenstein is the independent check that moves the quality flag.
  Json headline = k_est;
  if (k_est["value"].is_number() && r_est["value"].is_number()) {
    const double a = k_est["value"].get<double>(), b = r_est["value"].get<double>();
    const double scale = std::max({std::abs(a), std::abs(b), 1e-12});
    const bool near_zero = !kantz.fit.diverging && !rosenstein.fit.diverging;
    if (!near_zero && std::abs(a - b) > 0.15 * scale && headline["quality"] == "good") {
      headline["quality"] = "uncertain";
      headline["reason"] = headline["reason"].get<std::string>() +
                           fmt::format("; Rosenstein gives {:.4g} (differs by more than 15 %)", b);
    } else {
      headline["reason"] = headline["reason"].get<std::string>() +
                           fmt::format("; Rosenstein agrees: {:.4g}", b);
    }
  }
  auto per_time = [&](Json e) {
    for (const char* key : {"value", "ci_low", "ci_high"})
      if (e[key].is_number()) e[key] = e[key].get<double>() / dt;
    return e;
  };
  Json out;
  out["lyapunov_max_per_sample"] = headline;
  out["lyapunov_max_per_" + series.sample_unit] = per_time(headline);
  out["kantz_per_sample"] = k_est;
  out["rosenstein_per_sample"] = r_est;
  out["sample_interval"] = dt;
  out["delay_samples"] = embedding.delay;
  out["embedding_dimension"] = embedding.dimension;
  out["theiler_window_samples"] = embedding.theiler;
  out["embedding_source"] = embedding.source;
  out["kantz_radius"] = curves.radius;
  out["reference_points"] = curves.references;
  out["kantz"] = curve_json(kantz);
  out["rosenstein"] = curve_json(rosenstein);
  if (const auto count = nonlinear::given_integer(params_, "radius_scan_count"))
    out["kantz_scan"] = radius_scan(x, embedding, steps, curves.references, std::size_t(*count));
  return out;
}

void LyapunovAnalysis::plot(const Json& result, const SampledSeries& series,
                            const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  plot::Curves c;
  c.title = fmt::format("{}: divergence of neighbouring trajectories", title);
  c.x_label = fmt::format("time after start k dt [{}]", series.sample_unit);
  c.y_label = "< ln distance > (mean log separation)";
  const double dt = series.sample_interval;
  for (const char* method : {"kantz", "rosenstein"}) {
    const Json& m = result[method];
    const std::string name = method == std::string("kantz") ? "Kantz" : "Rosenstein";
    plot::Series curve{name + " S(k)", {}, {}, "lines"};
    for (std::size_t k = 0; k < m["divergence"].size(); ++k)
      if (m["divergence"][k].is_number()) {
        curve.x.push_back(double(k) * dt);
        curve.y.push_back(m["divergence"][k].get<double>());
      }
    if (!curve.x.empty()) c.series.push_back(curve);
    const Json& e = result[method + std::string("_per_sample")];
    if (m["fit_begin_step"].is_number() && e["value"].is_number()) {
      const double slope = e["value"].get<double>(), b = m["fit_intercept"].get<double>();
      const auto k0 = m["fit_begin_step"].get<double>(), k1 = m["fit_end_step"].get<double>();
      c.series.push_back({fmt::format("{} fit: {:.4g} per {}", name, slope / dt,
                                      series.sample_unit),
                          {k0 * dt, k1 * dt},
                          {b + slope * k0, b + slope * k1},
                          "linespoints"});
    }
  }
  plot::render(c, out_dir, "lyapunov_divergence");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::LyapunovAnalysis);
