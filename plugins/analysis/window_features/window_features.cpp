#include "analysis/window_features/window_features.hpp"

#include <fmt/format.h>

#include "shared/monitoring/monitor_common.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

PluginInfo WindowFeaturesAnalysis::info() {
  const ParamSpec window =
      monitor::count_spec("window_samples", "samples per window (the book uses 10)", 10, 3);
  ParamSpec hop = param_spec("hop_samples", ValueKind::integer, "1",
                             "samples between window starts (default: window_samples, i.e. "
                             "consecutive non-overlapping windows)");
  hop.min = 1;
  hop.optional = true;
  return plugin_info("window_features", "C1",
                     {window, hop},
                     {{"window_samples", 10}},
                     "per-window variance, lag-1 correlation and AR(1) residual variance of a signal",
                     ThreadSafety::shareable);
}

WindowFeaturesAnalysis::WindowFeaturesAnalysis(const ParamValues& params)
    : window_(static_cast<std::size_t>(params.integer("window_samples"))),
      hop_(params.has("hop_samples") ? static_cast<std::size_t>(params.integer("hop_samples"))
                                     : window_) {}

Json WindowFeaturesAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  return analyse_with_arrays(series, context).merged();
}

ResultWithArrays WindowFeaturesAnalysis::analyse_with_arrays(const SampledSeries& series,
                                                             const Json& /*context*/) const {
  monitor::require_samples(series, window_,
                           fmt::format("window_features.window_samples = {}", window_));
  FeatureSeries fs = feature_series(series.values, window_, hop_, series.sample_interval);
  std::vector<double> variance, rho1, residual;
  variance.reserve(fs.features.size());
  rho1.reserve(fs.features.size());
  residual.reserve(fs.features.size());
  for (const auto& f : fs.features) {
    variance.push_back(f.variance);
    rho1.push_back(f.rho1);
    residual.push_back(f.residual_variance);
  }
  ResultWithArrays out;
  out.result["window_samples"] = window_;
  out.result["hop_samples"] = hop_;
  out.add("t_s", std::move(fs.t_s));
  out.add("variance", std::move(variance));
  out.add("rho1", std::move(rho1));
  out.add("residual_variance", std::move(residual));
  return out;
}

void WindowFeaturesAnalysis::plot(const Json& result, const SampledSeries& series,
                                  const std::filesystem::path& out_dir) const {
  const auto t = result.at("t_s").get<std::vector<double>>();
  const std::string unit = series.sample_unit;
  plot::Curves variances;
  variances.title = fmt::format("C1 window features ({} samples per window): variances",
                                result.at("window_samples").get<std::size_t>());
  variances.x_label = fmt::format("time of the window's last sample [{}]", unit);
  variances.y_label = "variance [signal unit^2]";
  variances.log_y = true;
  variances.series.push_back({"variance sx2 (5-9)", t, result.at("variance").get<std::vector<double>>()});
  variances.series.push_back({"AR(1) residual variance sa2 (5-10)", t,
                              result.at("residual_variance").get<std::vector<double>>()});
  plot::render(variances, out_dir, "window_features_variance");
  plot::Curves rho;
  rho.title = "C1 window features: lag-1 correlation rho1 (5-8)";
  rho.x_label = variances.x_label;
  rho.y_label = "rho1 [1]";
  rho.series.push_back({"rho1", t, result.at("rho1").get<std::vector<double>>()});
  plot::render(rho, out_dir, "window_features_rho1");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::WindowFeaturesAnalysis);
