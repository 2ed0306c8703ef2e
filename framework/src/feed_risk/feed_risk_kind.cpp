#include "feed_risk/feed_risk_kind.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <tuple>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "feed_risk/feed_risk.hpp"
#include "chatterlab/kit/model.hpp"
#include "planner/feed_plan.hpp"
#include "planner/setup.hpp"

namespace chatterlab::feed_risk {

namespace {

namespace fs = std::filesystem;
using planner::SegmentConditions;

constexpr const char* model_keys[] = {"wheel_speed_rpm", "work_speed_rpm", "contact_stiffness_n_per_m",
                                      "wheel_wear_stiffness_n_per_m", "work_removal_stiffness_n_per_m"};

ParamSpec positive(std::string key, std::string unit, std::string description) {
  return planner::positive_spec(std::move(key), std::move(unit), std::move(description));
}
ParamSpec with_default(ParamSpec spec, Json value) {
  spec.default_value = std::move(value);
  return spec;
}
ParamSpec optional(ParamSpec spec) {
  spec.optional = true;
  return spec;
}

ParamSpec param_spec_bool(std::string key, std::string description) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::boolean, "1", std::move(description));
  spec.default_value = false;
  return spec;
}

std::vector<ParamSpec> simulation_specs() {
  ParamSpec enabled = param_spec("enabled", ValueKind::boolean, "1", "run the simulation along the plan");
  enabled.default_value = true;
  ParamSpec tolerance = with_default(positive("relative_tolerance", "1", "relative tolerance of the adaptive ARKODE route only (the along-plan simulation runs the fixed-step engine, which has none)"), 1e-4);
  tolerance.max = 1e-2;
  ParamSpec seed = param_spec("seed", ValueKind::integer, "1", "seed of the random initial surfaces");
  seed.default_value = 1;
  seed.min = 0;
  return {enabled,
          with_default(positive("sample_rate_hz", "Hz", "output samples reduced per work revolution"), 4000.0),
          tolerance, seed,
          with_default(positive("samples_per_wave", "1",
                                "surface samples per wave at the model's highest frequency (the engine's "
                                "default is 16; 8 halves the cost, growth rates change by ~0.1 %)"),
                       8.0),
          param_spec_bool("random_initial_surfaces",
                          "random initial wheel and work surfaces of +/- initial_waviness_um as well as the "
                          "initial displacement (white noise up to the surface resolution: ~10x the steps)"),
          with_default(positive("fit_window_revolutions", "1",
                                "work revolutions in the rolling fit of the simulated growth rate"),
                       10.0)};
}

std::vector<ParamSpec> optimise_specs() {
  ParamSpec steps = param_spec("speed_steps", ValueKind::integer, "1", "candidate spindle speeds per amplitude");
  steps.default_value = 11;
  steps.min = 1;
  steps.max = 1000;
  ParamSpec amplitudes = param_spec("modulation_amplitude_ratios", ValueKind::real_list, "1",
                                    "sinusoidal spindle-speed modulation amplitudes a (rpm = n (1 + a sin 2 pi f t))");
  amplitudes.default_value = Json::array({0.0});
  amplitudes.min = 0.0;
  amplitudes.min_items = 1;
  ParamSpec phases = param_spec("phase_samples", ValueKind::integer, "1",
                                "frozen speeds per modulation cycle in the averaged growth rate (S2)");
  phases.default_value = 8;
  phases.min = 1;
  phases.max = 64;
  ParamSpec factor = with_default(positive("max_time_factor", "1",
                                           "total time may grow to this multiple of the baseline plan's"),
                                  1.2);
  factor.min = 1.0;
  factor.min_exclusive = false;
  ParamSpec tolerance = with_default(positive("condition_tolerance", "1",
                                              "relative tolerance grouping segments in the search"),
                                     1e-2);
  tolerance.max = 0.1;
  ParamSpec band = param_spec("speed_tolerance", ValueKind::real, "1",
                              "spindle speed tolerance: candidates are rated by their worst case over "
                              "n (1 +- tol) (a verdict at an exact wheel/work speed ratio does not survive it)");
  band.default_value = 0.005;
  band.min = 0.0;
  band.max = 0.1;
  return {steps, amplitudes,
          with_default(positive("modulation_frequency_hz", "Hz", "modulation frequency f"), 0.5), phases,
          factor, tolerance, band};
}

fs::path study_dir(const SourceMap& sources, const std::string& key) {
  return fs::path(sources.locate(key).file).parent_path();
}

// The machine's spindle range [from, to] (a single value: from = to).
std::pair<double, double> spindle_range(const Json& machine) {
  const Json& v = machine.at("spindle_speed_rpm");
  if (v.is_object()) return {v.at("from").get<double>(), v.at("to").get<double>()};
  return {v.get<double>(), v.get<double>()};
}

struct PlanSource {
  Json machine, part, wheel, plan;
  std::vector<SegmentConditions> segments;
};

