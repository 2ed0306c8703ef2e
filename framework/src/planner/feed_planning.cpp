#include "chatterlab/planner/feed_planning.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/study_kind.hpp"
#include "planner/plan_io.hpp"
#include "planner/replay.hpp"
#include "planner/setup.hpp"

namespace chatterlab::planner {

namespace {

ParamSpec positive(std::string key, std::string unit, std::string description) {
  return positive_spec(std::move(key), std::move(unit), std::move(description));
}

std::vector<ParamSpec> machine_constraint_specs() {
  return {relative_rate_change_spec(),
          positive("max_axial_advance_mm_per_100_rev", "mm",
                   "largest advance of the contact point along the work axis per 100 work "
                   "revolutions")};
}

std::vector<ParamSpec> wheel_specs() {
  ParamSpec type = param_spec("type", ValueKind::string, "", "cylindrical or profiled (edge arc)");
  type.choices = {"cylindrical", "profiled"};
  ParamSpec radius = positive("edge_radius_mm", "mm", "profiled wheel: radius r of the edge arc");
  radius.optional = true;
  ParamSpec angle = positive("edge_angle_deg", "deg", "profiled wheel: opening angle of the edge arc");
  angle.max = 180.0;
  angle.default_value = 180.0;
  return {type, positive("diameter_mm", "mm", "largest section diameter phi"),
          positive("thickness_mm", "mm", "wheel thickness a (face width)"), radius, angle};
}

std::vector<ParamSpec> part_specs() {
  ParamSpec expression = param_spec("generatrix", ValueKind::string, "mm",
                                    "y = f(x): muparser expression in x (mm), _pi is pi");
  expression.optional = true;
  ParamSpec range = param_spec("x_range_mm", ValueKind::real_list, "mm", "[a, b]: the x range to grind");
  range.min_items = 2;
  range.optional = true;
  ParamSpec points = param_spec("points_file", ValueKind::string, "",
                                "instead of generatrix: CSV of x_mm, y_mm points (relative to the "
                                "study file), a natural cubic spline through or near them");
  points.optional = true;
  ParamSpec smoothing = param_spec("smoothing", ValueKind::string, "",
                                   "points_file: cross_validated (smoothing spline, GCV), tolerance "
                                   "(RMS residual = smoothing_tolerance_mm) or none (through the points)");
  smoothing.choices = {"cross_validated", "tolerance", "none"};
  smoothing.default_value = "cross_validated";
  ParamSpec smoothing_tolerance = positive("smoothing_tolerance_mm", "mm",
                                           "smoothing = \"tolerance\": RMS residual of the smoothing spline");
  smoothing_tolerance.optional = true;
  ParamSpec resolution = positive("geometry_resolution_mm", "mm",
                                  "features narrower than this (the tangent turning by more than "
                                  "1 rad within it, jumps, kinks) are refused");
  resolution.default_value = default_geometry_resolution_mm;
  return {expression, range, points, smoothing, smoothing_tolerance, resolution};
}

Json table_or_empty(const Json& document, const std::string& key, const SourceMap& sources) {
  if (!document.contains(key)) return Json::object();
  const Json& t = document.at(key);
  if (!t.is_object())
    throw InputError(fmt::format("{}: {} = {}: expected a table [{}]", sources.locate(key).str(), key,
                                 t.dump(), key));
  return t;
}

Json require_table(const Json& document, const std::string& key, const SourceMap& sources) {
  if (!document.contains(key))
    throw InputError(fmt::format("{}: missing table [{}] (the feed_plan study needs it)",
                                 sources.locate("study").str(), key));
  return table_or_empty(document, key, sources);
}

// spindle_speed_rpm = 300 or { from = 250, to = 300 }.
Json validate_spindle_speed(const Json& machine, const SourceMap& sources) {
  const std::string where = sources.locate("machine.spindle_speed_rpm").str();
  if (!machine.contains("spindle_speed_rpm"))
    throw InputError(fmt::format("{}: missing key 'machine.spindle_speed_rpm' (rpm, a value or "
                                 "{{ from, to }})", sources.locate("machine").str()));
  const Json& v = machine.at("spindle_speed_rpm");
  auto check = [&](const Json& x, const std::string& key) {
    if (!x.is_number() || !std::isfinite(x.get<double>()) || !(x.get<double>() > 0))
      throw InputError(fmt::format("{}: {} = {}: must be a number > 0 (rpm)", where, key, x.dump()));
    return x.get<double>();
  };
  if (v.is_number()) {
    check(v, "machine.spindle_speed_rpm");
    return v;
  }
  if (!v.is_object() || !v.contains("from") || !v.contains("to") || v.size() != 2)
    throw InputError(fmt::format("{}: machine.spindle_speed_rpm = {}: expected a number or "
                                 "{{ from = ..., to = ... }}", where, v.dump()));
  const double from = check(v["from"], "machine.spindle_speed_rpm.from");
  const double to = check(v["to"], "machine.spindle_speed_rpm.to");
  if (from > to)
    throw InputError(fmt::format("{}: machine.spindle_speed_rpm = {}: from must not exceed to", where, v.dump()));
  return Json{{"from", from}, {"to", to}};
}

Json validate_machine(const Json& document, const SourceMap& sources) {
  Json machine = require_table(document, "machine", sources);
  Json constraints = Json::object(), rest = Json::object();
  for (auto it = machine.begin(); it != machine.end(); ++it) {
    bool owned = false;
    for (const char* key : machine_constraint_keys) owned = owned || it.key() == key;
    (owned ? constraints : rest)[it.key()] = it.value();
  }
  Json spindle = validate_spindle_speed(machine, sources);
  constraints.erase("spindle_speed_rpm");
  constraints = validate_params(constraints, machine_constraint_specs(), "machine", sources);
  Json validated = validate_component(Json{{"machine", rest}}, "machine", kinematics_registry(), sources);
  for (auto it = constraints.begin(); it != constraints.end(); ++it) validated[it.key()] = it.value();
  validated["spindle_speed_rpm"] = spindle;
  return validated;
}

Json validate_part(const Json& document, const SourceMap& sources) {
  Json part = validate_params(require_table(document, "part", sources), part_specs(), "part", sources);
  const bool has_points = part["points_file"].is_string();
  if (has_points == part["generatrix"].is_string() || has_points == part["x_range_mm"].is_array())
    throw InputError(fmt::format("{}: [part] needs either generatrix and x_range_mm, or points_file "
                                 "(not both)", sources.locate("part").str()));
  if (has_points && part["smoothing"] == "tolerance" && !part["smoothing_tolerance_mm"].is_number())
    throw InputError(fmt::format("{}: part.smoothing = \"tolerance\" needs part.smoothing_tolerance_mm "
                                 "(the RMS residual, mm)", sources.locate("part.smoothing").str()));
  // A smoothing key that would be ignored is a mistake worth saying (checked on the validated
  // table, so that a validated document validates again unchanged).
  if (part["smoothing_tolerance_mm"].is_number() && (!has_points || part["smoothing"] != "tolerance"))
    throw InputError(fmt::format(
        "{}: part.smoothing_tolerance_mm = {}: only used with points_file and smoothing = \"tolerance\" "
        "(here {})", sources.locate("part.smoothing_tolerance_mm").str(), part["smoothing_tolerance_mm"].dump(),
        has_points ? "smoothing = \"" + part["smoothing"].get<std::string>() + "\"" : "a generatrix expression"));
  if (!has_points && part["smoothing"] != "cross_validated")
    throw InputError(fmt::format("{}: part.smoothing = {}: smoothing applies to a points_file, not to a "
                                 "generatrix expression", sources.locate("part.smoothing").str(),
                                 part["smoothing"].dump()));
  const double resolution = part["geometry_resolution_mm"].get<double>();
  // The geometry analysis (docs/planner.md): jumps, kinks, values that are not finite and
  // features narrower than the resolution are refused with where they are.
  auto check_geometry = [&](const Generatrix& generatrix) {
    check_smooth(generatrix, resolution);
    for (int i = 0; i <= 64; ++i) {
      const double x = generatrix.x_min_mm() + (generatrix.x_max_mm() - generatrix.x_min_mm()) * i / 64.0;
      if (!(generatrix.evaluate(x).f >= 0))  // 0: an apex on the axis (problem 1 at x = 600)
        throw std::invalid_argument(fmt::format("the radius f(x) must not be negative (f({}) = {})", x,
                                                generatrix.evaluate(x).f));
    }
  };
  if (has_points) {
    const std::filesystem::path study_dir =
        std::filesystem::path(sources.locate("part.points_file").file).parent_path();
    part["points_file"] = std::filesystem::absolute(study_dir / part["points_file"].get<std::string>()).string();
    try {
      check_geometry(*build_generatrix(part));  // reads and checks the table (InputError)
    } catch (const std::invalid_argument& e) {
      throw InputError(fmt::format("{}: part.points_file = \"{}\": {}", sources.locate("part.points_file").str(),
                                   part["points_file"].get<std::string>(), e.what()));
    }
    return part;
  }
  const auto range = part["x_range_mm"].get<std::vector<double>>();
  if (range.size() != 2 || !(range[0] < range[1]))
    throw InputError(fmt::format("{}: part.x_range_mm = {}: expected [a, b] with a < b",
                                 sources.locate("part.x_range_mm").str(), part["x_range_mm"].dump()));
  try {
    check_geometry(*build_generatrix(part));
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: part.generatrix = \"{}\" on x_range_mm = [{}, {}]: {}",
                                 sources.locate("part.generatrix").str(),
                                 part["generatrix"].get<std::string>(), range[0], range[1], e.what()));
  }
  return part;
}

