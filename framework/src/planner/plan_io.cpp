#include "planner/plan_io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <optional>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab::planner {

namespace {

namespace fs = std::filesystem;

std::string position_key(const MotorAxis& m) {
  return (m.position_name.empty() ? m.name : m.position_name) + "_mm";
}

Json error_stats(const ErrorStats& s) {
  return {{"max_abs_mm", s.max_abs_mm}, {"mean_mm", s.mean_mm}, {"mean_abs_mm", s.mean_abs_mm},
          {"rms_mm", s.rms_mm}};
}

}  // namespace

Json certificate_json(const Certificate& c, const FeedPlan& plan, const RateRules& rules,
                      const Json& path_rule) {
  Json rates = Json::object();
  for (std::size_t m = 0; m < plan.motors.size(); ++m) rates[plan.motors[m].name] = c.max_pulse_rate_hz[m];
  Json out = {{"ok", c.ok},
              {"checked", "every segment and motor after integerisation: pulse rate <= "
                          "max_pulse_rate_hz, |r' - r| <= max(delta |r|, start_stop_rate_hz) between "
                          "consecutive segments, position drift <= 1/2 step at segment ends, and the "
                          "path rule"},
              {"max_pulse_rate_hz", rates},
              {"max_relative_rate_change", c.max_relative_rate_change},
              {"relative_rate_change_limit", rules.max_relative_rate_change},
              {"start_stop_rate_hz", rules.start_stop_rate_hz},
              {"rate_changes_under_start_stop_allowance", c.rate_changes_under_start_stop_allowance},
              {"max_rate_change_under_allowance_hz", c.max_rate_change_at_low_rate_hz},
              {"reversals", c.reversals},
              {"max_position_drift_steps", c.max_position_drift_steps},
              {"violations", c.violations}};
  out.update(path_rule);
  return out;
}

namespace {

// Plans the interpolating spline of a smoothed point table the same way: the cost of grinding
// the measurement noise in.
NoiseEffect noise_effect(const PlanRun& run, const std::function<double(double)>& sweep,
                         const std::function<ToolContact(double)>& contact) {
  NoiseEffect out;
  const Generatrix& raw = *run.part.interpolating;
  try {
    const TolerancePlan p =
        plan_to_tolerance(raw, *run.kinematics, run.constraints, run.tolerance_settings, sweep, contact);
    out.planned = true;
    out.total_time_s = p.schedule.plan.total_time_s();
    out.max_profile_error_mm = p.errors.total.max_abs_mm;
    out.reversals = p.schedule.certificate.reversals;
    out.segments = p.schedule.plan.segments.size();
    out.tolerance_met = p.met;
    out.max_edge_radius_mm =
        largest_edge_radius(raw, raw.analyse(run.part.resolution_mm)).radius_mm;
  } catch (const std::exception& e) {
    out.failure = e.what();
  }
  return out;
}

}  // namespace