std::vector<SegmentConditions> conditions_of(const planner::Schedule& s, const planner::Generatrix& generatrix) {
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

// The feed planner at a given spindle speed (what feed_plan plans, without its reports).
planner::Schedule schedule_at(const PlanSource& src, double spindle_rpm) {
  auto generatrix = planner::build_generatrix(src.part);
  auto kinematics = planner::build_kinematics(src.machine);
  planner::FeedConstraints constraints = planner::build_constraints(src.machine, src.plan, *kinematics);
  constraints.spindle_speed_rpm = spindle_rpm;
  const planner::WearSweep sweep = planner::build_sweep(src.plan, src.wheel);
  try {
    return planner::plan_feed(*generatrix, *kinematics, constraints, planner::segment_length_mm(src.plan, constraints),
                              planner::sweep_function(sweep, generatrix->x_min_mm()), true,
                              planner::wheel_contact(planner::build_wheel(src.wheel)));
  } catch (const std::exception& e) {
    throw PointFailure(fmt::format("no plan at {} rpm: {}", spindle_rpm, e.what()));
  }
}

std::vector<SegmentConditions> plan_at(const PlanSource& src, double spindle_rpm) {
  return conditions_of(schedule_at(src, spindle_rpm), *planner::build_generatrix(src.part));
}

// The chatter-aware plan's pulses in feed_plan's pulses.csv format (segment, start_s, duration_s,
// <motor>_pulses), so the machine can run it.
void write_pulses(const fs::path& path, const planner::FeedPlan& plan) {
  std::vector<std::string> header{"segment", "start_s", "duration_s"};
  for (const MotorAxis& m : plan.motors) header.push_back(m.name + "_pulses");
  std::vector<std::vector<double>> c(header.size(), std::vector<double>(plan.segments.size()));
  for (std::size_t k = 0; k < plan.segments.size(); ++k) {
    c[0][k] = static_cast<double>(k);
    c[1][k] = plan.segments[k].start_s;
    c[2][k] = plan.segments[k].duration_s;
    for (std::size_t m = 0; m < plan.motors.size(); ++m)
      c[3 + m][k] = static_cast<double>(plan.segments[k].pulses[m]);
  }
  write_file_atomically(path, csv_text(header, c));
}

PlanSource plan_source(const Json& document) {
  PlanSource src;
  const Json& fr = document.at("feed_risk");
  if (fr["plan_dir"].is_string()) {
    planner::SavedPlan saved = planner::read_saved_plan(fr["plan_dir"].get<std::string>());
    src.machine = saved.machine;
    src.part = saved.part;
    src.wheel = saved.wheel;
    // The saved [plan] table (planner settings) for re-planning; read_saved_plan checked the file.
    InputFileStream in(fs::path(fr["plan_dir"].get<std::string>()) / "summary.json");
    src.plan = Json::parse(in).at("plan");
    src.segments = std::move(saved.segments);
    return src;
  }
  src.machine = document.at("machine");
  src.part = document.at("part");
  src.wheel = document.at("wheel");
  src.plan = document.at("plan");
  src.segments = plan_at(src, spindle_range(src.machine).second);
  return src;
}

ProcessSettings process_settings(const Json& document, const Json& wheel) {
  const Json& fr = document.at("feed_risk");
  const Json& model = document.at("model");
  ProcessSettings p;
  p.reference_contact_width_mm = fr.at("reference_contact_width_mm").get<double>();
  p.reference_work_radius_mm = fr.at("reference_work_radius_mm").get<double>();
  p.reference_work_speed_rpm = model.at("work_speed_rpm").get<double>();
  p.reference_wheel_speed_rpm = model.at("wheel_speed_rpm").get<double>();
  p.reference_contact_stiffness_n_per_m = model.at("contact_stiffness_n_per_m").get<double>();
  p.reference_wheel_wear_stiffness_n_per_m = model.at("wheel_wear_stiffness_n_per_m").get<double>();
  p.reference_work_removal_stiffness_n_per_m = model.at("work_removal_stiffness_n_per_m").get<double>();
  p.wheel_speed_rpm = fr.at("wheel_speed_rpm").is_number() ? fr["wheel_speed_rpm"].get<double>()
                                                           : p.reference_wheel_speed_rpm;
  p.wheel_diameter_mm = wheel.at("diameter_mm").get<double>();
  p.profiled_wheel = wheel.at("type").get<std::string>() == "profiled";
  p.wheel_thickness_mm = wheel.at("thickness_mm").get<double>();
  if (wheel.contains("edge_radius_mm") && wheel["edge_radius_mm"].is_number())
    p.edge_radius_mm = wheel["edge_radius_mm"].get<double>();
  p.edge_angle_deg = wheel.value("edge_angle_deg", 180.0);
  p.depth_of_cut_mm = fr.at("depth_of_cut_mm").get<double>();
  if (fr.at("contact_width_mm").is_number()) p.contact_width_mm = fr["contact_width_mm"].get<double>();
  p.speed_scaling = fr.at("speed_scaling").get<bool>();
  return p;
}

RiskThresholds thresholds_of(const Json& fr) {
  return {fr.at("marginal_growth_rate_per_s").get<double>(), fr.at("chatter_amplification").get<double>()};
}

constexpr const char* columns[] = {
    "total_time_s", "segments", "condition_groups", "max_growth_rate_per_s", "final_log_amplification",
    "max_log_amplification", "max_predicted_waviness_um", "worst_risk", "chatter_time_s",
    "simulated_max_waviness_um", "simulation_status", "optimised_spindle_speed_rpm",
    "optimised_amplitude_ratio", "optimised_total_time_s", "optimised_max_predicted_waviness_um",
    "optimised_simulated_max_waviness_um", "replan_verdict", "notice"};

Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(); }

std::string no_stable_candidate_notice(const OptimiseResult& best, const OptimiseSettings& os, const PlanRisk& risk,
                                       const RiskThresholds& thresholds) {
  const Candidate& c = best.candidates[best.best];
  return fmt::format(
      "no stable candidate: every spindle speed in [{}, {}] rpm (amplitudes {}) chatters or is marginal over the "
      "+-{:.2g} % speed band; the least risky, {:.1f} rpm, reaches growth {:.3g} /s (stable needs < {:.3g} /s) and is "
      "NOT written as an optimised plan.",
      os.spindle_min_rpm, os.spindle_max_rpm, Json(os.amplitude_ratios).dump(), 100 * os.speed_tolerance,
      c.spindle_speed_rpm, risk.max_growth_rate_per_s, -thresholds.marginal_growth_rate_per_s);
}

