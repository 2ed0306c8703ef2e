#include "study_kinds/cam_plan/cam_plan.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <optional>

#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/kit/output.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/planner/cam_planning.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab::planner {

namespace {

namespace fs = std::filesystem;
constexpr double pi = std::numbers::pi;

// [part]: the lift table and the fit (K1, K3), declared once.
struct CamPart {
  std::string lift_table_file;  // required; absolute after validation
  std::optional<std::vector<double>> chosen_angles_deg;
  double target_fit_error_mm = 5e-4;
};

const ParamTable<CamPart>& part_table() {
  static const ParamTable<CamPart> table = [] {
    ParamTable<CamPart> t;
    t.add(&CamPart::lift_table_file, "lift_table_file", "", "CSV angle_deg,radius_mm (relative to the study file)")
        .required();
    t.add(&CamPart::chosen_angles_deg, "chosen_angles_deg", "deg",
          "table rows the spline starts from (default: every row)").at_least(0.0).at_most(360.0);
    t.add(&CamPart::target_fit_error_mm, "target_fit_error_mm", "mm",
          "add table rows until every row is fitted within this (0: none)").non_negative();
    return t;
  }();
  return table;
}

LiftTable read_lift_table(const CamPart& part) {
  const fs::path file = part.lift_table_file;
  const DataTable data = read_data_table(file);
  LiftTable table{data.column("angle_deg"), data.column("radius_mm")};
  for (std::size_t i = 0; i < table.angle_deg.size(); ++i)
    if (!(table.angle_deg[i] > 0 && table.angle_deg[i] <= 360 && table.radius_mm[i] > 0))
      throw InputError(fmt::format("{}:{}: angle {} deg, radius {} mm: angles must lie in (0, 360] "
                                   "and radii be > 0", file.string(), data.source_line(i),
                                   table.angle_deg[i], table.radius_mm[i]));
  return table;
}

std::vector<double> chosen_angles(const CamPart& part, const LiftTable& table) {
  return part.chosen_angles_deg ? *part.chosen_angles_deg : table.angle_deg;
}

// The machine of a validated [machine] table (the planner's rules left out).
std::unique_ptr<Kinematics> build(const Json& machine) {
  Json params = machine;
  params.erase("type");
  for (const ParamSpec& rule : cam_machine_rule_specs()) params.erase(rule.key);
  return kinematics_registry().at(machine.at("type").get<std::string>()).create(ParamValues(params));
}

Json required_table(const Json& document, const char* key, const SourceMap& sources) {
  if (!document.contains(key) || !document[key].is_object())
    throw InputError(fmt::format("{}: missing table [{}] (the cam_plan study needs it)",
                                 sources.locate("study").str(), key));
  return document[key];
}

// [machine]: a kinematics plugin that can grind cams, plus the planner's rules.
Json validate_machine(const Json& document, const SourceMap& sources) {
  Json machine = required_table(document, "machine", sources);
  Json rules = Json::object();
  for (const ParamSpec& rule : cam_machine_rule_specs())
    if (machine.contains(rule.key)) {
      rules[rule.key] = machine[rule.key];
      machine.erase(rule.key);
    }
  rules = validate_params(rules, cam_machine_rule_specs(), "machine", sources);
  Json validated = validate_component(Json{{"machine", machine}}, "machine", kinematics_registry(), sources);
  validated.update(rules);
  if (!build(validated)->cam_grinding())
    throw InputError(fmt::format("{}: machine.type = {}: a cam_plan needs a machine that can grind cams "
                                 "(a rotary part axis and a wheel slide: the cam-grinding capability, e.g. "
                                 "xc_cam)", sources.locate("machine.type").str(), validated["type"].dump()));
  return validated;
}

// The seed fit (the chosen rows) and the adaptive one (rows inserted to the target).
struct CamFits {
  LiftTable table;
  ParametricSpline seed_spline{{{1, 0}, {0, 1}, {-1, 0}}, SplineEnds::periodic};
  ParametricSpline spline = seed_spline;
  CamFit seed, adaptive;
};

CamFits fit_profile(const CamPart& part) {
  CamFits f;
  f.table = read_lift_table(part);
  const std::vector<double> chosen = chosen_angles(part, f.table);
  f.seed = fit_cam(f.table, chosen, 0.0, &f.seed_spline);
  f.adaptive = fit_cam(f.table, chosen, part.target_fit_error_mm, &f.spline);
  return f;
}

Json fit_json(const CamFit& fit) {
  return {{"max_radius_error_mm", fit.max_radius_error_mm},
          {"mean_abs_radius_error_mm", fit.mean_abs_radius_error_mm},
          {"max_x_error_mm", fit.max_x_error_mm}, {"max_y_error_mm", fit.max_y_error_mm},
          {"worst_angle_deg", fit.worst_angle_deg}};
}

Json cam_summary(const Json& doc, const CamFits& fits, const CamPlan& cam, double wheel_radius_mm) {
  Json adaptive = {{"points", fits.adaptive.chosen_angles_deg.size()}, {"inserted", fits.adaptive.inserted},
                   {"inserted_angles_deg", fits.adaptive.chosen_angles_deg}};
  adaptive.update(fit_json(fits.adaptive));
  const bool concave = std::isfinite(cam.min_concave_radius_mm);
  return {
      {"certified", cam.certified},
      {"certification_failures", cam.certification_failures},
      {"certification", "every machine rule after integerisation and the lift requirements (K3) in "
                        "the replay, and the controller output read back exactly"},
      {"controller_export", {{"files", {"program.ngc", "steps.csv"}},
                             {"gcode_axes", {{"C", "c_axis (deg)"}, {"X", "x_slide (mm)"}}},
                             {"tick_hz", cam.tick_hz},
                             {"round_trip", cam.controller_round_trip},
                             {"shortest_step_interval_s", cam.shortest_step_interval_s}}},
      {"chosen_points", fits.seed.chosen_angles_deg.size()},
      {"chosen_points_fit", fit_json(fits.seed)},
      {"adaptive_fit", adaptive},
      {"total_time_s", cam.total_time_s},
      {"lower_bound_s", cam.lower_bound_s},
      {"lower_bound_kind", "continuous relaxation: the exact path at the largest speed each "
                           "per-segment bound allows (C speed, pulse rates), without smoothness"},
      {"gap_percent", 100.0 * (cam.total_time_s - cam.lower_bound_s) / cam.lower_bound_s},
      {"mean_cam_speed_rpm", 60.0 / cam.total_time_s},
      {"segments", cam.segments},
      {"smoothing_passes", cam.smoothing_passes},
      {"certificate", cam.certificate},
      {"pre_motion", {{"ramp_segments_each_end", cam.ramp_segments},
                      {"ramp_time_s", cam.ramp_time_s},
                      {"note", "the C axis and X slide ramp up from rest before the wheel engages "
                               "(and down after it leaves), not in total_time_s"}}},
      {"initial_position", {{"c_axis_deg", cam.targets[0][0]}, {"x_slide_mm", cam.targets[0][1]}}},
      {"max_profile_error_mm", cam.max_profile_error_mm},
      {"rms_profile_error_mm", cam.rms_profile_error_mm},
      {"max_lift_error_mm", cam.max_lift_error_mm},
      {"lift_error_method", "radial deviation of the surface the wheel leaves: every replayed "
                            "state, per 0.1 deg of cam angle the deepest; per degree: the largest "
                            "change between bins 1 deg apart"},
      {"replayed_states", cam.replayed_states},
      {"max_per_degree_error_mm", cam.max_per_degree_lift_error_mm},
      {"max_per_degree_lift_error_mm", cam.max_per_degree_lift_error_mm},
      {"meets_requirements", cam.meets_requirements},
      {"min_concave_radius_mm", concave ? Json(cam.min_concave_radius_mm) : Json()},
      {"min_concave_radius_at_deg", cam.min_concave_radius_at_deg},
      {"wheel_gouges_concave_parts", concave && wheel_radius_mm > cam.min_concave_radius_mm},
      {"requirements", {{"total_lift_error_mm", cam_total_lift_error_limit_mm},
                        {"per_degree_lift_error_mm", cam_per_degree_lift_error_limit_mm}}},
      {"machine", doc.at("machine")}, {"part", doc.at("part")}, {"plan", doc.at("plan")}};
}

// Fitted minus table radius at every table row, for the seed and the adaptive spline.
std::vector<std::vector<double>> fit_error_columns(const CamFits& fits) {
  std::vector<std::vector<double>> cols(4);
  for (std::size_t i = 0; i < fits.table.angle_deg.size(); ++i) {
    const double phi = fits.table.angle_deg[i] * pi / 180;
    cols[0].push_back(fits.table.angle_deg[i]);
    cols[1].push_back(fits.table.radius_mm[i]);
    cols[2].push_back(fits.seed_spline.polar_radius(phi) - fits.table.radius_mm[i]);
    cols[3].push_back(fits.spline.polar_radius(phi) - fits.table.radius_mm[i]);
  }
  return cols;
}

void write_cam_files(const fs::path& dir, const CamFits& fits, const CamPlan& cam) {
  write_file_atomically(dir / "program.ngc", cam.gcode);
  write_file_atomically(dir / "steps.csv", cam.step_table);
  std::vector<std::vector<double>> cols(5);
  for (std::size_t k = 0; k < cam.segments; ++k) {
    const PlanSegment& seg = cam.plan.segments[k];
    cols[0].push_back(static_cast<double>(k));
    cols[1].push_back(seg.start_s);
    cols[2].push_back(seg.duration_s);
    cols[3].push_back(static_cast<double>(seg.pulses[0]));
    cols[4].push_back(static_cast<double>(seg.pulses[1]));
  }
  write_file_atomically(dir / "pulses.csv",
                        csv_text({"segment", "start_s", "duration_s", "c_axis_pulses", "x_slide_pulses"}, cols));
  write_file_atomically(dir / "fit_errors.csv",
                        csv_text({"angle_deg", "radius_mm", "chosen_points_error_mm", "adaptive_error_mm"},
                                 fit_error_columns(fits)));
}

plot::Curves fit_error_figure(const CamFits& fits) {
  const auto cols = fit_error_columns(fits);
  plot::Curves f;
  f.title = "cam fit error at the lift-table rows";
  f.x_label = "cam angle [deg]";
  f.y_label = "fitted - table radius [um]";
  plot::Series a{fmt::format("{} chosen points", fits.seed.chosen_angles_deg.size()), cols[0], {}, "linespoints"};
  plot::Series b{fmt::format("after adaptive insertion ({} points)", fits.adaptive.chosen_angles_deg.size()),
                 cols[0], {}, "linespoints"};
  for (std::size_t i = 0; i < cols[0].size(); ++i) {
    a.y.push_back(1000 * cols[2][i]);
    b.y.push_back(1000 * cols[3][i]);
  }
  f.series = {a, b};
  return f;
}

plot::Curves lift_error_figure(const CamPlan& cam) {
  plot::Curves e;
  e.title = "lift error of the ground surface, per 0.1 deg (limit +-15 um)";
  e.x_label = "contact polar angle [deg]";
  e.y_label = "radial deviation [um] (+ material left)";
  plot::Series s{"lift error (deepest replayed state)", cam.lift_bin_angle_deg, {}, "lines"};
  plot::Series binds{"requirement binds (>= 90 % of 15 um)", {}, {}, "points"};
  for (std::size_t i = 0; i < cam.lift_error_mm.size(); ++i) {
    s.y.push_back(1000 * cam.lift_error_mm[i]);
    if (std::abs(cam.lift_error_mm[i]) >= 0.9 * cam_total_lift_error_limit_mm) {
      binds.x.push_back(cam.lift_bin_angle_deg[i]);
      binds.y.push_back(1000 * cam.lift_error_mm[i]);
    }
  }
  const double gap = std::nan("");
  plot::Series band{"requirement +-15 um (K3)", {0, 360, gap, 0, 360}, {15, 15, gap, -15, -15}, "dashes"};
  e.series = {s, band};
  if (!binds.x.empty()) e.series.push_back(binds);
  return e;
}

plot::Curves slide_figure(const CamPlan& cam) {
  plot::Curves x;
  x.title = "X slide position (tangent-point tracking)";
  x.x_label = "contact polar angle [deg]";
  x.y_label = "wheel centre distance from the C axis [mm]";
  plot::Series xs{"X slide", {}, {}, "lines"};
  for (std::size_t k = 0; k <= cam.segments; ++k) {
    xs.x.push_back(360.0 * static_cast<double>(k) / static_cast<double>(cam.segments));
    xs.y.push_back(cam.targets[k][1]);
  }
  x.series = {xs};
  return x;
}

// The figures; failures are listed in summary.json (plot_errors), not thrown.
Json draw_cam_plots(const fs::path& dir, const CamFits& fits, const CamPlan& cam) {
  Json plot_errors = Json::array();
  auto draw = [&](const plot::Curves& c, const std::string& stem) {
    try {
      plot::render(c, dir, stem);
    } catch (const std::exception& e) {
      plot_errors.push_back(fmt::format("{}: {}", stem, e.what()));
    }
  };
  draw(fit_error_figure(fits), "fit_error");
  draw(lift_error_figure(cam), "profile_error");
  draw(slide_figure(cam), "x_slide");
  return plot_errors;
}

constexpr const char* columns[] = {"seed_points_max_fit_error_mm", "max_fit_error_mm", "inserted_points",
                                   "total_time_s", "lower_bound_s", "max_profile_error_mm",
                                   "max_lift_error_mm", "max_per_degree_error_mm", "certified"};

}  // namespace