void compute_plan(const Json& document, PlanRun& run) {
  const Json& machine = document.at("machine");
  const Json& plan = document.at("plan");
  const Json& wheel = document.at("wheel");
  run.part = build_part(document.at("part"));
  run.generatrix = std::move(run.part.generatrix);
  run.geometry = run.generatrix->analyse(run.part.resolution_mm);
  run.kinematics = build_kinematics(machine);
  run.constraints = build_constraints(machine, plan, *run.kinematics);
  run.sweep = build_sweep(plan, wheel);
  run.tolerance_settings = build_tolerance(plan, run.constraints);
  const WheelSection section = build_wheel(wheel);
  const auto sweep = sweep_function(run.sweep, run.generatrix->x_min_mm());
  const auto contact = wheel_contact(section);
  try {
    run.tolerance = plan_to_tolerance(*run.generatrix, *run.kinematics, run.constraints,
                                      run.tolerance_settings, sweep, contact);
  } catch (const std::exception& e) {
    throw PointFailure(fmt::format("no plan: {}", e.what()));
  }
  run.edge_limit = largest_edge_radius(*run.generatrix, run.geometry);
  run.wheel_edge_radius_limit_mm = wheel_geometry_edge_radius_mm(section);
  if (std::isfinite(run.edge_limit.radius_mm)) {
    run.max_edge_radius_mm = run.edge_limit.radius_mm;
    run.max_edge_radius_limited_by = run.edge_limit.local ? "concave_part" : "distant_part";
  } else {
    run.max_edge_radius_mm = run.wheel_edge_radius_limit_mm;
    run.max_edge_radius_limited_by = "wheel_geometry";
  }
  run.interference = check_interference_along_plan(run.schedule, *run.generatrix, *run.kinematics, section);
  std::vector<double> durations;
  for (const auto& seg : run.schedule.plan.segments) durations.push_back(seg.duration_s);
  run.wear = wear_distribution(run.schedule.contact_on_tool_mm, durations, sweep_half_width_mm(section));
  run.ramp_segments = ramp_segments(run.schedule.plan, run.constraints.rate_rules());
  if (!durations.empty())
    run.ramp_time_s = static_cast<double>(run.ramp_segments) * (durations.front() + durations.back());
  if (run.part.interpolating) run.noise = noise_effect(run, sweep, contact);

  // Controller output, read back and replayed: the program's plan through the same replay, the
  // step table's states through the forward kinematics.
  const double tick_hz = controller_tick_hz(plan, run.schedule.plan.motors);
  run.controller = export_plan(run.schedule.plan,
                               {"chatterlab feed_plan: " + run.generatrix->describe(),
                                "G93 inverse time: F = 60 / segment duration (docs/planner.md, Controller output)"},
                               tick_hz);
  Schedule reread = run.schedule;
  reread.plan = run.controller.from_gcode;
  run.gcode_replay_max_error_mm = replay_errors(reread, *run.generatrix, *run.kinematics).total.max_abs_mm;
  run.step_replay = replay_step_events(run.schedule, run.controller.events, tick_hz, *run.generatrix, *run.kinematics);

  // Certified: every rule, the tolerance and zero interference hold in the replay.
  auto& failures = run.certification_failures;
  if (!run.schedule.certificate.ok)
    failures.push_back("machine rules: " + run.schedule.certificate.violations.front());
  if (!run.tolerance.met)
    failures.push_back(fmt::format("max_profile_error_mm = {} not met ({}): {}",
                                   run.tolerance_settings.max_profile_error_mm, run.tolerance.limited_by,
                                   run.tolerance.limit_note));
  const Interference& hit = run.interference;
  if (hit.contacts_with_interference > 0)
    failures.push_back(fmt::format(
        "the wheel cuts {:.4g} mm into the part at x = {:.3f} mm (contact at x = {:.3f} mm, t = "
        "{:.1f} s; {} states in {} segments beyond {} mm)",
        hit.depth_mm, hit.x_mm, hit.contact_x_mm, hit.time_s, hit.contacts_with_interference,
        hit.segments_with_interference, hit.tolerance_mm));
  if (!run.controller.exact())
    failures.push_back("controller export: program.ngc or steps.csv read back differs from the plan");
  run.certified = failures.empty();
}

