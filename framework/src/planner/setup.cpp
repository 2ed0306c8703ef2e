#include "planner/setup.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/signal_io.hpp"
#include "planner/geometry.hpp"

namespace chatterlab::planner {

std::unique_ptr<Kinematics> build_kinematics(const Json& machine) {
  Json params = machine;
  params.erase("type");
  for (const char* key : machine_constraint_keys) params.erase(key);
  return kinematics_registry().at(machine.at("type").get<std::string>()).create(ParamValues(std::move(params)));
}

namespace {

double number_or(const Json& table, const char* key, double fallback) {
  return table.contains(key) && table[key].is_number() ? table[key].get<double>() : fallback;
}

std::string string_or(const Json& table, const char* key, const std::string& fallback) {
  return table.contains(key) && table[key].is_string() ? table[key].get<std::string>() : fallback;
}

}  // namespace

PartGeometry build_part(const Json& part) {
  PartGeometry out;
  out.resolution_mm = number_or(part, "geometry_resolution_mm", default_geometry_resolution_mm);
  if (!(part.contains("points_file") && part["points_file"].is_string())) {
    const auto range = part.at("x_range_mm").get<std::vector<double>>();
    out.generatrix = expression_generatrix(part.at("generatrix").get<std::string>(), range.at(0), range.at(1));
    return out;
  }
  // Point table: first column x (mm), second y (mm).
  const DataTable table = read_data_table(part["points_file"].get<std::string>());
  if (table.columns.size() < 2)
    throw InputError(fmt::format("{}: needs two columns, x_mm and y_mm", table.file.string()));
  out.table_x_mm = table.columns[0];
  out.table_y_mm = table.columns[1];
  out.smoothing = string_or(part, "smoothing", "cross_validated");
  const std::size_t n = out.table_x_mm.size();
  if (out.smoothing == "none") {
    out.generatrix = spline_generatrix(out.table_x_mm, out.table_y_mm);
    return out;
  }
  out.fit = out.smoothing == "tolerance"
                ? tolerance_spline(out.table_x_mm, out.table_y_mm, part.at("smoothing_tolerance_mm").get<double>())
                : cross_validated_spline(out.table_x_mm, out.table_y_mm);
  out.generatrix = cubic_spline_generatrix(
      out.fit->spline,
      fmt::format("smoothing spline through {} points ({}, RMS residual {:.3g} mm)", n, out.smoothing,
                  out.fit->residual_rms_mm));
  out.interpolating = spline_generatrix(out.table_x_mm, out.table_y_mm);
  return out;
}

std::unique_ptr<Generatrix> build_generatrix(const Json& part) { return build_part(part).generatrix; }

ParamSpec relative_rate_change_spec() {
  ParamSpec delta = positive_spec("max_relative_rate_change", "1",
                                  "delta: largest relative change of a motor's pulse rate between "
                                  "consecutive segments, |f_q - f_h| / f_q");
  delta.max = 1.0;
  delta.max_exclusive = true;
  return delta;
}

ParamSpec controller_tick_spec() {
  ParamSpec tick = positive_spec("controller_tick_hz", "1/s",
                                 "time resolution of steps.csv, ticks per second (default: 100 per "
                                 "step at the fastest motor's top rate, at least 1e6)");
  tick.optional = true;
  return tick;
}

double controller_tick_hz(const Json& plan, const std::vector<MotorAxis>& motors) {
  if (plan.contains("controller_tick_hz") && plan["controller_tick_hz"].is_number())
    return plan["controller_tick_hz"].get<double>();
  double fastest = 0.0;
  for (const MotorAxis& m : motors) fastest = std::max(fastest, m.max_pulse_rate_hz);
  return std::max(1e6, std::pow(10.0, std::ceil(std::log10(std::max(100.0 * fastest, 1.0)))));
}

ParamSpec start_stop_rate_spec() {
  ParamSpec start_stop = positive_spec(
      "start_stop_rate_hz", "1/s",
      "start-stop rate: a motor may change its rate by this much in one step where the relative "
      "rule does not apply (start, stop, reversal, low rates); default delta x max pulse rate");
  start_stop.optional = true;
  return start_stop;
}

RateRules build_rate_rules(const Json& machine, const Json& plan, const Kinematics& kinematics) {
  RateRules rules;
  rules.max_relative_rate_change = machine.at("max_relative_rate_change").get<double>();
  if (plan.contains("start_stop_rate_hz") && plan["start_stop_rate_hz"].is_number()) {
    rules.start_stop_rate_hz = plan["start_stop_rate_hz"].get<double>();
  } else {
    double slowest = 1e300;
    for (const MotorAxis& m : kinematics.motors()) slowest = std::min(slowest, m.max_pulse_rate_hz);
    rules.start_stop_rate_hz = rules.max_relative_rate_change * slowest;
  }
  return rules;
}

FeedConstraints build_constraints(const Json& machine, const Json& plan, const Kinematics& kinematics) {
  FeedConstraints c;
  const Json& speed = machine.at("spindle_speed_rpm");
  // A range: the highest speed, since the axial-advance bound per revolution is the only
  // planning constraint that depends on it and it grows with the speed (docs/planner.md).
  c.spindle_speed_rpm = speed.is_object() ? speed.at("to").get<double>() : speed.get<double>();
  c.max_axial_advance_mm_per_100_rev = machine.at("max_axial_advance_mm_per_100_rev").get<double>();
  const RateRules rules = build_rate_rules(machine, plan, kinematics);
  c.max_relative_rate_change = rules.max_relative_rate_change;
  c.start_stop_rate_hz = rules.start_stop_rate_hz;
  return c;
}

WheelSection build_wheel(const Json& wheel) {
  WheelSection w;
  w.profiled = wheel.at("type").get<std::string>() == "profiled";
  w.thickness_mm = wheel.at("thickness_mm").get<double>();
  if (wheel.contains("edge_radius_mm") && wheel["edge_radius_mm"].is_number())
    w.edge_radius_mm = wheel["edge_radius_mm"].get<double>();
  w.edge_angle_deg = wheel.at("edge_angle_deg").get<double>();
  return w;
}

std::function<ToolContact(double)> wheel_contact(const WheelSection& wheel) {
  if (!wheel.profiled) return nullptr;
  const double r = wheel.edge_radius_mm;
  return [r](double s) {
    const double phi = s / r;
    return ToolContact{r * std::sin(phi), r * (1.0 - std::cos(phi)), phi};
  };
}

double sweep_half_width_mm(const WheelSection& wheel) {
  return wheel.profiled ? wheel.edge_radius_mm * 0.5 * wheel.edge_angle_deg * std::numbers::pi / 180.0
                        : 0.5 * wheel.thickness_mm;
}

WearSweep build_sweep(const Json& plan, const Json& wheel) {
  WearSweep s;
  s.law = plan.at("wear_sweep").get<std::string>();
  const Json& amplitude = plan.at("wear_sweep_amplitude_mm");
  s.amplitude_mm = amplitude.is_number() ? amplitude.get<double>() : sweep_half_width_mm(build_wheel(wheel));
  s.period_mm = plan.at("wear_sweep_period_mm").get<double>();
  s.steps = plan.at("wear_sweep_steps").get<int>();
  return s;
}

double segment_length_mm(const Json& plan, const FeedConstraints& constraints) {
  // Default: one second at the axial-speed bound (seed 000's 1 s segments).
  return number_or(plan, "segment_length_mm", constraints.max_axial_speed_mm_per_s() * 1.0);
}

ToleranceSettings build_tolerance(const Json& plan, const FeedConstraints& constraints) {
  ToleranceSettings t;
  t.max_profile_error_mm = number_or(plan, "max_profile_error_mm", t.max_profile_error_mm);
  t.segment_length_mm = segment_length_mm(plan, constraints);
  t.min_segment_length_mm =
      std::min(number_or(plan, "min_segment_length_mm", t.min_segment_length_mm), t.segment_length_mm);
  return t;
}

}  // namespace chatterlab::planner

namespace chatterlab::planner {

Json p2_machine_params() {
  return {{"pivot_to_nut_mm", 300.0}, {"fixture_to_pivot_mm", 250.0}, {"screw_pitch_mm", 12.0},
          {"gear_ratio", 10.0},       {"step_angle_deg", 1.0},        {"max_pulse_rate_hz", 100.0}};
}

// FeedConstraints' defaults are P2's rules (scheduler.hpp).
FeedConstraints p2_constraints() { return FeedConstraints{}; }

}  // namespace chatterlab::planner
