#include "study_kinds/stability_lobes/lobes_settings.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "chatterlab/kit/model.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab::lobes {

const ParamTable<LobesSettings>& lobes_settings_table() {
  static const ParamTable<LobesSettings> table = [] {
    ParamTable<SpeedRange> range;
    range.add(&SpeedRange::from, "from", "1", "first speed (in the speed key's unit)").positive().required();
    range.add(&SpeedRange::to, "to", "1", "last speed (in the speed key's unit)").positive().required();
    range.add(&SpeedRange::steps, "steps", "1", "number of speeds, ends included").at_least(2).at_most(100000);
    range.add(&SpeedRange::log, "log", "1", "geometric instead of linear spacing");
    using S = LobesSettings;
    ParamTable<S> t;
    t.add(&S::parameter, "parameter", "", "the limited parameter: a numeric key of [model], e.g. \"model.contact_stiffness_n_per_m\"").required();
    t.add(&S::parameter_range, "parameter_range", "1", "[low, high]: where to look for its critical value (the parameter's unit; > 0)").positive().min_items(2).required();
    t.add(&S::speed, "speed", "", "the [model] key swept along the x axis, e.g. \"work_speed_rpm\"").required();
    t.add(&S::speed_values, "speed_values", "1", "the speeds (the speed key's unit); or speed_range").positive().min_items(2);
    t.add_optional_table(&S::speed_range, "speed_range", "{ from, to, steps, log }: the speeds as a range; or speed_values", range);
    t.add(&S::window_value, "window_value", "1", "chatter-free windows are marked where the limit exceeds this value (default: the model's value of the parameter)").positive();
    t.add_choice(&S::route, "route", "stability route: auto (roots when the model has a characteristic function, else the Nyquist count), roots, nyquist",
                 {{"auto", RouteChoice::automatic}, {"roots", RouteChoice::roots}, {"nyquist", RouteChoice::nyquist}});
    t.add(&S::sensitivities, "sensitivities", "1", "compute the limit's sensitivity to every other real model parameter");
    return t;
  }();
  return table;
}

const ParamTable<TimeToChatterSettings>& time_to_chatter_table() {
  static const ParamTable<TimeToChatterSettings> table = [] {
    using T = TimeToChatterSettings;
    ParamTable<T> t;
    t.add(&T::initial_waviness_um, "initial_waviness_um", "um", "waviness amplitude at the start (after dressing)").positive();
    t.add(&T::tolerance_um, "tolerance_um", "um", "waviness tolerance: chatter 'arrives' when the amplitude exceeds it").positive();
    t.add(&T::part_time_s, "part_time_s", "s", "grinding time per part").positive();
    t.add(&T::dressing_interval_parts, "dressing_interval_parts", "1", "parts ground between two dressings of the wheel").at_least(1);
    t.add(&T::speed_steps, "speed_steps", "1", "map resolution along the speed range").at_least(2).at_most(1000);
    t.add(&T::parameter_steps, "parameter_steps", "1", "map resolution along the parameter").at_least(2).at_most(1000);
    t.add(&T::parameter_range, "parameter_range", "1", "[low, high] of the map (default: [lobes] parameter_range)").positive().min_items(2);
    return t;
  }();
  return table;
}

std::string model_path(const std::string& key) {
  return key.rfind("model.", 0) == 0 ? key.substr(6) : key;
}

Json::json_pointer pointer_of(const std::string& path) {
  std::string pointer;
  for (std::size_t start = 0;;) {
    const std::size_t dot = path.find('.', start);
    pointer += '/';
    pointer += path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return Json::json_pointer(pointer);
}

VariedModel::VariedModel(Json model_table, std::string parameter_path, std::string speed_path)
    : table_(std::move(model_table)),
      parameter_(pointer_of(parameter_path)),
      speed_(pointer_of(speed_path)),
      parameter_path_(std::move(parameter_path)),
      speed_path_(std::move(speed_path)) {}

std::unique_ptr<Model> VariedModel::at(double parameter, double speed) const {
  Json t = table_;
  t[parameter_] = parameter;
  t[speed_] = speed;
  return kit::build_model(t);
}

std::unique_ptr<Model> VariedModel::at(double parameter, double speed, const std::string& other_path, double other) const {
  Json t = table_;
  t[parameter_] = parameter;
  t[speed_] = speed;
  t[pointer_of(other_path)] = other;
  return kit::build_model(t);
}

double VariedModel::value(const std::string& path) const { return table_.at(pointer_of(path)).get<double>(); }

std::vector<std::string> VariedModel::other_real_keys() const {
  const PluginInfo& info = model_registry().at(table_.at("type").get<std::string>()).info;
  std::vector<std::string> keys;
  auto add = [&](const std::string& path, const Json& v) {
    if (v.is_number() && path != parameter_path_ && path != speed_path_ && v.get<double>() != 0.0) keys.push_back(path);
  };
  for (const ParamSpec& spec : info.params) {
    if (!table_.contains(spec.key)) continue;
    const Json& v = table_.at(spec.key);
    if (spec.kind == ValueKind::real) add(spec.key, v);
    if (spec.kind == ValueKind::table_list)
      for (std::size_t i = 0; i < v.size(); ++i)
        for (const ParamSpec& field : spec.fields)
          if (field.kind == ValueKind::real && v[i].contains(field.key))
            add(fmt::format("{}.{}.{}", spec.key, i, field.key), v[i].at(field.key));
  }
  return keys;
}

std::vector<double> speeds_of(const LobesSettings& s) {
  std::vector<double> v;
  if (s.speed_values) v = *s.speed_values;
  if (s.speed_range) {
    const SpeedRange& r = *s.speed_range;
    for (int i = 0; i < r.steps; ++i) {
      const double t = static_cast<double>(i) / (r.steps - 1);
      v.push_back(i == r.steps - 1 ? r.to : r.log ? r.from * std::pow(r.to / r.from, t) : r.from + t * (r.to - r.from));
    }
  }
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

Route route_of(const LobesSettings& s, const Model& model) {
  if (s.route == RouteChoice::roots) return Route::roots;
  if (s.route == RouteChoice::nyquist) return Route::nyquist;
  return model.characteristic() ? Route::roots : Route::nyquist;
}

}  // namespace chatterlab::lobes