namespace {

Json tolerance_json(const PlanRun& run) {
  const TolerancePlan& t = run.tolerance;
  return {{"max_profile_error_mm", run.tolerance_settings.max_profile_error_mm},
          {"achieved_mm", t.errors.total.max_abs_mm},
          {"met", t.met},
          {"limited_by", t.met ? Json() : Json(t.limited_by)},
          {"note", t.met ? Json() : Json(t.limit_note)},
          {"rounds", t.rounds},
          {"segments_split", t.segments_split},
          {"first_knot_chosen", t.first_knot_chosen},
          {"shortest_segment_mm", t.shortest_segment_mm},
          {"longest_segment_mm", t.longest_segment_mm},
          {"min_segment_length_mm", run.tolerance_settings.min_segment_length_mm},
          {"binding_segments", t.binding_segments},
          {"binding", "segments whose replayed error uses >= 90 % of the tolerance"},
          {"linearisation_budget_mm",
           run.tolerance_settings.linearisation_share * run.tolerance_settings.max_profile_error_mm},
          {"method", "segment lengths from the chord error of the axis paths (budget: a share of "
                     "the tolerance), then segments over the tolerance in the replay split in two "
                     "until the replay meets it"}};
}

Json geometry_json(const PlanRun& run) {
  const GeometryAnalysis& g = run.geometry;
  return {{"resolution_mm", g.resolution_mm},
          {"method", g.method},
          {"evaluations", g.evaluations},
          {"max_concave_curvature_per_mm", g.max_concave_curvature_per_mm},
          {"max_concave_curvature_at_x_mm", g.max_concave_curvature_at_x_mm},
          {"max_concave_curvature_bound_per_mm", g.max_concave_curvature_bound_per_mm},
          {"max_turn_rate_rad_per_mm", g.max_turn_rate_rad_per_mm},
          {"max_turn_rate_at_x_mm", g.max_turn_rate_at_x_mm},
          {"turn_rate_limit_rad_per_mm", 1.0 / g.resolution_mm}};
}

Json controller_json(const PlanRun& run) {
  const ControllerExport& c = run.controller;
  const std::vector<char> letters = gcode_letters(run.schedule.plan);
  Json axes = Json::object();
  for (std::size_t m = 0; m < letters.size(); ++m)
    axes[std::string(1, letters[m])] = run.schedule.plan.motors[m].name;
  return {{"files", {"program.ngc", "steps.csv"}},
          {"gcode_axes", axes},
          {"tick_hz", c.tick_hz},
          {"round_trip",
           {{"exact", c.exact()},
            {"gcode_pulses_identical", c.check.gcode_pulses_identical},
            {"gcode_max_duration_error_s", c.check.gcode_max_duration_error_s},
            {"gcode_replay_max_profile_error_mm", run.gcode_replay_max_error_mm},
            {"step_events", c.check.step_events},
            {"step_positions_identical", c.check.step_positions_identical},
            {"step_max_time_error_s", c.check.step_max_time_error_s},
            {"step_replay_states", run.step_replay.states},
            {"step_replay_max_profile_error_mm", run.step_replay.total.max_abs_mm},
            {"step_replay_rms_profile_error_mm", run.step_replay.total.rms_mm}}},
          {"shortest_step_interval_s", c.check.shortest_step_interval_s},
          {"shortest_direction_setup_s",
           std::isfinite(c.check.shortest_direction_setup_s) ? Json(c.check.shortest_direction_setup_s) : Json()}};
}

Json point_table_json(const PlanRun& run) {
  const PartGeometry& p = run.part;
  Json j = {{"points", p.table_x_mm.size()}, {"smoothing", p.smoothing}};
  if (p.fit) {
    j["lambda_mm3"] = p.fit->lambda;
    j["residual_rms_mm"] = p.fit->residual_rms_mm;
    j["residual_max_mm"] = p.fit->residual_max_mm;
    j["effective_parameters"] = p.fit->effective_parameters;
    j["noise_estimate_mm"] = p.fit->noise_estimate_mm;
    j["gcv_score_mm2"] = p.fit->gcv_score;
  }
  if (p.interpolating) {
    const NoiseEffect& n = run.noise;
    const double t = run.schedule.plan.total_time_s();
    Json raw = {{"planned", n.planned}};
    if (n.planned) {
      raw["total_time_s"] = n.total_time_s;
      raw["time_change_percent"] = 100.0 * (n.total_time_s - t) / t;
      raw["reversals"] = n.reversals;
      raw["segments"] = n.segments;
      raw["max_profile_error_mm"] = n.max_profile_error_mm;
      raw["tolerance_met"] = n.tolerance_met;
      raw["max_edge_radius_mm"] = n.max_edge_radius_mm;
    } else {
      raw["failure"] = n.failure;
    }
    raw["note"] = "the natural spline through the raw points planned the same way: what grinding "
                  "the measurement noise in would cost (the plan follows the smoothed curve)";
    j["interpolating_spline"] = raw;
    j["smoothed"] = {{"total_time_s", t},
                     {"reversals", run.schedule.certificate.reversals},
                     {"max_edge_radius_mm", run.max_edge_radius_mm}};
  }
  return j;
}

}  // namespace

