#include "analysis/surface_profile/surface_profile.hpp"

#include <algorithm>

#include "chatterlab/errors.hpp"
#include "chatterlab/plugin_info.hpp"
#include "shared/metrology/surface_report.hpp"

namespace chatterlab::surface {

namespace fs = std::filesystem;

PluginInfo SurfaceAnalysis::info() {
  std::vector<ParamSpec> params{unit_spec()};
  for (const auto& specs : {filter_specs(), process_specs(), parameter_specs()})
    params.insert(params.end(), specs.begin(), specs.end());
  // `type` names the plugin in a component table: the filter type is `filter` here.
  params[1].key = "filter";
  // Names are unique across registries: the kind is "surface".
  return plugin_info("surface_profile", "W1, W2", std::move(params), {{"cutoff_upr", 50}, {"unit", "m"}},
                     "waviness, MOTIF, roundness and Wz|f of a profile series (the surface study's evaluation)",
                     ThreadSafety::shareable);
}

SurfaceAnalysis::SurfaceAnalysis(const ParamValues& params) : params_(params.json()) {
  check_process(params_, "", [](const std::string&, const std::string& what) {
    throw InputError(what);
  });
}

SurfaceSettings SurfaceAnalysis::settings() const {
  // The flat parameters regrouped into the study kind's tables, read by the same code.
  Json document{{"input", Json::object()}, {"filter", Json::object()},
                {"process", Json::object()}, {"parameters", Json::object()}};
  auto take = [&](const std::vector<ParamSpec>& specs, const char* table) {
    for (const auto& spec : specs)
      document[table][spec.key] = params_.contains(spec.key) ? params_.at(spec.key) : Json();
  };
  take({unit_spec()}, "input");
  take(filter_specs(), "filter");
  document["filter"]["type"] = params_.at("filter");
  take(process_specs(), "process");
  take(parameter_specs(), "parameters");
  return settings_from(document);
}

Json SurfaceAnalysis::analyse(const SampledSeries& series, const Json& /*context*/) const {
  return evaluate_surface(series, settings());
}

ResultWithArrays SurfaceAnalysis::analyse_with_arrays(const SampledSeries& series, const Json& /*context*/) const {
  SurfaceEvaluation e = evaluate_surface_profile(series, settings());
  ResultWithArrays out;
  out.result = std::move(e.summary);
  out.add_array_only("waviness_um", std::move(e.waviness_um));
  return out;
}

void SurfaceAnalysis::plot(const Json& /*result*/, const SampledSeries& series,
                           const fs::path& out_dir) const {
  plot_closed(series, settings(), out_dir);
}

void SurfaceAnalysis::plot_closed(const SampledSeries& series, const SurfaceSettings& settings,
                                  const fs::path& out_dir) const {
  // The study kind's figures of a closed profile, drawn from a re-evaluation (the summary alone
  // does not hold the filtered profile): polar roundness and, with speeds, the Wz|f bands.
  if (!series.closed) return;
  const SurfaceEvaluation e = evaluate_surface_profile(series, settings);
  const std::string title = series.name.empty() ? std::string("profile") : series.name;
  plot_polar(e, title, out_dir, "surface_profile_polar");
  if (e.summary.contains("Wz_f")) plot_bands(e, title, out_dir, "surface_profile_wz_f_bands");
}

std::vector<ParamSpec> SurfaceAnalysis::measurement_params() const {
  std::vector<ParamSpec> specs = info().params;
  std::erase_if(specs, [](const ParamSpec& spec) { return spec.key == unit_spec().key; });
  return specs;
}

std::optional<ProfileQualityMeasurement::SettingProblem> SurfaceAnalysis::setting_problem(bool closed_profile) const {
  const Json& cutoff_mm = params_.contains("cutoff_mm") ? params_.at("cutoff_mm") : Json();
  if (closed_profile && cutoff_mm.is_number())
    return SettingProblem{"cutoff_mm", cutoff_mm, "a closed profile takes its cut-off in undulations per revolution: "
                                                  "give cutoff_upr"};
  return std::nullopt;
}

SurfaceSettings SurfaceAnalysis::settings_in_metres(const ProfileSpeeds& speeds, bool& speeds_from_caller) const {
  SurfaceSettings s = settings();
  s.value_to_um = unit_to_um("m");
  speeds_from_caller = !s.work_speed_rpm && speeds.work_speed_rpm > 0.0 && speeds.wheel_speed_rpm > 0.0;
  if (speeds_from_caller) {
    s.wheel_speed_rpm = speeds.wheel_speed_rpm;
    s.work_speed_rpm = speeds.work_speed_rpm;
  }
  return s;
}

ProfileQuality SurfaceAnalysis::measure_profile(const SampledSeries& profile_m, const ProfileSpeeds& speeds) const {
  ProfileQuality q;
  const SurfaceSettings s = settings_in_metres(speeds, q.speeds_from_caller);
  q.report = evaluate_surface(profile_m, s);
  auto number = [&](const char* key) -> std::optional<double> {
    const Json& v = q.report.contains(key) ? q.report.at(key) : Json();
    return v.is_number() ? std::optional<double>(v.get<double>()) : std::nullopt;
  };
  q.waviness_wt_um = number("Wt_um");
  q.waviness_wz_um = number("Wz_um");
  q.roundness_ront_um = number("RONt_um");
  if (s.work_speed_rpm && s.wheel_speed_rpm) q.speeds = ProfileSpeeds{*s.wheel_speed_rpm, *s.work_speed_rpm};
  return q;
}

void SurfaceAnalysis::plot_profile(const SampledSeries& profile_m, const ProfileSpeeds& speeds,
                                   const fs::path& out_dir) const {
  bool from_caller = false;
  plot_closed(profile_m, settings_in_metres(speeds, from_caller), out_dir);
}

}  // namespace chatterlab::surface

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::surface::SurfaceAnalysis);
