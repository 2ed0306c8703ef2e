#include "analysis/embedding/embedding.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "shared/nonlinear/embedding_choice.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {
Json vector_json(const std::vector<double>& v) { return Json(v); }
}  // namespace

template <>
PluginInfo EmbeddingAnalysis::info() {
  using nonlinear::numeric_spec;
  ParamSpec delay = nonlinear::delay_spec();
  delay.description = "fixed delay instead of the AMI choice (absent: automatic)";
  return plugin_info("embedding", "N1",
                     {
                         numeric_spec("max_delay_samples", ValueKind::integer, "samples",
                                      "largest lag searched for the AMI minimum (absent: N/10, at most 1000)", Json(),
                                      2),
                         delay,
                         numeric_spec("histogram_bins", ValueKind::integer, "1", "bins of the AMI histogram estimator",
                                      embedding_default_bins, 4, 256),
                         numeric_spec("max_dimension", ValueKind::integer, "1",
                                      "largest embedding dimension examined by FNN and Cao", embedding_default_max_dimension, 2,
                                      30),
                         numeric_spec("fnn_distance_ratio", ValueKind::real, "1",
                                      "a neighbour is false when the added coordinate separates it by more than this "
                                      "times the distance (Kennel's R_tol)",
                                      embedding_default_distance_ratio, 0, 1000, true),
                         numeric_spec("fnn_threshold", ValueKind::real, "1",
                                      "the embedding dimension is the first whose false-neighbour fraction is at most "
                                      "this",
                                      embedding_default_fnn_threshold, 0, 1, true),
                     },
                     {{"max_dimension", 6}},
                     "delay by average mutual information, embedding dimension by false nearest neighbours and "
                     "Cao's method, Theiler window by space-time separation",
                     ThreadSafety::shareable);
}

template <>
Json EmbeddingAnalysis::analyse(const SampledSeries& series, const Json& /*context*/) const {
  const auto& x = series.values;
  const std::string name = series.name.empty() ? std::string("series") : series.name;
  const int max_dimension = int(params_.integer("max_dimension"));
  nonlinear::check_series(x, 2, 1, name);
  const auto given_lag = nonlinear::given_integer(params_, "max_delay_samples");
  const std::size_t max_lag = given_lag ? std::size_t(*given_lag) : embedding_default_max_lag(x.size());
  const EmbeddingChoice c =
      choose_embedding(x, std::max<std::size_t>(max_lag, 3), int(params_.integer("histogram_bins")),
                 max_dimension, params_.real("fnn_distance_ratio"), params_.real("fnn_threshold"),
                 params_.json().contains("delay_samples") ? params_.json()["delay_samples"] : Json());

  Json out;
  const double dt = series.sample_interval;
  out["delay_samples"] = nonlinear::estimate(
      c.delay.delay, c.delay.delay, c.delay.delay,
      c.delay.from_mutual_information || c.delay.rule.rfind("given", 0) == 0 ? "good"
                                                                             : "uncertain",
      c.delay.rule);
  if (series.sample_unit != "sample") out["delay_" + series.sample_unit] = c.delay.delay * dt;
  const auto& d = c.dimension;
  std::string quality = "good", reason;
  if (d.fnn_dimension > 0 && d.cao_dimension > 0) {
    reason = fmt::format("false nearest neighbours <= {:g} at dimension {}; Cao E1 saturates at {}",
                         params_.real("fnn_threshold"), d.fnn_dimension, d.cao_dimension);
    if (std::abs(d.fnn_dimension - d.cao_dimension) > 1) quality = "uncertain";
  } else if (d.fnn_dimension > 0) {
    reason = fmt::format("false nearest neighbours at dimension {}; Cao's E1 does not saturate",
                         d.fnn_dimension);
    quality = "uncertain";
  } else if (d.cao_dimension > 0) {
    reason = fmt::format("false nearest neighbours stay above {:g} up to dimension {}: Cao's E1 "
                         "saturation at {} used",
                         params_.real("fnn_threshold"), max_dimension, d.cao_dimension);
    quality = "uncertain";
  } else {
    reason = fmt::format("neither false nearest neighbours nor Cao's E1 saturate up to dimension "
                         "{}: noise-like or high-dimensional signal",
                         max_dimension);
    quality = "failed";
  }
  if (!d.deterministic) reason += "; Cao's E2 stays near 1 (no sign of determinism)";
  const int lo = std::min(d.fnn_dimension > 0 ? d.fnn_dimension : c.chosen_dimension,
                          d.cao_dimension > 0 ? d.cao_dimension : c.chosen_dimension);
  const int hi = std::max(d.fnn_dimension > 0 ? d.fnn_dimension : c.chosen_dimension,
                          d.cao_dimension > 0 ? d.cao_dimension : c.chosen_dimension);
  out["embedding_dimension"] =
      nonlinear::estimate(c.chosen_dimension, lo, hi, quality, reason);
  out["fnn_dimension"] = d.fnn_dimension;
  out["cao_dimension"] = d.cao_dimension;
  out["deterministic"] = d.deterministic;
  out["cao_e2_max_deviation"] = d.e2_max_deviation;
  out["theiler_window_samples"] = nonlinear::estimate(
      double(c.theiler.window), double(c.theiler.window), double(c.theiler.window),
      c.theiler.window < x.size() / 10 ? "good" : "uncertain", c.theiler.rule);
  out["mutual_information_nats"] = vector_json(c.delay.mutual_information);
  out["autocorrelation"] = vector_json(c.delay.autocorrelation);
  out["fnn_fraction"] = vector_json(d.fnn_fraction);
  out["cao_e1"] = vector_json(d.cao_e1);
  out["cao_e2"] = vector_json(d.cao_e2);
  out["space_time_separation_samples"] = vector_json(c.theiler.separations);
  out["space_time_contour"] = vector_json(c.theiler.contour);
  return out;
}