Json plan_summary(const PlanRun& run, const Json& document) {
  const Schedule& s = run.schedule;
  const FeedPlan& plan = s.plan;
  const double total = plan.total_time_s();
  Json initial = Json::object(), rates = Json::object(), steps = Json::object();
  for (std::size_t m = 0; m < plan.motors.size(); ++m) {
    initial[position_key(plan.motors[m])] = plan.initial_position_mm[m];
    rates[plan.motors[m].name] = s.certificate.max_pulse_rate_hz[m];
    steps[plan.motors[m].name] = plan.motors[m].mm_per_pulse;
  }
  const bool edge_limited = std::isfinite(run.edge_limit.radius_mm);
  const WheelSection wheel = build_wheel(document.at("wheel"));
  Json summary = {
      {"certified", run.certified},
      {"certification_failures", run.certification_failures},
      {"certification", "every machine rule after integerisation, the profile tolerance "
                        "(max_profile_error_mm) and zero wheel interference, all in the replay"},
      {"tolerance", tolerance_json(run)},
      {"geometry", geometry_json(run)},
      {"total_time_s", total},
      {"lower_bound_s", s.lower_bound_s},
      {"lower_bound_kind", "continuous relaxation: the exact path at the largest speed each "
                           "per-segment bound allows, without smoothness"},
      {"gap_percent", 100.0 * (total - s.lower_bound_s) / s.lower_bound_s},
      {"segments", plan.segments.size()},
      {"spindle_speed_rpm", plan.spindle_speed_rpm},
      {"x_start_mm", s.knots_mm.front()},
      {"x_end_mm", s.knots_mm.back()},
      {"initial_position", initial},
      {"mm_per_pulse", steps},
      {"max_pulse_rate_hz", rates},
      {"max_edge_radius_mm", run.max_edge_radius_mm},
      {"max_edge_radius_limited_by", run.max_edge_radius_limited_by},
      {"max_edge_radius_note",
       edge_limited
           ? fmt::format("set at x = {:.3f} mm by {}; the wheel itself carries at most {:.4g} mm "
                         "(arc width 2 r sin(alpha/2) <= thickness)", run.edge_limit.x_mm,
                         run.edge_limit.local ? "the radius of curvature of a concave part"
                                              : "a distant part of the profile (normal-line condition)",
                         run.wheel_edge_radius_limit_mm)
           : fmt::format("no part of the profile limits the edge radius (no concave part, any arc "
                         "tangent at a contact clears the part); the limit is the wheel's own: an "
                         "arc of opening {} deg fits the {} mm face up to r = {:.4g} mm",
                         wheel.edge_angle_deg, wheel.thickness_mm,
                         run.wheel_edge_radius_limit_mm)},
      {"edge_radius_limit_from_wheel_geometry_mm", run.wheel_edge_radius_limit_mm},
      {"min_concave_radius_of_curvature_mm",
       run.geometry.max_concave_curvature_per_mm > 0 ? Json(1.0 / run.geometry.max_concave_curvature_per_mm) : Json()},
      {"min_concave_radius_of_curvature_bound_mm",
       run.geometry.max_concave_curvature_bound_per_mm > 0
           ? Json(1.0 / run.geometry.max_concave_curvature_bound_per_mm) : Json()},
      {"max_profile_error_mm", run.errors.total.max_abs_mm},
      {"mean_profile_error_mm", run.errors.total.mean_mm},
      {"mean_abs_profile_error_mm", run.errors.total.mean_abs_mm},
      {"rms_profile_error_mm", run.errors.total.rms_mm},
      {"max_profile_error_at_x_mm", run.errors.x_at_max_mm},
      {"area_error_percent", run.errors.area_percent},
      {"error_split", {{"linearisation", error_stats(run.errors.linearisation)},
                       {"quantisation", error_stats(run.errors.quantisation)},
                       {"replayed_states", run.errors.states}}},
      {"certificate", certificate_json(s.certificate, plan, run.constraints.rate_rules(),
                                       {{"path_rule", "axial speed <= max_axial_advance_mm_per_100_rev"
                                                      " / 100 x spindle rev/s"},
                                        {"max_axial_speed_mm_per_s", s.certificate.max_axial_speed_mm_per_s},
                                        {"axial_speed_limit_mm_per_s",
                                         run.constraints.max_axial_speed_mm_per_s()}})},
      {"interference", {{"max_depth_mm", run.interference.depth_mm},
                        {"at_x_mm", run.interference.x_mm},
                        {"contact_x_mm", run.interference.contact_x_mm},
                        {"at_time_s", run.interference.time_s},
                        {"states_with_interference", run.interference.contacts_with_interference},
                        {"segments_with_interference", run.interference.segments_with_interference},
                        {"states_checked", run.interference.states_checked},
                        {"tolerance_mm", run.interference.tolerance_mm},
                        {"method", "every pulse state of the quantised plan through the forward "
                                   "kinematics; the wheel section probed against the generatrix; "
                                   "depth beyond the contact's own cut-in (the profile error)"}}},
      {"wear", {{"sweep", run.sweep.law},
                {"amplitude_mm", run.sweep.law == "none" ? 0.0 : run.sweep.amplitude_mm},
                {"period_mm", run.sweep.period_mm},
                {"used_face_width_mm", run.wear.used_width_mm},
                {"uniformity", run.wear.uniformity}}},
      {"pre_motion", {{"ramp_segments_each_end", run.ramp_segments},
                      {"ramp_time_s", run.ramp_time_s},
                      {"note", "approach and run-out ramps outside the part, not in total_time_s"}}},
      {"smoothing_passes", s.smoothing_passes},
      {"machine", document.at("machine")},
      {"part", document.at("part")},
      {"wheel", document.at("wheel")},
      {"plan", document.at("plan")}};
  if (!run.part.table_x_mm.empty()) summary["point_table"] = point_table_json(run);
  summary["controller_export"] = controller_json(run);
  return summary;
}