// The wheel must fit the part (MODELS.md P5): edge radius within the computed limit, face or arc
// clear of the part at every contact.
void check_wheel_fits(const Json& wheel, const Json& part, const SourceMap& sources) {
  auto generatrix = build_generatrix(part);
  const WheelSection section = build_wheel(wheel);
  if (section.profiled) {
    if (!wheel["edge_radius_mm"].is_number())
      throw InputError(fmt::format("{}: missing key 'wheel.edge_radius_mm' (a profiled wheel needs "
                                   "its edge arc radius, mm)", sources.locate("wheel").str()));
    const EdgeRadiusLimit limit =
        largest_edge_radius(*generatrix, generatrix->analyse(part.at("geometry_resolution_mm").get<double>()));
    if (section.edge_radius_mm > limit.radius_mm)
      throw InputError(fmt::format(
          "{}: wheel.edge_radius_mm = {}: the wheel is too large for the part: the largest edge "
          "radius that touches the part only at the contact is {:.2f} mm ({} at x = {:.2f} mm)",
          sources.locate("wheel.edge_radius_mm").str(), section.edge_radius_mm, limit.radius_mm,
          limit.local ? "radius of curvature of a concave part" : "distant part of the profile",
          limit.x_mm));
    const double arc_width = 2 * section.edge_radius_mm *
                             std::sin(0.5 * section.edge_angle_deg * 3.14159265358979323846 / 180.0);
    if (section.edge_radius_mm > wheel_geometry_edge_radius_mm(section) * (1 + 1e-12))
      throw InputError(fmt::format(
          "{}: wheel.edge_radius_mm = {}: an arc of radius {} mm and opening {} deg is {:.4g} mm "
          "wide, more than wheel.thickness_mm = {}", sources.locate("wheel.edge_radius_mm").str(),
          section.edge_radius_mm, section.edge_radius_mm, section.edge_angle_deg, arc_width,
          section.thickness_mm));
  }
  std::vector<double> contacts;
  const double a = generatrix->x_min_mm(), b = generatrix->x_max_mm();
  for (int i = 0; i <= 600; ++i) contacts.push_back(a + (b - a) * i / 600.0);
  const Interference hit = check_interference(*generatrix, section, contacts);
  if (hit.depth_mm > 0)
    throw InputError(fmt::format(
        "{}: wheel = {} wheel, thickness_mm = {}: the wheel is too large for the part: its {} cuts "
        "{:.4g} mm into the part at x = {:.2f} mm with the contact at x = {:.2f} mm ({} of 601 "
        "contacts interfere)",
        sources.locate("wheel").str(), section.profiled ? "profiled" : "cylindrical",
        section.thickness_mm, section.profiled ? "edge arc" : "flat face", hit.depth_mm, hit.x_mm,
        hit.contact_x_mm,
        hit.contacts_with_interference));
}

}  // namespace