PluginInfo CamPlanKind::info() {
  return plugin_info("cam_plan", "K1-K3",
                     cam_plan_settings_specs(),
                     {{"segment_angle_deg", 1.0}},
                     "X-C cam grinding: spline fit of a lift table with adaptive insertion, "
                     "tangent-point tracking, pulses and replayed profile error");
}

void CamPlanKind::validate(Json& document, const SourceMap& sources) const {
  Json machine = validate_machine(document, sources);
  required_table(document, "part", sources);
  CamPart part = kit::validate_settings(document, "part", part_table(), sources);
  document["plan"] = validate_params(kit::table_or_empty(document, "plan", sources), info().params, "plan", sources);
  const fs::path study_dir = fs::path(sources.locate("part.lift_table_file").file).parent_path();
  part.lift_table_file = fs::absolute(study_dir / part.lift_table_file).string();
  document["part"]["lift_table_file"] = part.lift_table_file;
  const LiftTable table = read_lift_table(part);
  try {
    fit_cam(table, chosen_angles(part, table), 0.0);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: part = lift table {}: {}", sources.locate("part").str(),
                                 part.lift_table_file, e.what()));
  }
  document["machine"] = std::move(machine);
}

std::vector<std::string> CamPlanKind::output_columns(const Json&) const {
  return {std::begin(columns), std::end(columns)};
}

