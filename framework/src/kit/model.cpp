// Study kit: the study's model and its certified rightmost root (chatterlab/kit/model.hpp).
#include "chatterlab/kit/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "chatterlab/errors.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/process_conditions.hpp"
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
    t.add(&StabilitySettings::speed_tolerance, "speed_tolerance", "1",
          "relative speed tolerance of the spindles: verdicts are also evaluated over each speed "
          "in [1 - tol, 1 + tol] x nominal (models with process conditions; 0: nominal only)")
        .non_negative()
        .below(0.2);
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

std::string exact_ratio(double a, double b, int max_denominator) {
  if (!(a > 0.0) || !(b > 0.0)) return {};
  const double r = a / b;
  for (int q = 1; q <= max_denominator; ++q) {
    const double p = std::round(r * q);
    if (p >= 1.0 && std::abs(r * q - p) <= 1e-9 * r * q) {
      // Lowest terms: the first q that works is the smallest denominator.
      return fmt::format("{}/{}", static_cast<long>(p), q);
    }
  }
  return {};
}

namespace {

// Odd number of speed samples across the band of a rotor with delay period_s: four per lobe the
// chatter frequency passes through (the regenerative phase 2 pi f T changes by 2 pi f T 2 tol).
int band_samples(double chatter_frequency_hz, double period_s, double tolerance) {
  const double lobes = chatter_frequency_hz * period_s * 2.0 * tolerance;
  int n = static_cast<int>(std::ceil(4.0 * lobes)) + 1;
  n = std::clamp(n, 3, 33);
  return n % 2 == 1 ? n : n + 1;
}

}  // namespace

SpeedBandVerdict speed_band_verdict(const Json& model_table, const Model& model,
                                    const StabilitySettings& settings, const RightmostRoot& nominal) {
  SpeedBandVerdict band;
  const ProcessConditionsModel* process = model.process_conditions();
  const StabilityVerdict at_nominal = verdict(nominal, model);
  band.worst_growth_rate_per_s = at_nominal.growth_rate_per_s;
  band.worst_chatter_frequency_hz = at_nominal.chatter_frequency_hz;
  band.certified = nominal.certified;
  band.samples = 1;
  band.stable_over_band = at_nominal.stable;
  if (!process || !(settings.speed_tolerance > 0.0)) return band;
  band.applies = true;
  const ProcessConditions reference = process->nominal_conditions();
  band.worst_wheel_speed_rpm = reference.wheel_speed_rpm;
  band.worst_work_speed_rpm = reference.work_speed_rpm;
  band.exact_speed_ratio = exact_ratio(reference.wheel_speed_rpm, reference.work_speed_rpm);
  const double tol = settings.speed_tolerance;
  const int n_wheel = band_samples(at_nominal.chatter_frequency_hz, 60.0 / reference.wheel_speed_rpm, tol);
  const int n_work = band_samples(at_nominal.chatter_frequency_hz, 60.0 / reference.work_speed_rpm, tol);
  ProcessScaling scaling;
  scaling.speed_dependent_stiffness = false;  // the band moves the delays, not the process
  const Json type = {{"type", model_table.at("type")}};
  // Each rotor's speed across its band with the other at nominal (the regenerative lobes of the
  // two chains lie mostly along one axis each), and the four corners where both deviate.
  const int mid_wheel = n_wheel / 2, mid_work = n_work / 2;
  for (int i = 0; i < n_wheel; ++i)
    for (int j = 0; j < n_work; ++j) {
      const bool on_cross = i == mid_wheel || j == mid_work;
      const bool corner = (i == 0 || i == n_wheel - 1) && (j == 0 || j == n_work - 1);
      if ((i == mid_wheel && j == mid_work) || !(on_cross || corner)) continue;
      ProcessConditions at = reference;
      at.wheel_speed_rpm = reference.wheel_speed_rpm * (1.0 + tol * (2.0 * i / (n_wheel - 1) - 1.0));
      at.work_speed_rpm = reference.work_speed_rpm * (1.0 + tol * (2.0 * j / (n_work - 1) - 1.0));
      Json table = type;
      table.update(process->parameters_at(reference, at, scaling));
      auto sample = build_model(table);
      const RightmostRoot root = rightmost_root(*sample, settings);
      ++band.samples;
      band.certified = band.certified && root.certified;
      if (root.root.real() > band.worst_growth_rate_per_s) {
        band.worst_growth_rate_per_s = root.root.real();
        band.worst_chatter_frequency_hz = std::abs(root.root.imag()) / (2 * std::numbers::pi);
        band.worst_wheel_speed_rpm = at.wheel_speed_rpm;
        band.worst_work_speed_rpm = at.work_speed_rpm;
      }
    }
  band.stable_over_band = band.worst_growth_rate_per_s < 0.0;
  return band;
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