// The levers at the plan's worst segment (largest band growth rate), as JSON rows.
Json levers_at_worst_segment(const Json& model, const ProcessSettings& p, const PlanRisk& risk,
                             const RootSettings& roots, const RiskThresholds& thresholds, double speed_tolerance) {
  std::size_t worst = 0;
  for (std::size_t k = 1; k < risk.segments.size(); ++k)
    if (risk.segments[k].growth_rate_per_s > risk.segments[worst].growth_rate_per_s) worst = k;
  const Json table = segment_model_table(model, p, risk.process[worst]);
  // A margin beyond the marginal threshold, so the change lands clearly in the stable class.
  const double target = -1.5 * thresholds.marginal_growth_rate_per_s;
  Json rows = Json::array();
  for (const Lever& l : stability_levers(table, roots, target, speed_tolerance))
    rows.push_back({{"lever", l.name},
                    {"acts_on", l.acts_on},
                    {"growth_per_unit_log_per_s", l.growth_per_unit_log},
                    {"change_percent", l.change_percent ? Json(*l.change_percent) : Json()},
                    {"growth_rate_after_per_s", l.growth_rate_after_per_s},
                    {"reaches_stability", l.reaches_target},
                    {"at_x_mm", risk.process[worst].x_mid_mm}});
  return rows;
}

std::string levers_text(const Json& levers) {
  std::string text = " Levers at the worst segment:";
  for (const Json& l : levers) {
    if (l["change_percent"].is_null()) {
      text += fmt::format(" {}: no effect;", l["lever"].get<std::string>());
      continue;
    }
    text += fmt::format(" {} {:+.0f} % -> {:.3g} /s{};", l["lever"].get<std::string>(), l["change_percent"].get<double>(),
                        l["growth_rate_after_per_s"].get<double>(), l["reaches_stability"].get<bool>() ? " (stable)" : "");
  }
  text.pop_back();
  return text + " (feed per revolution does not enter the linear G1 stiffnesses: no lever).";
}

// results.csv simulation_status: completed, reached_depth_of_cut (the linear model ends where the
// wheel would leave the work; the rows up to there are kept) or failed (numerical failure).
const char* simulation_outcome(const AlongPlanSimulation& sim) {
  return sim.failed ? "failed" : sim.diverged ? "reached_depth_of_cut" : "completed";
}

double plan_time(const std::vector<SegmentConditions>& plan) {
  return plan.back().start_s + plan.back().duration_s - plan.front().start_s;
}

double max_waviness_um(const AlongPlanSimulation& sim) {
  double w = 0.0;
  for (const RevolutionRow& r : sim.revolutions) w = std::max(w, r.work_waviness_m);
  return 1e6 * w;
}

// Predicted waviness amplitude [um]: the initial waviness times the floored amplification, at most
// the depth of cut (beyond it the wheel leaves the work and the linear prediction ends).
struct Waviness {
  double initial_um, cap_um;
  double operator()(double floored_log) const {
    return std::min(cap_um, initial_um * std::exp(std::min(floored_log, 600.0)));
  }
};

// Floored ln amplification at time t (linear inside the segment in progress).
double floored_log_at(const std::vector<SegmentConditions>& plan, const PlanRisk& risk, double t) {
  auto it = std::upper_bound(plan.begin(), plan.end(), t,
                             [](double v, const SegmentConditions& c) { return v < c.start_s; });
  const std::size_t k = it == plan.begin() ? 0 : static_cast<std::size_t>(it - plan.begin()) - 1;
  const double before = k == 0 ? 0.0 : risk.segments[k - 1].floored_log_amplification;
  const double u = std::clamp((t - plan[k].start_s) / plan[k].duration_s, 0.0, 1.0);
  return std::max(0.0, before + u * (risk.segments[k].floored_log_amplification - before));
}

void write_segments(const fs::path& path, const std::vector<SegmentConditions>& plan, const PlanRisk& risk,
                    const Waviness& predicted_um) {
  const std::vector<std::string> header{
      "segment", "start_s", "duration_s", "x_start_mm", "x_end_mm", "radius_mm", "axial_speed_mm_per_s",
      "work_speed_rpm", "work_surface_speed_m_per_s", "speed_ratio", "equivalent_diameter_mm",
      "contact_length_mm", "contact_width_mm", "axial_feed_per_rev_mm", "overlap_ratio",
      "contact_stiffness_n_per_m", "wheel_wear_stiffness_n_per_m", "work_removal_stiffness_n_per_m",
      "growth_rate_per_s", "chatter_frequency_hz", "certified", "log_amplification",
      "floored_log_amplification", "predicted_waviness_um", "risk"};
  std::vector<std::vector<double>> c(header.size(), std::vector<double>(plan.size()));
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const SegmentProcess& s = risk.process[k];
    const SegmentRisk& r = risk.segments[k];
    const double row[] = {static_cast<double>(k), plan[k].start_s, plan[k].duration_s, plan[k].x_start_mm,
                          plan[k].x_end_mm, plan[k].radius_mm, plan[k].axial_speed_mm_per_s, s.work_speed_rpm,
                          s.work_surface_speed_m_per_s, s.speed_ratio, s.equivalent_diameter_mm,
                          s.contact_length_mm, s.contact_width_mm, s.axial_feed_per_rev_mm, s.overlap_ratio,
                          s.contact_stiffness_n_per_m, s.wheel_wear_stiffness_n_per_m,
                          s.work_removal_stiffness_n_per_m, r.growth_rate_per_s, r.chatter_frequency_hz,
                          r.certified ? 1.0 : 0.0, r.log_amplification, r.floored_log_amplification,
                          predicted_um(r.floored_log_amplification), static_cast<double>(r.risk)};
    for (std::size_t i = 0; i < header.size(); ++i) c[i][k] = row[i];
  }
  write_file_atomically(path, csv_text(header, c));
}