std::vector<Json> CamPlanKind::run_point(const Json& doc, const PointContext& context) const {
  const CamFits fits = fit_profile(kit::read_settings(doc, "part", part_table()));
  const auto kinematics = build(doc.at("machine"));
  const CamPlan cam = plan_cam(fits.spline, *kinematics, doc.at("machine"), doc.at("plan"));
  if (!context.artifact_dir.empty()) {
    const fs::path& dir = context.artifact_dir;
    write_cam_files(dir, fits, cam);
    Json summary = cam_summary(doc, fits, cam, kinematics->cam_grinding()->wheel_radius_mm());
    summary["plot_errors"] = context.plots ? draw_cam_plots(dir, fits, cam) : Json::array();
    kit::write_summary(context, summary);
  }
  // A plan that breaks a rule or misses the lift requirements is never "ok" (files written above).
  if (!cam.certified)
    throw PointFailure(fmt::format("plan not certified: {}", fmt::join(cam.certification_failures, "; ")));
  return {fits.seed.max_radius_error_mm, fits.adaptive.max_radius_error_mm,
          static_cast<double>(fits.adaptive.inserted), cam.total_time_s, cam.lower_bound_s,
          cam.max_profile_error_mm, cam.max_lift_error_mm, cam.max_per_degree_lift_error_mm, cam.certified};
}

}  // namespace chatterlab::planner

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::planner::CamPlanKind);
