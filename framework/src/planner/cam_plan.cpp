#include "planner/cam_plan.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <limits>

#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/signal_io.hpp"
#include "planner/controller_export.hpp"
#include "planner/parametric_spline.hpp"
#include "planner/plan_io.hpp"
#include "planner/replay.hpp"
#include "planner/setup.hpp"

namespace chatterlab::planner {

namespace {

namespace fs = std::filesystem;
constexpr double pi = std::numbers::pi;

ParamSpec positive(std::string key, std::string unit, std::string description) {
  return positive_spec(std::move(key), std::move(unit), std::move(description));
}

std::vector<ParamSpec> part_specs() {
  ParamSpec file = param_spec("lift_table_file", ValueKind::string, "",
                              "CSV angle_deg,radius_mm (relative to the study file)");
  ParamSpec chosen = param_spec("chosen_angles_deg", ValueKind::real_list, "deg",
                                "table rows the spline starts from (default: every row)");
  chosen.optional = true;
  chosen.min = 0.0;
  chosen.max = 360.0;
  ParamSpec target = param_spec("target_fit_error_mm", ValueKind::real, "mm",
                                "add table rows until every row is fitted within this (0: none)");
  target.min = 0.0;
  target.default_value = 5e-4;
  return {file, chosen, target};
}

std::vector<ParamSpec> machine_rule_specs() {
  ParamSpec speed = positive("cam_speed_rpm", "rpm", "largest cam (C axis) speed");
  speed.default_value = 60.0;
  ParamSpec delta = relative_rate_change_spec();
  delta.default_value = 0.1;  // P2's machine
  return {speed, delta};
}

LiftTable read_lift_table(const Json& part, const fs::path& study_dir) {
  const fs::path file = study_dir / part.at("lift_table_file").get<std::string>();
  const DataTable data = read_data_table(file);
  LiftTable table{data.column("angle_deg"), data.column("radius_mm")};
  for (std::size_t i = 0; i < table.angle_deg.size(); ++i)
    if (!(table.angle_deg[i] > 0 && table.angle_deg[i] <= 360 && table.radius_mm[i] > 0))
      throw InputError(fmt::format("{}:{}: angle {} deg, radius {} mm: angles must lie in (0, 360] "
                                   "and radii be > 0", file.string(), data.source_lines[i],
                                   table.angle_deg[i], table.radius_mm[i]));
  return table;
}

std::vector<double> chosen_angles(const Json& part, const LiftTable& table) {
  if (part.contains("chosen_angles_deg") && part["chosen_angles_deg"].is_array())
    return part["chosen_angles_deg"].get<std::vector<double>>();
  return table.angle_deg;
}

std::unique_ptr<Kinematics> build(const Json& machine) {
  Json params = machine;
  params.erase("type");
  for (const ParamSpec& rule : machine_rule_specs()) params.erase(rule.key);
  return kinematics_registry().at(machine.at("type").get<std::string>()).create(ParamValues(params));
}

// Signed distance from the closed profile to the wheel centre minus the wheel radius (positive:
// material left), nearest point by Newton on the spline parameter from `l`.
struct CamDeviation {
  double normal_mm;  // signed normal distance minus the wheel radius (+: material left)
  double lift_mm;    // the same as a radial (lift) deviation at the foot point
  double angle_deg;  // polar angle of the foot point, [0, 360)
};

CamDeviation cam_deviation(const ParametricSpline& spline, const ToolInPart& wheel, double& l) {
  // Safeguarded Newton: steps of at most 0.5 mm, a fixed downhill step where the distance is not
  // locally convex in l (concave flanks seen from a large wheel).
  std::array<double, 2> p{}, d1{}, d2{};
  for (int i = 0; i < 40; ++i) {
    spline.evaluate(l, p, d1, d2);
    const double rx = p[0] - wheel.x_mm, ry = p[1] - wheel.y_mm;
    const double g = rx * d1[0] + ry * d1[1];
    const double dg = d1[0] * d1[0] + d1[1] * d1[1] + rx * d2[0] + ry * d2[1];
    const double step = dg > 0 ? std::clamp(-g / dg, -0.5, 0.5) : (g > 0 ? -0.1 : 0.1);
    l += step;
    if (std::abs(step) < 1e-12) break;
  }
  spline.evaluate(l, p, d1, d2);
  const double distance = std::hypot(p[0] - wheel.x_mm, p[1] - wheel.y_mm);
  // Outside (wheel side) when the centre lies along the outward normal (d1.y, -d1.x).
  const double side = (wheel.x_mm - p[0]) * d1[1] - (wheel.y_mm - p[1]) * d1[0];
  const double normal = (side >= 0 ? distance : -distance) - wheel.radius_mm;
  // Radial deviation: the produced profile lies `normal` along the unit normal n; along the
  // radius r_hat that is normal / (n . r_hat).
  const double speed = std::hypot(d1[0], d1[1]), rho = std::hypot(p[0], p[1]);
  const double cos_angle = (d1[1] * p[0] - d1[0] * p[1]) / (speed * rho);
  return {normal, normal / cos_angle, std::fmod(std::atan2(p[1], p[0]) * 180.0 / pi + 360.0, 360.0)};
}

constexpr const char* columns[] = {"seed_points_max_fit_error_mm", "max_fit_error_mm", "inserted_points",
                                   "total_time_s", "lower_bound_s", "max_profile_error_mm",
                                   "max_lift_error_mm", "max_per_degree_error_mm", "certified"};

}  // namespace

PluginInfo CamPlanKind::info() {
  PluginInfo info;
  info.name = "cam_plan";
  info.description = "X-C cam grinding: spline fit of a lift table with adaptive insertion, "
                     "tangent-point tracking, pulses and replayed profile error";
  info.models_md_ids = "K1-K3";
  ParamSpec step = positive("segment_angle_deg", "deg", "polar angle of the contact per segment");
  step.default_value = 0.5;
  step.max = 10.0;
  const ParamSpec tick = controller_tick_spec();
  info.params = {step, start_stop_rate_spec(), tick};
  info.thread_safety = ThreadSafety::copy_per_thread;
  info.example_params = {{"segment_angle_deg", 1.0}};
  return info;
}

void CamPlanKind::validate(Json& document, const SourceMap& sources) const {
  auto table_of = [&](const char* key) {
    if (!document.contains(key) || !document[key].is_object())
      throw InputError(fmt::format("{}: missing table [{}] (the cam_plan study needs it)",
                                   sources.locate("study").str(), key));
    return document[key];
  };
  Json machine = table_of("machine");
  // The planner's rules in [machine] (the kinematics plugin does not know them).
  Json rules = Json::object();
  for (const char* key : {"cam_speed_rpm", "max_relative_rate_change"})
    if (machine.contains(key)) {
      rules[key] = machine[key];
      machine.erase(key);
    }
  rules = validate_params(rules, machine_rule_specs(), "machine", sources);
  Json validated = validate_component(Json{{"machine", machine}}, "machine", kinematics_registry(), sources);
  if (validated["type"] != "xc_cam")
    throw InputError(fmt::format("{}: machine.type = {}: a cam_plan needs the xc_cam machine",
                                 sources.locate("machine.type").str(), validated["type"].dump()));
  validated.update(rules);
  Json part = validate_params(table_of("part"), part_specs(), "part", sources);
  Json plan = validate_params(document.contains("plan") ? document["plan"] : Json::object(),
                              info().params, "plan", sources);
  const fs::path study_dir = fs::path(sources.locate("part.lift_table_file").file).parent_path();
  part["lift_table_file"] = fs::absolute(study_dir / part["lift_table_file"].get<std::string>()).string();
  const LiftTable table = read_lift_table(part, "");
  try {
    fit_cam(table, chosen_angles(part, table), 0.0);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: part = lift table {}: {}", sources.locate("part").str(),
                                 part["lift_table_file"].get<std::string>(), e.what()));
  }
  document["machine"] = std::move(validated);
  document["part"] = std::move(part);
  document["plan"] = std::move(plan);
}