void write_plan_files(const PlanRun& run, const Json& document, const fs::path& dir, bool plots) {
  const Schedule& s = run.schedule;
  const FeedPlan& plan = s.plan;
  const std::size_t n = plan.segments.size(), motors = plan.motors.size();
  std::vector<std::string> header{"segment", "start_s", "duration_s"};
  for (const auto& m : plan.motors) header.push_back(m.name + "_pulses");
  std::vector<std::vector<double>> columns(header.size(), std::vector<double>(n));
  std::vector<std::vector<double>> seg_columns(6, std::vector<double>(n));
  for (std::size_t k = 0; k < n; ++k) {
    const PlanSegment& seg = plan.segments[k];
    columns[0][k] = static_cast<double>(k);
    columns[1][k] = seg.start_s;
    columns[2][k] = seg.duration_s;
    for (std::size_t m = 0; m < motors; ++m) columns[3 + m][k] = static_cast<double>(seg.pulses[m]);
    const double x0 = s.knots_mm[k], x1 = s.knots_mm[k + 1];
    seg_columns[0][k] = static_cast<double>(k);
    seg_columns[1][k] = x0;
    seg_columns[2][k] = x1;
    seg_columns[3][k] = run.generatrix->evaluate(0.5 * (x0 + x1)).f;
    seg_columns[4][k] = (x1 - x0) / seg.duration_s;
    seg_columns[5][k] = 0.5 * (s.contact_on_tool_mm[k] + s.contact_on_tool_mm[k + 1]);
  }
  write_file_atomically(dir / "pulses.csv", csv_text(header, columns));
  write_file_atomically(dir / "segments.csv",
                        csv_text({"segment", "x_start_mm", "x_end_mm", "radius_mm",
                                  "axial_speed_mm_per_s", "contact_on_wheel_mm"},
                                 seg_columns));
  write_file_atomically(dir / "program.ngc", run.controller.gcode);
  write_file_atomically(dir / "steps.csv", run.controller.step_table);
  // Plots first: a figure that fails (gnuplot missing) is listed in summary.json's plot_errors
  // and does not fail the plan, whose files are complete without it.
  Json summary = plan_summary(run, document);
  summary["plot_errors"] = Json::array();
  if (plots) draw_plan_plots(run, document, dir, summary["plot_errors"]);
  write_json_file(dir / "summary.json", summary);
}

