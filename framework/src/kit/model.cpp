// Study kit: the study's model and its certified rightmost root (chatterlab/kit/model.hpp).
#include "chatterlab/kit/model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <utility>

#include "chatterlab/errors.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::kit {

std::unique_ptr<Model> build_model(const Json& model_table) {
  Json params = model_table;
  params.erase("type");
  return model_registry()
      .at(model_table.at("type").get<std::string>())
      .create(ParamValues(std::move(params)));
}

std::unique_ptr<Model> validate_model(Json& document, ModelNeeds needs, const std::string& kind,
                                      const SourceMap& sources) {
  Json model_table = validate_component(document, "model", model_registry(), sources);
  std::unique_ptr<Model> model = build_model(model_table);
  const std::string type = model_table["type"].get<std::string>();
  auto refuse = [&](const char* what) {
    throw InputError(fmt::format("{}: model.type = \"{}\": this model has no {}, which the {} study needs",
                                 sources.locate("model.type").str(), type, what, kind));
  };
  if (has(needs, ModelNeeds::characteristic) && !model->characteristic())
    refuse("characteristic function (linear stability)");
  if (has(needs, ModelNeeds::time_domain) && !model->time_domain())
    refuse("time-domain form (simulation)");
  document["model"] = std::move(model_table);
  return model;
}

const ParamTable<StabilitySettings>& stability_settings_table() {
  static const ParamTable<StabilitySettings> table = [] {
    ParamTable<StabilitySettings> t;
    t.add(&StabilitySettings::max_frequency_hz, "max_frequency_hz", "Hz",
          fmt::format("search band |Im s| <= 2 pi max_frequency_hz (default: {} x the model's "
                      "highest structural natural frequency)",
                      default_band_multiple))
        .positive();
    t.add(&StabilitySettings::max_newton_iterations, "max_newton_iterations", "1",
          "Newton iterations per starting guess before the guess is abandoned")
        .at_least(1)
        .at_most(100000);
    t.add(&StabilitySettings::newton_relative_tolerance, "newton_relative_tolerance", "1",
          "Newton stops when its step is below this times |s|")
        .positive()
        .at_most(1e-3);
    t.add(&StabilitySettings::max_function_evaluations, "max_function_evaluations", "1",
          "work budget per grid point (evaluations of the characteristic function): beyond it the "
          "point is reported uncertified, or failed if no root was found yet")
        .at_least(1);
    return t;
  }();
  return table;
}

StabilitySettings validate_stability(Json& document, const Model& model, const SourceMap& sources) {
  StabilitySettings settings =
      validate_settings(document, "stability", stability_settings_table(), sources);
  // Checked here, not per point: a model without a characteristic function, or without a band,
  // is a study error (exit 2), not thousands of failed points.
  const std::string type = document.at("model").at("type").get<std::string>();
  auto characteristic = model.characteristic();
  if (!characteristic)
    throw InputError(fmt::format(
        "{}: model.type = \"{}\": this model has no characteristic function (linear stability), "
        "which the study's [stability] search needs",
        sources.locate("model.type").str(), type));
  if (!settings.max_frequency_hz) {
    const double scale = characteristic->natural_frequency_scale_hz();
    if (!(std::isfinite(scale) && scale > 0))
      throw InputError(fmt::format(
          "{}: missing key 'stability.max_frequency_hz': model '{}' has no structural frequency "
          "to derive the default search band from",
          sources.locate("stability").str(), type));
  }
  return settings;
}

RootSearchOptions root_search_options(const StabilitySettings& settings,
                                      const CharacteristicFunction& characteristic) {
  RootSearchOptions options;
  options.max_frequency_hz = settings.max_frequency_hz
                                 ? *settings.max_frequency_hz
                                 : default_band_multiple * characteristic.natural_frequency_scale_hz();
  options.max_newton_iterations = settings.max_newton_iterations;
  options.newton_relative_tolerance = settings.newton_relative_tolerance;
  options.max_function_evaluations = settings.max_function_evaluations;
  return options;
}

RightmostRoot rightmost_root(const Model& model, const StabilitySettings& settings) {
  auto characteristic = model.characteristic();
  if (!characteristic) throw PointFailure("the model has no characteristic function here");
  return find_rightmost_root(*characteristic, root_search_options(settings, *characteristic));
}

StabilityVerdict verdict(const RightmostRoot& root, const Model& model) {
  StabilityVerdict v;
  v.growth_rate_per_s = root.root.real();
  v.chatter_frequency_hz = std::abs(root.root.imag()) / (2 * std::numbers::pi);
  if (auto wheel_period = model.wheel_period_s())
    v.growth_rate_per_wheel_rev = *wheel_period * v.growth_rate_per_s / (2 * std::numbers::pi);
  v.stable = v.growth_rate_per_s < 0;
  return v;
}

}  // namespace chatterlab::kit
