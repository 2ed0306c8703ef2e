#pragma once
// The [lobes] and [time_to_chatter] tables of a stability_lobes study, declared once
// (chatterlab/param_table.hpp), and the model the study varies: its table with the limited
// parameter and the speed written in.
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "chatterlab/model.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/params.hpp"
#include "study_kinds/stability_lobes/lobe_tracer.hpp"

namespace chatterlab::lobes {

struct SpeedRange {
  double from = 0.0, to = 0.0;
  int steps = 100;
  bool log = false;
};

enum class RouteChoice { automatic, roots, nyquist };

struct LobesSettings {
  std::string parameter;                // "model.contact_stiffness_n_per_m" (or without "model.")
  std::vector<double> parameter_range;  // [low, high]
  std::string speed;                    // "work_speed_rpm" (or "model.work_speed_rpm")
  std::optional<std::vector<double>> speed_values;
  std::optional<SpeedRange> speed_range;
  std::optional<double> window_value;   // chatter-free windows at this value (default: the model's)
  RouteChoice route = RouteChoice::automatic;
  bool sensitivities = true;
};
const ParamTable<LobesSettings>& lobes_settings_table();

struct TimeToChatterSettings {
  double initial_waviness_um = 0.1;
  double tolerance_um = 1.0;
  double part_time_s = 20.0;
  int dressing_interval_parts = 10;
  int speed_steps = 30;
  int parameter_steps = 24;
  std::optional<std::vector<double>> parameter_range;  // default: [lobes] parameter_range
};
const ParamTable<TimeToChatterSettings>& time_to_chatter_table();

// The [model] table varied at the limited parameter and the speed (dotted paths below "model").
class VariedModel {
 public:
  VariedModel(Json model_table, std::string parameter_path, std::string speed_path);
  std::unique_ptr<Model> at(double parameter, double speed) const;
  // With one more key changed (a sensitivity).
  std::unique_ptr<Model> at(double parameter, double speed, const std::string& other_path, double other) const;
  double value(const std::string& path) const;  // the table's value at a path below "model"
  ModelAt model_at() const {
    return [this](double p, double v) { return at(p, v); };
  }
  // The real-valued keys of the model's declared parameters (and of its lists of tables), except
  // the limited parameter and the speed: what the boundary's sensitivity is computed for.
  std::vector<std::string> other_real_keys() const;
  const Json& table() const { return table_; }

 private:
  Json table_;
  Json::json_pointer parameter_, speed_;
  std::string parameter_path_, speed_path_;
};

// "model.modes.0.stiffness_n_per_m" or "modes.0.stiffness_n_per_m" -> "modes.0.stiffness_n_per_m".
std::string model_path(const std::string& key);
Json::json_pointer pointer_of(const std::string& path_below_model);

// The ascending, distinct speeds of the settings (speed_values or speed_range).
std::vector<double> speeds_of(const LobesSettings& settings);

Route route_of(const LobesSettings& settings, const Model& model);

}  // namespace chatterlab::lobes