std::vector<ParamSpec> feed_plan_settings_specs() {
  ParamSpec length = positive("segment_length_mm", "mm",
                              "longest plan segment along x; shorter where the tolerance needs "
                              "(default: 1 s at the axial-speed bound)");
  length.optional = true;
  ParamSpec tolerance = positive("max_profile_error_mm", "mm",
                                 "largest replayed normal profile error a certified plan may have");
  tolerance.default_value = 0.005;
  ParamSpec shortest = positive("min_segment_length_mm", "mm",
                                "shortest segment the tolerance may ask for");
  shortest.default_value = 0.005;
  const ParamSpec tick = controller_tick_spec();
  ParamSpec start_stop = start_stop_rate_spec();
  ParamSpec sweep = param_spec("wear_sweep", ValueKind::string, "",
                               "contact sweep across the wheel face (MODELS.md P6)");
  sweep.choices = {"none", "triangle", "sine", "stepped"};
  sweep.default_value = "none";
  ParamSpec amplitude = param_spec("wear_sweep_amplitude_mm", ValueKind::real, "mm",
                                   "sweep amplitude A (default: half the wheel thickness)");
  amplitude.min = 0.0;
  amplitude.optional = true;
  ParamSpec period = positive("wear_sweep_period_mm", "mm", "axial travel per sweep cycle");
  period.default_value = 40.0;
  ParamSpec steps = param_spec("wear_sweep_steps", ValueKind::integer, "1",
                               "stepped sweep: number of contact positions");
  steps.min = 2;
  steps.max = 1000;
  steps.default_value = 5;
  return {length, tolerance, shortest, start_stop, sweep, amplitude, period, steps, tick};
}