void write_along_x(const fs::path& path, const std::vector<SegmentConditions>& plan, const PlanRisk& risk,
                   const AlongPlanSimulation& sim, const Waviness& predicted_um) {
  const std::vector<std::string> header{"t_s", "x_mm", "predicted_waviness_um", "simulated_vibration_um",
                                        "simulated_waviness_um", "simulated_growth_rate_per_s"};
  const auto& rows = sim.revolutions;
  std::vector<std::vector<double>> c(header.size(), std::vector<double>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    c[0][i] = rows[i].t_s;
    c[1][i] = rows[i].x_mm;
    c[2][i] = predicted_um(floored_log_at(plan, risk, rows[i].t_s));
    c[3][i] = 1e6 * rows[i].vibration_amplitude_m;
    c[4][i] = 1e6 * rows[i].work_waviness_m;
    c[5][i] = rows[i].growth_rate_per_s;
  }
  write_file_atomically(path, csv_text(header, c));
}

std::string title_of(const Json& document) {
  if (document.contains("study") && document["study"].contains("name") && document["study"]["name"].is_string())
    return document["study"]["name"].get<std::string>();
  return "feed risk";
}

void draw(const plot::Curves& figure, const fs::path& dir, const std::string& stem, Json& failures) {
  try {
    plot::render(figure, dir, stem);
  } catch (const std::exception& e) {
    failures.push_back(fmt::format("{}: {}", stem, e.what()));
  }
}

void draw_plots(const Json& document, const fs::path& dir, const std::vector<SegmentConditions>& plan,
                const PlanRisk& risk, const AlongPlanSimulation* sim, const Waviness& predicted_um, Json& failures) {
  const std::string name = title_of(document);
  plot::Curves growth;
  growth.title = fmt::format("{}: growth rate along the plan", name);
  growth.x_label = "axial contact position x [mm]";
  growth.y_label = "growth rate Re s [1/s]";
  plot::Series roots{"rightmost root per segment (G1)", {}, {}, "lines"};
  for (std::size_t k = 0; k < plan.size(); ++k) {
    roots.x.push_back(risk.process[k].x_mid_mm);
    roots.y.push_back(risk.segments[k].growth_rate_per_s);
  }
  growth.series.push_back(roots);
  if (sim) {
    plot::Series fitted{"simulation: rolling fit of ln(amplitude)", {}, {}, "points"};
    for (const RevolutionRow& r : sim->revolutions)
      if (std::isfinite(r.growth_rate_per_s)) {
        fitted.x.push_back(r.x_mm);
        fitted.y.push_back(r.growth_rate_per_s);
      }
    if (!fitted.x.empty()) growth.series.push_back(fitted);
  }
  growth.reference_y = 0.0;
  growth.reference_label = "stability limit (Re s = 0)";
  draw(growth, dir, "growth_along_x", failures);

  plot::Curves waviness;
  waviness.title = fmt::format("{}: waviness along x", name);
  waviness.x_label = "axial contact position x [mm]";
  waviness.y_label = "waviness amplitude [um]";
  waviness.log_y = true;
  plot::Series predicted{"predicted: initial x accumulated amplification (roots), at most the depth of cut",
                         {plan.front().x_start_mm}, {predicted_um(0.0)}, "lines"};
  for (std::size_t k = 0; k < plan.size(); ++k) {
    predicted.x.push_back(plan[k].x_end_mm);
    predicted.y.push_back(predicted_um(risk.segments[k].floored_log_amplification));
  }
  waviness.series.push_back(predicted);
  if (sim) {
    plot::Series simulated{"simulated: work surface per revolution", {}, {}, "lines"};
    for (const RevolutionRow& r : sim->revolutions)
      if (r.work_waviness_m > 0) {
        simulated.x.push_back(r.x_mm);
        simulated.y.push_back(1e6 * r.work_waviness_m);
      }
    if (!simulated.x.empty()) waviness.series.push_back(simulated);
  }
  waviness.reference_y = predicted_um.cap_um;
  waviness.reference_label = "depth of cut (the linear model ends: the wheel leaves the work)";
  draw(waviness, dir, "waviness_along_x", failures);

  plot::Curves amplification;
  amplification.title = fmt::format("{}: ln amplification over time", name);
  amplification.x_label = "time t [s]";
  amplification.y_label = "ln(amplitude / initial amplitude)";
  plot::Series raw{"integral of the growth rate", {}, {}, "lines"}, floored{"floored at the disturbance level (0)", {}, {}, "lines"};
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const double t = plan[k].start_s + plan[k].duration_s;
    raw.x.push_back(t);
    raw.y.push_back(risk.segments[k].log_amplification);
    floored.x.push_back(t);
    floored.y.push_back(risk.segments[k].floored_log_amplification);
  }
  amplification.series = {raw, floored};
  draw(amplification, dir, "amplification_over_time", failures);
}

}  // namespace