template <>
void EmbeddingAnalysis::plot(const Json& result, const SampledSeries& series,
                             const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  {
    plot::Curves ami;
    ami.title = fmt::format("{}: average mutual information", title);
    ami.x_label = "lag [samples]";
    ami.y_label = "mutual information [nats]";
    const int delay = result["delay_samples"]["value"].get<int>();
    // Lags up to 5 delays (at least 50): the first minimum, not the long tail, is the point.
    auto mi = result["mutual_information_nats"].get<std::vector<double>>();
    mi.resize(std::min(mi.size(), std::size_t(std::max(50, 5 * delay)) + 1));
    plot::Series curve{"AMI", {}, mi, "linespoints"};
    for (std::size_t k = 0; k < mi.size(); ++k) curve.x.push_back(double(k));
    ami.series.push_back(curve);
    if (std::size_t(delay) < mi.size())
      ami.series.push_back({fmt::format("chosen delay {} samples", delay),
                            {double(delay)},
                            {mi[std::size_t(delay)]},
                            "points"});
    plot::render(ami, out_dir, "embedding_ami");
  }
  {
    plot::Curves fnn;
    fnn.title = fmt::format("{}: false nearest neighbours and Cao's E1, E2", title);
    fnn.x_label = "embedding dimension d";
    fnn.integer_x = true;
    fnn.y_label = "FNN fraction, E1(d), E2(d)";
    auto add = [&](const char* key, const char* label) {
      const auto v = result[key].get<std::vector<double>>();
      plot::Series s{label, {}, v, "linespoints"};
      for (std::size_t k = 0; k < v.size(); ++k) s.x.push_back(double(k + 1));
      fnn.series.push_back(s);
    };
    add("fnn_fraction", "false nearest neighbour fraction");
    add("cao_e1", "Cao E1");
    add("cao_e2", "Cao E2");
    const int d = result["embedding_dimension"]["value"].get<int>();
    fnn.series.push_back({fmt::format("chosen dimension {}", d), {double(d)}, {0.0}, "points"});
    plot::render(fnn, out_dir, "embedding_fnn");
  }
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::EmbeddingAnalysis);