// ------------------------------------------------------------------------------ reading back

namespace {

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  return cells;
}

}  // namespace

SavedPlan read_saved_plan(const fs::path& dir) {
  const fs::path summary_path = dir / "summary.json", pulses_path = dir / "pulses.csv";
  SavedPlan out;
  Json summary;
  {
    InputFileStream in(summary_path);  // the run's snapshot (chatterlab/input_files.hpp)
    if (!in) throw InputError(fmt::format("{}: cannot open (a saved feed plan needs summary.json)", summary_path.string()));
    try {
      summary = Json::parse(in);
      out.machine = summary.at("machine");
      out.part = summary.at("part");
      out.wheel = summary.at("wheel");
      out.plan.spindle_speed_rpm = summary.at("spindle_speed_rpm").get<double>();
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: not a feed_plan summary: {}", summary_path.string(), e.what()));
    }
  }
  std::unique_ptr<Kinematics> kinematics;
  std::unique_ptr<Generatrix> generatrix;
  try {
    kinematics = build_kinematics(out.machine);
    generatrix = build_generatrix(out.part);
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: machine/part tables unusable: {}", summary_path.string(), e.what()));
  }
  out.plan.motors = kinematics->motors();
  const std::size_t motors = out.plan.motors.size();
  for (const auto& m : out.plan.motors) {
    const Json& initial = summary.at("initial_position");
    if (!initial.contains(position_key(m)) || !initial[position_key(m)].is_number())
      throw InputError(fmt::format("{}: initial_position has no number '{}'", summary_path.string(), position_key(m)));
    out.plan.initial_position_mm.push_back(initial[position_key(m)].get<double>());
  }

  InputFileStream in(pulses_path);
  if (!in) throw InputError(fmt::format("{}: cannot open (a saved feed plan needs pulses.csv)", pulses_path.string()));
  std::string line;
  std::getline(in, line);
  const auto header = split_csv_line(line);
  std::vector<std::string> expected{"segment", "start_s", "duration_s"};
  for (const auto& m : out.plan.motors) expected.push_back(m.name + "_pulses");
  if (header != expected)
    throw InputError(fmt::format("{}:1: header '{}' does not match the machine's motors (expected '{}')",
                                 pulses_path.string(), line, fmt::join(expected, ",")));
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    const auto cells = split_csv_line(line);
    if (cells.size() != expected.size())
      throw InputError(fmt::format("{}:{}: {} cells, expected {}", pulses_path.string(), line_number,
                                   cells.size(), expected.size()));
    PlanSegment seg;
    try {
      seg.start_s = std::stod(cells[1]);
      seg.duration_s = std::stod(cells[2]);
      for (std::size_t m = 0; m < motors; ++m) {
        std::size_t used = 0;
        seg.pulses.push_back(std::stoll(cells[3 + m], &used));
        if (used != cells[3 + m].size()) throw std::invalid_argument("not an integer");
      }
    } catch (const std::exception&) {
      throw InputError(fmt::format("{}:{}: '{}': times must be numbers and pulse counts integers",
                                   pulses_path.string(), line_number, line));
    }
    if (!(seg.duration_s > 0))
      throw InputError(fmt::format("{}:{}: duration_s = {}: must be > 0", pulses_path.string(), line_number, cells[2]));
    out.plan.segments.push_back(std::move(seg));
  }
  // Conditions per segment by forward kinematics of the replayed positions; the contact offset
  // on the wheel follows the saved sweep law as a function of x (fixed-point iteration).
  const auto sweep = sweep_function(build_sweep(summary.at("plan"), out.wheel), generatrix->x_min_mm());
  const auto contact = wheel_contact(build_wheel(out.wheel));
  auto contact_x = [&](const std::vector<double>& positions, double& zeta) {
    // Solve x = forward(positions, zeta(x)).x: secant iterations on the residual (the sweep can
    // move the contact as fast as x itself, where plain fixed-point iteration stalls).
    double x = kinematics->forward(positions, {}).x_mm;
    zeta = 0.0;
    if (!sweep) return x;
    auto residual = [&](double guess) {
      const double s = sweep(guess);
      return kinematics->forward(positions, contact ? contact(s) : ToolContact{s, 0.0, 0.0}).x_mm - guess;
    };
    double x0 = x, r0 = residual(x0), x1 = x0 + 1e-3, r1 = residual(x1);
    for (int i = 0; i < 50 && std::abs(r1) > 1e-10 && r1 != r0; ++i) {
      const double next = x1 - r1 * (x1 - x0) / (r1 - r0);
      x0 = x1;
      r0 = r1;
      x1 = next;
      r1 = residual(x1);
    }
    zeta = sweep(x1);
    return x1;
  };
  // segments.csv (written with the plan) gives x and the contact on the wheel directly; without it
  // they are solved from the replayed positions (unique unless a fast sweep tilts the work).
  const fs::path segments_path = dir / "segments.csv";
  std::optional<DataTable> saved_segments;
  if (fs::exists(segments_path)) {
    saved_segments = read_data_table(segments_path);
    if (saved_segments->rows() != out.plan.segments.size())
      throw InputError(fmt::format("{}: {} rows, but pulses.csv has {} segments", segments_path.string(),
                                   saved_segments->rows(), out.plan.segments.size()));
  }
  double zeta0 = 0.0;
  std::vector<double> positions = out.plan.initial_position_mm;
  double x_prev = contact_x(positions, zeta0);
  for (std::size_t k = 0; k < out.plan.segments.size(); ++k) {
    for (std::size_t m = 0; m < motors; ++m)
      positions[m] += static_cast<double>(out.plan.segments[k].pulses[m]) * out.plan.motors[m].mm_per_pulse;
    double zeta1 = 0.0;
    double x_next = saved_segments ? 0.0 : contact_x(positions, zeta1);
    SegmentConditions c;
    if (saved_segments) {
      x_prev = saved_segments->column("x_start_mm")[k];
      x_next = saved_segments->column("x_end_mm")[k];
      c.contact_on_wheel_mm = saved_segments->column("contact_on_wheel_mm")[k];
    } else {
      c.contact_on_wheel_mm = 0.5 * (zeta0 + zeta1);
    }
    c.start_s = out.plan.segments[k].start_s;
    c.duration_s = out.plan.segments[k].duration_s;
    c.x_start_mm = x_prev;
    c.x_end_mm = x_next;
    c.radius_mm = generatrix->evaluate(0.5 * (x_prev + x_next)).f;
    c.axial_speed_mm_per_s = (x_next - x_prev) / c.duration_s;
    c.spindle_speed_rpm = out.plan.spindle_speed_rpm;
    out.segments.push_back(c);
    x_prev = x_next;
    zeta0 = zeta1;
  }
  return out;
}

}  // namespace chatterlab::planner