PluginInfo FeedRiskKind::info() {
  PluginInfo info;
  info.name = "feed_risk";
  info.description =
      "chatter risk along a feed plan: rightmost root per segment, accumulated amplification, risk "
      "class, simulation along the schedule, chatter-aware spindle speed";
  info.models_md_ids = "P, G1, G3, G4, S2";
  ParamSpec plan_dir = param_spec("plan_dir", ValueKind::string, "",
                                  "a saved feed_plan output directory (pulses.csv, summary.json), relative to "
                                  "the study file; default: plan from [machine], [part], [wheel], [plan]");
  plan_dir.optional = true;
  ParamSpec scaling = param_spec("speed_scaling", ValueKind::boolean, "1",
                                 "scale kw by Kv/(1+Kv) and kg by 1/(1+Kv) with the local work surface speed (G4)");
  scaling.default_value = true;
  ParamSpec tolerance = with_default(positive("condition_tolerance", "1",
                                              "relative tolerance: segments whose G1 parameters agree within it share "
                                              "one root"),
                                     1e-3);
  tolerance.max = 0.1;
  ParamSpec amplification = with_default(positive("chatter_amplification", "1",
                                                  "risk class chatter: accumulated amplification at or above this"),
                                         10.0);
  amplification.min = 1.0;
  // [feed_risk.simulation] (always run unless disabled: its defaults) and [feed_risk.optimise]
  // (only when present).
  ParamSpec simulation = param_spec("simulation", ValueKind::table, "",
                                    "[feed_risk.simulation]: the simulation along the schedule");
  simulation.fields = simulation_specs();
  simulation.default_value = Json::object();
  ParamSpec optimise = optional(param_spec("optimise", ValueKind::table, "",
                                           "[feed_risk.optimise]: search for a chatter-aware spindle speed"));
  optimise.fields = optimise_specs();
  info.params = {
      plan_dir,
      positive("reference_contact_width_mm", "mm", "contact width at which the [model]'s kc, kg, kw hold"),
      positive("reference_work_radius_mm", "mm",
               "work radius at which the [model]'s kw, kg hold (with its work and wheel speeds)"),
      positive("depth_of_cut_mm", "mm", "radial stock removed by the pass (contact width and length)"),
      optional(positive("wheel_speed_rpm", "rpm", "wheel speed along the plan (default: the [model]'s)")),
      optional(positive("contact_width_mm", "mm", "fixed contact width instead of the geometric one")),
      scaling,
      with_default(positive("initial_waviness_um", "um",
                            "disturbance level: the predicted waviness starts here, the simulation's initial "
                            "displacement (docs/feed_risk.md)"),
                   1.0),
      with_default(positive("marginal_growth_rate_per_s", "1/s",
                            "risk class marginal: growth rate above minus this value"),
                   0.1),
      amplification,
      tolerance,
      simulation,
      optimise,
  };
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"reference_contact_width_mm", 35.0}, {"reference_work_radius_mm", 50.0},
                         {"depth_of_cut_mm", 0.01}};
  return info;
}

void FeedRiskKind::validate(Json& document, const SourceMap& sources) const {
  Json model = validate_component(document, "model", model_registry(), sources);
  for (const char* key : model_keys)
    if (!model.contains(key) || !model[key].is_number())
      throw InputError(fmt::format(
          "{}: model.type = \"{}\": plan/model mismatch: the feed_risk process model writes the local "
          "G1 parameters (wheel_speed_rpm, work_speed_rpm, contact_stiffness_n_per_m, "
          "wheel_wear_stiffness_n_per_m, work_removal_stiffness_n_per_m) into the model, which has no '{}'",
          sources.locate("model.type").str(), model["type"].get<std::string>(), key));
  {
    auto built = kit::build_model(model);
    if (!built->characteristic() || !built->time_domain())
      throw InputError(fmt::format("{}: model.type = \"{}\": feed_risk needs a characteristic function and a "
                                   "time-domain form", sources.locate("model.type").str(),
                                   model["type"].get<std::string>()));
  }
  Json stability = document.contains("stability") ? document["stability"] : Json::object();
  if (!stability.is_object())
    throw InputError(fmt::format("{}: stability = {}: expected a table [stability]",
                                 sources.locate("stability").str(), stability.dump()));
  stability = validate_params(stability, kit::stability_settings_table().specs(), "stability", sources);

  if (!document.contains("feed_risk") || !document["feed_risk"].is_object())
    throw InputError(fmt::format("{}: missing table [feed_risk] (the feed_risk study needs it)",
                                 sources.locate("study").str()));
  // Also [feed_risk.simulation] (defaults filled in) and [feed_risk.optimise] (null if absent).
  Json fr = validate_params(document["feed_risk"], info().params, "feed_risk", sources);
  const Json optimise = fr.at("optimise");

  // The plan: saved, or planned here from the feed_plan tables.
  Json machine, wheel;
  if (fr["plan_dir"].is_string()) {
    fs::path dir = fr["plan_dir"].get<std::string>();
    if (dir.is_relative()) dir = fs::absolute(study_dir(sources, "feed_risk.plan_dir") / dir);
    fr["plan_dir"] = dir.string();
    planner::SavedPlan saved;
    try {
      saved = planner::read_saved_plan(dir);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: feed_risk.plan_dir = \"{}\": {}", sources.locate("feed_risk.plan_dir").str(),
                                   dir.string(), e.what()));
    }
    if (saved.segments.empty())
      throw InputError(fmt::format("{}: feed_risk.plan_dir = \"{}\": the saved plan has no segments",
                                   sources.locate("feed_risk.plan_dir").str(), dir.string()));
    // Feed-plan tables next to plan_dir must describe the same machine and wheel.
    for (const char* table : {"machine", "wheel", "part"}) {
      if (!document.contains(table)) continue;
      const Json& saved_table = std::string(table) == "machine" ? saved.machine
                                : std::string(table) == "wheel" ? saved.wheel : saved.part;
      for (auto it = document[table].begin(); it != document[table].end(); ++it) {
        if (saved_table.contains(it.key()) && saved_table[it.key()] == it.value()) continue;
        throw InputError(fmt::format(
            "{}: {}.{} = {}: plan/model mismatch: the saved plan in {} has {}.{} = {}",
            sources.locate(std::string(table) + "." + it.key()).str(), table, it.key(), it.value().dump(),
            dir.string(), table, it.key(),
            saved_table.contains(it.key()) ? saved_table[it.key()].dump() : std::string("nothing")));
      }
    }
    if (document.contains("plan"))
      throw InputError(fmt::format("{}: [plan] with feed_risk.plan_dir: the saved plan's settings are used",
                                   sources.locate("plan").str()));
    machine = saved.machine;
    wheel = saved.wheel;
    const auto [from, to] = spindle_range(machine);
    const double rpm = saved.plan.spindle_speed_rpm;
    if (rpm < from * (1 - 1e-12) || rpm > to * (1 + 1e-12))
      throw InputError(fmt::format("{}: feed_risk.plan_dir = \"{}\": spindle range violated: the plan runs the "
                                   "spindle at {} rpm, outside the machine's range [{}, {}] rpm",
                                   sources.locate("feed_risk.plan_dir").str(), dir.string(), rpm, from, to));
  } else {
    for (const char* table : {"machine", "part", "wheel"})
      if (!document.contains(table))
        throw InputError(fmt::format("{}: missing table [{}]: feed_risk plans from [machine], [part], [wheel] "
                                     "(and [plan]) unless feed_risk.plan_dir names a saved plan",
                                     sources.locate("study").str(), table));
    planner::FeedPlanKind().validate(document, sources);
    machine = document["machine"];
    wheel = document["wheel"];
  }

  if (!optimise.is_null()) {
    const auto [from, to] = spindle_range(machine);
    for (const Json& a : optimise["modulation_amplitude_ratios"]) {
      const double ratio = a.get<double>();
      if (!(ratio < 1.0))
        throw InputError(fmt::format("{}: feed_risk.optimise.modulation_amplitude_ratios = {}: an amplitude ratio "
                                     "{} would stop or reverse the spindle (must be < 1)",
                                     sources.locate("feed_risk.optimise.modulation_amplitude_ratios").str(),
                                     optimise["modulation_amplitude_ratios"].dump(), ratio));
      if (from / (1.0 - ratio) > to / (1.0 + ratio) * (1 + 1e-12))
        throw InputError(fmt::format(
            "{}: feed_risk.optimise.modulation_amplitude_ratios = {}: spindle range violated: with amplitude "
            "ratio {} no mean speed keeps n (1 - a) >= {} rpm and n (1 + a) <= {} rpm",
            sources.locate("feed_risk.optimise.modulation_amplitude_ratios").str(),
            optimise["modulation_amplitude_ratios"].dump(), ratio, from, to));
    }
  }
  if (!wheel.contains("diameter_mm"))
    throw InputError(fmt::format("{}: the wheel has no diameter_mm", sources.locate("wheel").str()));
  document["model"] = std::move(model);
  document["stability"] = std::move(stability);
  document["feed_risk"] = std::move(fr);
}