void validate_feed_plan_tables(Json& document, const SourceMap& sources) {
  Json machine = validate_machine(document, sources);
  Json part = validate_part(document, sources);
  Json wheel = validate_params(require_table(document, "wheel", sources), wheel_specs(), "wheel", sources);
  Json plan = validate_params(table_or_empty(document, "plan", sources), feed_plan_settings_specs(), "plan", sources);
  check_wheel_fits(wheel, part, sources);
  if (plan["wear_sweep"] != "none") {
    const WheelSection section = build_wheel(wheel);
    const double half = sweep_half_width_mm(section);
    if (plan["wear_sweep_amplitude_mm"].is_number() && plan["wear_sweep_amplitude_mm"].get<double>() > half)
      throw InputError(fmt::format(
          "{}: plan.wear_sweep_amplitude_mm = {}: the contact would leave the wheel's {} (at most "
          "{:.4g} mm: {})", sources.locate("plan.wear_sweep_amplitude_mm").str(),
          plan["wear_sweep_amplitude_mm"].get<double>(), section.profiled ? "edge arc" : "face", half,
          section.profiled ? "edge radius x half the opening angle" : "half the thickness"));
  }
  // The machine must reach every contact (e.g. a slope the upper table cannot turn to).
  auto kinematics = build_kinematics(machine);
  auto generatrix = build_generatrix(part);
  std::vector<double> positions(kinematics->motors().size());
  for (int i = 0; i <= 64; ++i) {
    const double x = generatrix->x_min_mm() + (generatrix->x_max_mm() - generatrix->x_min_mm()) * i / 64.0;
    const GeneratrixValue v = generatrix->evaluate(x);
    try {
      kinematics->inverse({x, v.f, 1.0, v.d1}, {}, positions);
    } catch (const std::domain_error& e) {
      throw InputError(fmt::format("{}: machine.type = {}: cannot reach the contact at x = {}: {}",
                                   sources.locate("machine.type").str(), machine["type"].dump(), x, e.what()));
    }
  }
  document["machine"] = std::move(machine);
  document["part"] = std::move(part);
  document["wheel"] = std::move(wheel);
  document["plan"] = std::move(plan);
}