std::vector<std::string> CamPlanKind::output_columns(const Json&) const {
  return {std::begin(columns), std::end(columns)};
}

std::vector<Json> CamPlanKind::run_point(const Json& doc, const PointContext& context) const {
  const Json& part = doc.at("part");
  const LiftTable table = read_lift_table(part, "");
  const std::vector<double> chosen = chosen_angles(part, table);
  ParametricSpline seed_spline({{1, 0}, {0, 1}, {-1, 0}}, SplineEnds::periodic), spline = seed_spline;
  const CamFit seed = fit_cam(table, chosen, 0.0, &seed_spline);
  const CamFit fit = fit_cam(table, chosen, part.at("target_fit_error_mm").get<double>(), &spline);

  // Tangent-point tracking at equal steps of the contact's polar angle.
  auto kinematics = build(doc.at("machine"));
  const auto motors = kinematics->motors();
  const double step_deg = doc.at("plan").at("segment_angle_deg").get<double>();
  const auto segments = static_cast<std::size_t>(std::ceil(360.0 / step_deg - 1e-9));
  std::vector<std::vector<double>> q(segments + 1, std::vector<double>(2));
  std::vector<double> contact_l(segments + 1);
  for (std::size_t k = 0; k <= segments; ++k) {
    const double phi = 2 * pi * static_cast<double>(k) / static_cast<double>(segments);
    contact_l[k] = spline.parameter_at_polar_angle(phi);
    std::array<double, 2> p{}, d1{}, d2{};
    spline.evaluate(contact_l[k], p, d1, d2);
    kinematics->inverse({p[0], p[1], d1[0], d1[1]}, {}, q[k]);
    if (k > 0) q[k][0] += 360.0 * std::round((q[k - 1][0] - q[k][0]) / 360.0);  // unwrap C
  }
  // Integer positions (remainders carried) and time-optimal durations under every machine rule
  // (the feed planner's scheduler, docs/planner.md): C speed <= cam_speed_rpm, every motor's
  // pulse rate, and the smoothness rule with starts, stops and reversals (the X slide reverses
  // at the nose and the base circle), periodic because the cam is ground revolution after
  // revolution. Then the same certificate after integerisation.
  const Json& machine = doc.at("machine");
  FeedPlan plan;
  plan.motors = motors;
  quantise_targets(plan, q);
  const double c_speed_deg_s = machine.at("cam_speed_rpm").get<double>() * 6.0;
  std::vector<double> cap(segments), exact_cap(segments);
  for (std::size_t k = 0; k < segments; ++k) {
    const double pulses_c = static_cast<double>(std::llabs(plan.segments[k].pulses[0]));
    cap[k] = pulses_c > 0 ? c_speed_deg_s / (pulses_c * motors[0].mm_per_pulse)
                          : std::numeric_limits<double>::infinity();
    exact_cap[k] = c_speed_deg_s / std::abs(q[k + 1][0] - q[k][0]);
  }
  const RateRules rules = build_rate_rules(machine, doc.at("plan"), *kinematics);
  std::size_t passes = 0;
  try {
    passes = time_optimal_durations(plan, cap, rules, true);
  } catch (const NoAdmissibleSpeed& e) {
    throw PointFailure(fmt::format("no plan: no admissible speed at contact angle {} deg",
                                   360.0 * static_cast<double>(e.segment) / static_cast<double>(segments)));
  }
  const double lower_bound = relaxed_time_bound(plan, exact_cap, q);
  Certificate certificate = certify_motor_rules(plan, q, rules, true);
  double max_c_speed = 0.0;
  for (std::size_t k = 0; k < segments; ++k) {
    const PlanSegment& seg = plan.segments[k];
    const double c_speed = static_cast<double>(std::llabs(seg.pulses[0])) * motors[0].mm_per_pulse / seg.duration_s;
    max_c_speed = std::max(max_c_speed, c_speed);
    if (c_speed > c_speed_deg_s * (1 + 1e-9))
      certificate.add_violation(fmt::format("segment {}: C speed {} deg/s > {} deg/s", k, c_speed, c_speed_deg_s));
  }
  const double t = plan.total_time_s();
  std::vector<std::vector<double>> cols(5);
  for (std::size_t k = 0; k < segments; ++k) {
    cols[0].push_back(static_cast<double>(k));
    cols[1].push_back(plan.segments[k].start_s);
    cols[2].push_back(plan.segments[k].duration_s);
    cols[3].push_back(static_cast<double>(plan.segments[k].pulses[0]));
    cols[4].push_back(static_cast<double>(plan.segments[k].pulses[1]));
  }
  // Replay every state (pulses spread evenly per segment) through the forward kinematics: the
  // normal deviation of each state, and the lift error of the surface the wheel leaves: the
  // radial deviation (normal deviation / cos of the angle between the profile normal and the
  // radius), and per 0.1 deg bin of the cam angle the deepest state (the envelope: a state that
  // leaves material there is ground away by a deeper one).
  constexpr std::size_t bins_per_degree = 10;
  std::vector<double> envelope(360 * bins_per_degree, std::numeric_limits<double>::infinity());
  double max_error = 0.0, sum_sq = 0.0;
  std::size_t states = 0;
  double l = contact_l[0];
  for_each_pulse_state(plan, [&](std::size_t k, double u, const std::vector<double>& position) {
    if (u == 0.0) l = contact_l[k];
    const CamDeviation d = cam_deviation(spline, kinematics->forward(position, {}), l);
    auto& bin = envelope[std::min(envelope.size() - 1, static_cast<std::size_t>(d.angle_deg * bins_per_degree))];
    bin = std::min(bin, d.lift_mm);
    max_error = std::max(max_error, std::abs(d.normal_mm));
    sum_sq += d.normal_mm * d.normal_mm;
    ++states;
  });
  std::vector<double> bin_angle, lift_error;
  double max_lift_error = 0.0, per_degree = 0.0;
  for (std::size_t i = 0; i < envelope.size(); ++i)
    if (std::isfinite(envelope[i])) {
      bin_angle.push_back((static_cast<double>(i) + 0.5) / bins_per_degree);
      lift_error.push_back(envelope[i]);
      max_lift_error = std::max(max_lift_error, std::abs(envelope[i]));
      const double next = envelope[(i + bins_per_degree) % envelope.size()];  // periodic
      if (std::isfinite(next)) per_degree = std::max(per_degree, std::abs(next - envelope[i]));
    }
  // Concave parts of the fitted profile: a wheel of larger radius gouges there (K2 tracking keeps
  // the tangency at the contact but the wheel then cuts the profile next to it).
  double min_concave_radius = std::numeric_limits<double>::infinity(), concave_at_deg = 0.0;
  for (int i = 0; i < 20000; ++i) {
    std::array<double, 2> p{}, d1{}, d2{};
    spline.evaluate(spline.length() * i / 20000.0, p, d1, d2);
    const double speed = std::hypot(d1[0], d1[1]);
    const double curvature = (d1[0] * d2[1] - d1[1] * d2[0]) / (speed * speed * speed);
    if (curvature < 0 && -1 / curvature < min_concave_radius) {
      min_concave_radius = -1 / curvature;
      concave_at_deg = std::fmod(std::atan2(p[1], p[0]) * 180 / pi + 360.0, 360.0);
    }
  }
  // Controller output (docs/planner.md, "Controller output"), read back: the program's pulses and
  // durations, and the step table's states replayed through the forward kinematics.
  const double tick_hz = controller_tick_hz(doc.at("plan"), motors);
  const ControllerExport controller = export_plan(
      plan, {"chatterlab cam_plan: one revolution of the cam, C in degrees (unwrapped), X slide in mm",
             "G93 inverse time: F = 60 / segment duration"}, tick_hz);
  double step_replay_error = 0.0;
  std::size_t step_states = 0;
  {
    double ls = contact_l[0];
    for_each_step_state(plan, controller.events, tick_hz, [&](std::size_t k, double u, const std::vector<double>& position) {
      if (u == 0.0) ls = contact_l[k];
      step_replay_error = std::max(step_replay_error, std::abs(cam_deviation(spline, kinematics->forward(position, {}), ls).normal_mm));
      ++step_states;
    });
  }
  const bool meets = max_lift_error <= 0.015 && per_degree <= 0.004;
  const bool certified = certificate.ok && meets && controller.exact();
  std::vector<std::string> failures;
  if (!certificate.ok) failures.push_back("machine rules: " + certificate.violations.front());
  if (!meets)
    failures.push_back(fmt::format("lift error {:.4g} mm (limit 0.015), per degree {:.4g} mm (limit 0.004)",
                                   max_lift_error, per_degree));
  if (!controller.exact()) failures.push_back("controller export: program.ngc or steps.csv read back differs from the plan");
  if (!context.artifact_dir.empty()) {
    const fs::path dir = context.artifact_dir;
    write_file_atomically(dir / "program.ngc", controller.gcode);
    write_file_atomically(dir / "steps.csv", controller.step_table);
    write_file_atomically(dir / "pulses.csv",
                          csv_text({"segment", "start_s", "duration_s", "c_axis_pulses", "x_slide_pulses"}, cols));
    std::vector<std::vector<double>> fit_cols(4);
    for (std::size_t i = 0; i < table.angle_deg.size(); ++i) {
      const double phi = table.angle_deg[i] * pi / 180;
      fit_cols[0].push_back(table.angle_deg[i]);
      fit_cols[1].push_back(table.radius_mm[i]);
      fit_cols[2].push_back(seed_spline.polar_radius(phi) - table.radius_mm[i]);
      fit_cols[3].push_back(spline.polar_radius(phi) - table.radius_mm[i]);
    }
    write_file_atomically(dir / "fit_errors.csv",
                          csv_text({"angle_deg", "radius_mm", "chosen_points_error_mm", "adaptive_error_mm"}, fit_cols));
    Json summary = {
        {"certified", certified},
        {"certification_failures", failures},
        {"certification", "every machine rule after integerisation and the lift requirements (K3) in "
                          "the replay, and the controller output read back exactly"},
        {"controller_export",
         {{"files", {"program.ngc", "steps.csv"}},
          {"gcode_axes", {{"C", "c_axis (deg)"}, {"X", "x_slide (mm)"}}},
          {"tick_hz", tick_hz},
          {"round_trip", {{"exact", controller.exact()},
                          {"gcode_pulses_identical", controller.check.gcode_pulses_identical},
                          {"gcode_max_duration_error_s", controller.check.gcode_max_duration_error_s},
                          {"step_events", controller.check.step_events},
                          {"step_positions_identical", controller.check.step_positions_identical},
                          {"step_max_time_error_s", controller.check.step_max_time_error_s},
                          {"step_replay_states", step_states},
                          {"step_replay_max_profile_error_mm", step_replay_error}}},
          {"shortest_step_interval_s", controller.check.shortest_step_interval_s}}},
        {"chosen_points", seed.chosen_angles_deg.size()},
        {"chosen_points_fit", {{"max_radius_error_mm", seed.max_radius_error_mm},
                               {"mean_abs_radius_error_mm", seed.mean_abs_radius_error_mm},
                               {"max_x_error_mm", seed.max_x_error_mm}, {"max_y_error_mm", seed.max_y_error_mm},
                               {"worst_angle_deg", seed.worst_angle_deg}}},
        {"adaptive_fit", {{"points", fit.chosen_angles_deg.size()}, {"inserted", fit.inserted},
                          {"inserted_angles_deg", fit.chosen_angles_deg},
                          {"max_radius_error_mm", fit.max_radius_error_mm},
                          {"mean_abs_radius_error_mm", fit.mean_abs_radius_error_mm},
                          {"max_x_error_mm", fit.max_x_error_mm}, {"max_y_error_mm", fit.max_y_error_mm},
                          {"worst_angle_deg", fit.worst_angle_deg}}},
        {"total_time_s", t},
        {"lower_bound_s", lower_bound},
        {"lower_bound_kind", "continuous relaxation: the exact path at the largest speed each "
                             "per-segment bound allows (C speed, pulse rates), without smoothness"},
        {"gap_percent", 100.0 * (t - lower_bound) / lower_bound},
        {"mean_cam_speed_rpm", 60.0 / t},
        {"segments", segments},
        {"smoothing_passes", passes},
        {"certificate", certificate_json(certificate, plan, rules,
                                         {{"path_rule", "C speed <= cam_speed_rpm"},
                                          {"max_c_speed_deg_per_s", max_c_speed},
                                          {"c_speed_limit_deg_per_s", c_speed_deg_s}})},
        {"pre_motion", {{"ramp_segments_each_end", ramp_segments(plan, rules)},
                        {"ramp_time_s", static_cast<double>(ramp_segments(plan, rules)) *
                                            (plan.segments.front().duration_s + plan.segments.back().duration_s)},
                        {"note", "the C axis and X slide ramp up from rest before the wheel engages "
                                 "(and down after it leaves), not in total_time_s"}}},
        {"initial_position", {{"c_axis_deg", q[0][0]}, {"x_slide_mm", q[0][1]}}},
        {"max_profile_error_mm", max_error},
        {"rms_profile_error_mm", states ? std::sqrt(sum_sq / static_cast<double>(states)) : 0.0},
        {"max_lift_error_mm", max_lift_error},
        {"lift_error_method", "radial deviation of the surface the wheel leaves: every replayed "
                              "state, per 0.1 deg of cam angle the deepest; per degree: the largest "
                              "change between bins 1 deg apart"},
        {"replayed_states", states},
        {"max_per_degree_error_mm", per_degree},
        {"max_per_degree_lift_error_mm", per_degree},
        {"meets_requirements", meets},
        {"min_concave_radius_mm", std::isfinite(min_concave_radius) ? Json(min_concave_radius) : Json()},
        {"min_concave_radius_at_deg", concave_at_deg},
        {"wheel_gouges_concave_parts",
         std::isfinite(min_concave_radius) &&
             doc.at("machine").at("wheel_radius_mm").get<double>() > min_concave_radius},
        {"requirements", {{"total_lift_error_mm", 0.015}, {"per_degree_lift_error_mm", 0.004}}},
        {"machine", doc.at("machine")}, {"part", part}, {"plan", doc.at("plan")}};
    Json plot_errors = Json::array();
    if (context.plots) {
      auto draw = [&](const plot::Curves& c, const std::string& stem) {
        try {
          plot::render(c, dir, stem);
        } catch (const std::exception& e) {
          plot_errors.push_back(fmt::format("{}: {}", stem, e.what()));
        }
      };
      plot::Curves f;
      f.title = "cam fit error at the lift-table rows";
      f.x_label = "cam angle [deg]";
      f.y_label = "fitted - table radius [um]";
      plot::Series a{fmt::format("{} chosen points", seed.chosen_angles_deg.size()), fit_cols[0], {}, "linespoints"};
      plot::Series b{fmt::format("after adaptive insertion ({} points)", fit.chosen_angles_deg.size()), fit_cols[0], {}, "linespoints"};
      for (std::size_t i = 0; i < fit_cols[0].size(); ++i) {
        a.y.push_back(1000 * fit_cols[2][i]);
        b.y.push_back(1000 * fit_cols[3][i]);
      }
      f.series = {a, b};
      draw(f, "fit_error");
      plot::Curves e;
      e.title = "lift error of the ground surface, per 0.1 deg (limit +-15 um)";
      e.x_label = "contact polar angle [deg]";
      e.y_label = "radial deviation [um] (+ material left)";
      plot::Series s{"lift error (deepest replayed state)", bin_angle, {}, "lines"};
      plot::Series binds{"requirement binds (>= 90 % of 15 um)", {}, {}, "points"};
      for (std::size_t i = 0; i < lift_error.size(); ++i) {
        s.y.push_back(1000 * lift_error[i]);
        if (std::abs(lift_error[i]) >= 0.9 * 0.015) {
          binds.x.push_back(bin_angle[i]);
          binds.y.push_back(1000 * lift_error[i]);
        }
      }
      const double gap = std::nan("");
      plot::Series band{"requirement +-15 um (K3)", {0, 360, gap, 0, 360}, {15, 15, gap, -15, -15}, "dashes"};
      e.series = {s, band};
      if (!binds.x.empty()) e.series.push_back(binds);
      draw(e, "profile_error");
      plot::Curves x;
      x.title = "X slide position (tangent-point tracking)";
      x.x_label = "contact polar angle [deg]";
      x.y_label = "wheel centre distance from the C axis [mm]";
      plot::Series xs{"X slide", {}, {}, "lines"};
      for (std::size_t k = 0; k <= segments; ++k) {
        xs.x.push_back(360.0 * static_cast<double>(k) / static_cast<double>(segments));
        xs.y.push_back(q[k][1]);
      }
      x.series = {xs};
      draw(x, "x_slide");
    }
    summary["plot_errors"] = plot_errors;
    write_json_file(dir / "summary.json", summary);
  }
  // A plan that breaks a rule or misses the lift requirements is never "ok" (files written above).
  if (!certified)
    throw PointFailure(fmt::format("plan not certified: {}", fmt::join(failures, "; ")));
  return {seed.max_radius_error_mm, fit.max_radius_error_mm, static_cast<double>(fit.inserted), t,
          lower_bound, max_error, max_lift_error, per_degree, certified};
}

}  // namespace chatterlab::planner

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::planner::CamPlanKind);