std::vector<std::string> FeedRiskKind::output_columns(const Json& /*document*/) const {
  return {std::begin(columns), std::end(columns)};
}

std::vector<Json> FeedRiskKind::run_point(const Json& document, const PointContext& context) const {
  const Json& fr = document.at("feed_risk");
  const Json& sim_table = fr.at("simulation");
  const PlanSource src = plan_source(document);
  const ProcessSettings p = process_settings(document, src.wheel);
  auto generatrix = planner::build_generatrix(src.part);
  const RiskThresholds thresholds = thresholds_of(fr);
  const RootSettings roots{document.at("stability"), fr.at("condition_tolerance").get<double>()};
  const double w0_um = fr.at("initial_waviness_um").get<double>();
  const Waviness predicted_um{w0_um, 1e3 * p.depth_of_cut_mm};
  const Json& model = document.at("model");

  const PlanRisk risk = evaluate_roots(model, p, src.segments, *generatrix, roots, thresholds);
  AlongPlanSettings sim_settings;
  sim_settings.sample_rate_hz = sim_table.at("sample_rate_hz").get<double>();
  sim_settings.relative_tolerance = sim_table.at("relative_tolerance").get<double>();
  sim_settings.initial_waviness_m = 1e-6 * w0_um;
  sim_settings.divergence_limit_m = 1e-3 * p.depth_of_cut_mm;
  sim_settings.seed = sim_table.at("seed").get<std::uint64_t>();
  sim_settings.samples_per_wave = sim_table.at("samples_per_wave").get<double>();
  sim_settings.random_initial_surfaces = sim_table.at("random_initial_surfaces").get<bool>();
  sim_settings.fit_window_revolutions = sim_table.at("fit_window_revolutions").get<double>();
  const bool simulate = sim_table.at("enabled").get<bool>();
  AlongPlanSimulation sim;
  if (simulate) sim = simulate_along_plan(model, p, src.segments, risk, sim_settings);

  Json summary = {
      {"total_time_s", plan_time(src.segments)},
      {"segments", src.segments.size()},
      {"condition_groups", risk.groups},
      {"spindle_speed_rpm", src.segments.front().spindle_speed_rpm},
      {"wheel_speed_rpm", p.wheel_speed_rpm},
      {"max_growth_rate_per_s", risk.max_growth_rate_per_s},
      {"final_log_amplification", risk.final_log_amplification},
      {"max_log_amplification", risk.max_floored_log_amplification},
      {"max_predicted_waviness_um", predicted_um(risk.max_floored_log_amplification)},
      {"worst_risk", to_string(risk.worst)},
      {"time_in_risk_s", {{"stable", risk.time_in_risk_s[0]}, {"marginal", risk.time_in_risk_s[1]},
                          {"chatter", risk.time_in_risk_s[2]}}},
      {"thresholds", {{"marginal_growth_rate_per_s", thresholds.marginal_growth_rate_per_s},
                      {"chatter_amplification", thresholds.chatter_amplification}}},
  };
  if (simulate)
    summary["simulation"] = {{"outcome", simulation_outcome(sim)}, {"engine_status", sim.status}, {"failed", sim.failed}, {"diverged", sim.diverged},
                             {"end_time_s", sim.end_time_s}, {"steps", sim.steps},
                             {"wall_s", sim.wall_s}, {"revolutions", sim.revolutions.size()},
                             {"max_work_waviness_um", max_waviness_um(sim)}};

  Json optimised = Json::object();
  bool stable_replan = false;
  std::string notice;
  std::optional<OptimiseResult> best;
  PlanRisk best_risk;
  AlongPlanSimulation best_sim;
  if (!fr.at("optimise").is_null()) {
    const Json& o = fr["optimise"];
    OptimiseSettings os;
    std::tie(os.spindle_min_rpm, os.spindle_max_rpm) = spindle_range(src.machine);
    os.speed_steps = o.at("speed_steps").get<int>();
    os.amplitude_ratios = o.at("modulation_amplitude_ratios").get<std::vector<double>>();
    os.modulation_frequency_hz = o.at("modulation_frequency_hz").get<double>();
    os.phase_samples = o.at("phase_samples").get<int>();
    os.max_time_factor = o.at("max_time_factor").get<double>();
    os.condition_tolerance = o.at("condition_tolerance").get<double>();
    os.speed_tolerance = o.at("speed_tolerance").get<double>();
    best = optimise(model, p, [&](double rpm) { return plan_at(src, rpm); }, plan_time(src.segments), *generatrix,
                    roots, thresholds, os);
    const Candidate& c = best->candidates[best->best];
    // The chosen plan rated at full resolution (roots at the mean speed; the modulation's frozen-
    // speed average is the candidate's own rating) and simulated with the exact modulated spindle.
    best_risk = evaluate_roots(model, p, best->best_plan, *generatrix, roots, thresholds, os.speed_tolerance);
    stable_replan = best->stable && best_risk.worst == Risk::stable;
    if (simulate && stable_replan) {
      AlongPlanSettings s = sim_settings;
      if (c.amplitude_ratio > 0)
        s.work_speed = make_modulated_speed(c.spindle_speed_rpm, SpeedModulation::sinusoidal, c.amplitude_ratio,
                                            os.modulation_frequency_hz);
      best_sim = simulate_along_plan(model, p, best->best_plan, best_risk, s);
    }
    Json rows = Json::array();
    for (const Candidate& k : best->candidates)
      rows.push_back({{"spindle_speed_rpm", k.spindle_speed_rpm}, {"amplitude_ratio", k.amplitude_ratio},
                      {"total_time_s", k.total_time_s}, {"time_factor", k.time_factor},
                      {"max_growth_rate_per_s", k.max_growth_rate_per_s},
                      {"nominal_max_growth_rate_per_s", k.nominal_max_growth_rate_per_s},
                      {"exact_speed_ratio", k.exact_speed_ratio},
                      {"max_log_amplification", k.max_floored_log_amplification},
                      {"worst_risk", to_string(k.worst)}, {"admissible", k.admissible}});
    optimised = {{"spindle_speed_rpm", c.spindle_speed_rpm},
                 {"modulation_amplitude_ratio", c.amplitude_ratio},
                 {"modulation_frequency_hz", c.amplitude_ratio > 0 ? os.modulation_frequency_hz : 0.0},
                 {"planning_speed_rpm", c.planning_speed_rpm},
                 {"total_time_s", c.total_time_s},
                 {"time_factor", c.time_factor},
                 {"max_time_factor", os.max_time_factor},
                 {"search_max_log_amplification", c.max_floored_log_amplification},
                 {"max_growth_rate_per_s", best_risk.max_growth_rate_per_s},
                 {"max_log_amplification", best_risk.max_floored_log_amplification},
                 {"max_predicted_waviness_um", predicted_um(best_risk.max_floored_log_amplification)},
                 {"worst_risk", to_string(best_risk.worst)},
                 {"speed_tolerance", os.speed_tolerance},
                 {"nominal_max_growth_rate_per_s", c.nominal_max_growth_rate_per_s},
                 {"exact_speed_ratio", c.exact_speed_ratio},
                 {"stable_over_speed_band", stable_replan},
                 {"candidates", rows}};
    if (best->stable_window_rpm)
      optimised["stable_window_rpm"] = {{"from", best->stable_window_rpm->first},
                                        {"to", best->stable_window_rpm->second},
                                        {"candidate_spacing_rpm", best->speed_spacing_rpm}};
    if (stable_replan) {
      optimised["verdict"] = "stable";
      optimised["plan_written"] = true;
    } else {
      optimised["verdict"] = "no stable candidate";
      optimised["plan_written"] = false;
      notice = no_stable_candidate_notice(*best, os, best_risk, thresholds);
      optimised["levers"] = levers_at_worst_segment(model, p, best_risk, roots, thresholds, os.speed_tolerance);
      notice += levers_text(optimised["levers"]);
      optimised["notice"] = notice;
    }
    if (simulate && stable_replan)
      optimised["simulation"] = {{"outcome", simulation_outcome(best_sim)}, {"engine_status", best_sim.status}, {"failed", best_sim.failed}, {"diverged", best_sim.diverged},
                                 {"max_work_waviness_um", max_waviness_um(best_sim)}};
    summary["optimised"] = optimised;
  }

  if (!context.artifact_dir.empty()) {
    const fs::path& dir = context.artifact_dir;
    write_segments(dir / "segments.csv", src.segments, risk, predicted_um);
    if (best && stable_replan) {
      // Re-planned once more at the chosen planning speed (deterministic: the same plan).
      write_pulses(dir / "optimised_pulses.csv",
                   schedule_at(src, best->candidates[best->best].planning_speed_rpm).plan);
    }
    if (simulate) write_along_x(dir / "along_x.csv", src.segments, risk, sim, predicted_um);
    Json failures = Json::array();
    if (context.plots) draw_plots(document, dir, src.segments, risk, simulate ? &sim : nullptr, predicted_um, failures);
    if (best) {
      if (stable_replan) write_segments(dir / "optimised_segments.csv", best->best_plan, best_risk, predicted_um);
      const auto& cands = best->candidates;
      std::vector<std::vector<double>> c(7, std::vector<double>(cands.size()));
      for (std::size_t i = 0; i < cands.size(); ++i) {
        const double row[] = {cands[i].spindle_speed_rpm, cands[i].amplitude_ratio, cands[i].total_time_s,
                              cands[i].time_factor, cands[i].max_growth_rate_per_s,
                              cands[i].max_floored_log_amplification, cands[i].admissible ? 1.0 : 0.0};
        for (std::size_t j = 0; j < 7; ++j) c[j][i] = row[j];
      }
      write_file_atomically(dir / "optimisation.csv",
                            csv_text({"spindle_speed_rpm", "amplitude_ratio", "total_time_s", "time_factor",
                                      "max_growth_rate_per_s", "max_log_amplification", "admissible"},
                                     c));
      if (context.plots) {
        plot::Curves search;
        search.title = fmt::format("{}: chatter-aware spindle speed", title_of(document));
        search.x_label = "mean spindle speed n [rpm]";
        search.y_label = "max accumulated ln amplification";
        std::vector<double> amplitudes;
        for (const Candidate& k : cands)
          if (std::find(amplitudes.begin(), amplitudes.end(), k.amplitude_ratio) == amplitudes.end())
            amplitudes.push_back(k.amplitude_ratio);
        for (double a : amplitudes) {
          plot::Series s{fmt::format("modulation a = {}", a), {}, {}, "linespoints"};
          for (const Candidate& k : cands)
            if (k.amplitude_ratio == a && k.admissible) {
              s.x.push_back(k.spindle_speed_rpm);
              s.y.push_back(k.max_floored_log_amplification);
            }
          if (!s.x.empty()) search.series.push_back(s);
        }
        const Candidate& chosen = cands[best->best];
        search.series.push_back({stable_replan ? "chosen" : "least risk: no candidate is stable", {chosen.spindle_speed_rpm},
                                 {chosen.max_floored_log_amplification}, "points"});
        draw(search, dir, "optimisation", failures);

        plot::Curves compare;
        compare.title = fmt::format("{}: predicted waviness before / after", title_of(document));
        compare.x_label = "axial contact position x [mm]";
        compare.y_label = "waviness amplitude [um]";
        compare.log_y = true;
        auto series = [&](const std::string& label, const std::vector<SegmentConditions>& plan, const PlanRisk& r) {
          plot::Series s{label, {plan.front().x_start_mm}, {predicted_um(0.0)}, "lines"};
          for (std::size_t k = 0; k < plan.size(); ++k) {
            s.x.push_back(plan[k].x_end_mm);
            s.y.push_back(predicted_um(r.segments[k].floored_log_amplification));
          }
          return s;
        };
        compare.series.push_back(series(fmt::format("before: {:.0f} rpm, {:.0f} s", src.segments.front().spindle_speed_rpm,
                                                    plan_time(src.segments)), src.segments, risk));
        compare.series.push_back(series(fmt::format("{}: {:.1f} rpm, a = {}, {:.0f} s",
                                                    stable_replan ? "after" : "least risk (NOT stable)",
                                                    chosen.spindle_speed_rpm,
                                                    chosen.amplitude_ratio, chosen.total_time_s),
                                        best->best_plan, best_risk));
        if (simulate) {
          auto simulated = [](const std::string& label, const AlongPlanSimulation& run) {
            plot::Series s{label, {}, {}, "lines"};
            for (const RevolutionRow& r : run.revolutions)
              if (r.work_waviness_m > 0) {
                s.x.push_back(r.x_mm);
                s.y.push_back(1e6 * r.work_waviness_m);
              }
            return s;
          };
          compare.series.push_back(simulated("before, simulated", sim));
          if (stable_replan) compare.series.push_back(simulated("after, simulated", best_sim));
        }
        draw(compare, dir, "before_after", failures);
      }
    }
    summary["plot_errors"] = failures;
    write_json_file(dir / "summary.json", summary);
  }

  // The optimised columns describe a plan only when one was written.
  auto optional_number = [&](const char* key) {
    return stable_replan && optimised.contains(key) ? optimised[key] : Json();
  };
  return {summary["total_time_s"],
          summary["segments"],
          summary["condition_groups"],
          number_or_null(risk.max_growth_rate_per_s),
          number_or_null(risk.final_log_amplification),
          number_or_null(risk.max_floored_log_amplification),
          number_or_null(predicted_um(risk.max_floored_log_amplification)),
          to_string(risk.worst),
          risk.time_in_risk_s[2],
          simulate && !sim.revolutions.empty() ? Json(max_waviness_um(sim)) : Json(),
          simulate ? Json(simulation_outcome(sim)) : Json("off"),
          optional_number("spindle_speed_rpm"),
          optional_number("modulation_amplitude_ratio"),
          optional_number("total_time_s"),
          optional_number("max_predicted_waviness_um"),
          best && simulate && stable_replan ? Json(max_waviness_um(best_sim)) : Json(),
          best ? Json(stable_replan ? "stable" : "no stable candidate") : Json(),
          notice};
}

void FeedRiskKind::write_artifacts(const Study& /*study*/, const ResultTable& /*results*/,
                                   const fs::path& /*out_dir*/) const {
  // Every figure belongs to one plan and is drawn by run_point into its artefact directory.
}

bool FeedRiskKind::requires_serial(const Json& document) const {
  return model_is_serial(document.at("model"));
}

}  // namespace chatterlab::feed_risk

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::feed_risk::FeedRiskKind);