std::pair<double, double> spindle_range_rpm(const Json& machine) {
  const Json& v = machine.at("spindle_speed_rpm");
  if (v.is_object()) return {v.at("from").get<double>(), v.at("to").get<double>()};
  return {v.get<double>(), v.get<double>()};
}

FeedPlanFigures plan_and_report(const Json& document, const std::filesystem::path& dir, bool plots) {
  PlanRun run;
  compute_plan(document, run);
  if (!dir.empty()) write_plan_files(run, document, dir, plots);
  const Schedule& s = run.schedule;
  FeedPlanFigures f;
  f.total_time_s = s.plan.total_time_s();
  f.lower_bound_s = s.lower_bound_s;
  f.segments = s.plan.segments.size();
  f.max_profile_error_mm = run.errors.total.max_abs_mm;
  f.rms_profile_error_mm = run.errors.total.rms_mm;
  f.max_edge_radius_mm = run.max_edge_radius_mm;
  f.schedule_certified = s.certificate.ok;
  f.certified = run.certified;
  f.certification_failures = run.certification_failures;
  return f;
}

namespace {

std::vector<SegmentConditions> conditions_of(const Schedule& s, const Generatrix& generatrix) {
  std::vector<SegmentConditions> out;
  for (std::size_t k = 0; k < s.plan.segments.size(); ++k) {
    SegmentConditions c;
    c.start_s = s.plan.segments[k].start_s;
    c.duration_s = s.plan.segments[k].duration_s;
    c.x_start_mm = s.knots_mm[k];
    c.x_end_mm = s.knots_mm[k + 1];
    c.radius_mm = generatrix.evaluate(0.5 * (c.x_start_mm + c.x_end_mm)).f;
    c.axial_speed_mm_per_s = (c.x_end_mm - c.x_start_mm) / c.duration_s;
    c.spindle_speed_rpm = s.plan.spindle_speed_rpm;
    c.contact_on_wheel_mm = 0.5 * (s.contact_on_tool_mm[k] + s.contact_on_tool_mm[k + 1]);
    out.push_back(c);
  }
  return out;
}

}  // namespace

PlannedFeed plan_feed_at(const PlanTables& tables, double spindle_rpm) {
  auto generatrix = build_generatrix(tables.part);
  auto kinematics = build_kinematics(tables.machine);
  FeedConstraints constraints = build_constraints(tables.machine, tables.plan, *kinematics);
  constraints.spindle_speed_rpm = spindle_rpm;
  const WearSweep sweep = build_sweep(tables.plan, tables.wheel);
  Schedule schedule;
  try {
    schedule = plan_feed(*generatrix, *kinematics, constraints, segment_length_mm(tables.plan, constraints),
                         sweep_function(sweep, generatrix->x_min_mm()), true,
                         wheel_contact(build_wheel(tables.wheel)));
  } catch (const std::exception& e) {
    throw PointFailure(fmt::format("no plan at {} rpm: {}", spindle_rpm, e.what()));
  }
  PlannedFeed out;
  out.segments = conditions_of(schedule, *generatrix);
  out.plan = std::move(schedule.plan);
  return out;
}

}  // namespace chatterlab::planner
