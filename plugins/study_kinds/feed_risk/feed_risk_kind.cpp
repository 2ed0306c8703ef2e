#include "study_kinds/feed_risk/feed_risk_kind.hpp"

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
#include "chatterlab/plugin_info.hpp"
#include "study_kinds/feed_risk/feed_risk.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/kit/output.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/planner/feed_planning.hpp"

namespace chatterlab::feed_risk {

namespace {

namespace fs = std::filesystem;
using planner::SegmentConditions;

// ------------------------------------------------------------------ [feed_risk], declared once

// [feed_risk.simulation]: the simulation along the schedule (run unless disabled).
struct AlongPlanTable {
  bool enabled = true;
  double sample_rate_hz = 4000.0;
  double relative_tolerance = 1e-4;
  std::uint64_t seed = 1;
  double samples_per_wave = 8.0;
  bool random_initial_surfaces = false;
  double fit_window_revolutions = 10.0;
};

const ParamTable<AlongPlanTable>& along_plan_table() {
  static const ParamTable<AlongPlanTable> table = [] {
    ParamTable<AlongPlanTable> t;
    t.add(&AlongPlanTable::enabled, "enabled", "1", "run the simulation along the plan");
    t.add(&AlongPlanTable::sample_rate_hz, "sample_rate_hz", "Hz", "output samples reduced per work revolution")
        .positive();
    t.add(&AlongPlanTable::relative_tolerance, "relative_tolerance", "1",
          "relative tolerance of the adaptive ARKODE route only (the along-plan simulation runs the fixed-step "
          "engine, which has none)").positive().at_most(1e-2);
    t.add(&AlongPlanTable::seed, "seed", "1", "seed of the random initial surfaces").at_least(0);
    t.add(&AlongPlanTable::samples_per_wave, "samples_per_wave", "1",
          "surface samples per wave at the model's highest frequency (the engine's default is 16; 8 halves "
          "the cost, growth rates change by ~0.1 %)").positive();
    t.add(&AlongPlanTable::random_initial_surfaces, "random_initial_surfaces", "1",
          "random initial wheel and work surfaces of +/- initial_waviness_um as well as the initial displacement "
          "(white noise up to the surface resolution: ~10x the steps)");
    t.add(&AlongPlanTable::fit_window_revolutions, "fit_window_revolutions", "1",
          "work revolutions in the rolling fit of the simulated growth rate").positive();
    return t;
  }();
  return table;
}

// [feed_risk.optimise]: the search for a chatter-aware spindle speed (only when present).
struct OptimiseTable {
  int speed_steps = 11;
  std::vector<double> modulation_amplitude_ratios{0.0};
  double modulation_frequency_hz = 0.5;
  int phase_samples = 8;
  double max_time_factor = 1.2;
  double condition_tolerance = 1e-2;
  double speed_tolerance = 0.005;
};

const ParamTable<OptimiseTable>& optimise_table() {
  static const ParamTable<OptimiseTable> table = [] {
    ParamTable<OptimiseTable> t;
    t.add(&OptimiseTable::speed_steps, "speed_steps", "1", "candidate spindle speeds per amplitude")
        .at_least(1).at_most(1000);
    t.add(&OptimiseTable::modulation_amplitude_ratios, "modulation_amplitude_ratios", "1",
          "sinusoidal spindle-speed modulation amplitudes a (rpm = n (1 + a sin 2 pi f t))").non_negative().min_items(1);
    t.add(&OptimiseTable::modulation_frequency_hz, "modulation_frequency_hz", "Hz", "modulation frequency f")
        .positive();
    t.add(&OptimiseTable::phase_samples, "phase_samples", "1",
          "frozen speeds per modulation cycle in the averaged growth rate (S2)").at_least(1).at_most(64);
    t.add(&OptimiseTable::max_time_factor, "max_time_factor", "1",
          "total time may grow to this multiple of the baseline plan's").at_least(1.0);
    t.add(&OptimiseTable::condition_tolerance, "condition_tolerance", "1",
          "relative tolerance grouping segments in the search").positive().at_most(0.1);
    t.add(&OptimiseTable::speed_tolerance, "speed_tolerance", "1",
          "spindle speed tolerance: candidates are rated by their worst case over n (1 +- tol) (a verdict at an "
          "exact wheel/work speed ratio does not survive it)").fraction().at_most(0.1);
    return t;
  }();
  return table;
}

struct FeedRiskSettings {
  std::optional<std::string> plan_dir;
  double reference_contact_width_mm = 0.0;  // required
  double reference_work_radius_mm = 0.0;    // required
  double depth_of_cut_mm = 0.0;             // required
  std::optional<double> wheel_speed_rpm;
  std::optional<double> contact_width_mm;
  bool speed_scaling = true;
  double initial_waviness_um = 1.0;
  double marginal_growth_rate_per_s = 0.1;
  double chatter_amplification = 10.0;
  double condition_tolerance = 1e-3;
  AlongPlanTable simulation;
  std::optional<OptimiseTable> optimise;
};

const ParamTable<FeedRiskSettings>& feed_risk_table() {
  static const ParamTable<FeedRiskSettings> table = [] {
    using S = FeedRiskSettings;
    ParamTable<S> t;
    t.add(&S::plan_dir, "plan_dir", "",
          "a saved feed_plan output directory (pulses.csv, summary.json), relative to the study file; default: "
          "plan from [machine], [part], [wheel], [plan]");
    t.add(&S::reference_contact_width_mm, "reference_contact_width_mm", "mm",
          "contact width at which the [model]'s own parameters hold").positive().required();
    t.add(&S::reference_work_radius_mm, "reference_work_radius_mm", "mm",
          "work radius at which the [model]'s own parameters hold (with its work and wheel speeds)")
        .positive().required();
    t.add(&S::depth_of_cut_mm, "depth_of_cut_mm", "mm",
          "radial stock removed by the pass (contact width and length)").positive().required();
    t.add(&S::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed along the plan (default: the [model]'s)")
        .positive();
    t.add(&S::contact_width_mm, "contact_width_mm", "mm", "fixed contact width instead of the geometric one")
        .positive();
    t.add(&S::speed_scaling, "speed_scaling", "1",
          "the stiffnesses follow the local work surface speed through Kv (G4: kw by Kv/(1+Kv), kg by 1/(1+Kv))");
    t.add(&S::initial_waviness_um, "initial_waviness_um", "um",
          "disturbance level: the predicted waviness starts here, the simulation's initial displacement "
          "(docs/feed_risk.md)").positive();
    t.add(&S::marginal_growth_rate_per_s, "marginal_growth_rate_per_s", "1/s",
          "risk class marginal: growth rate above minus this value").positive();
    t.add(&S::chatter_amplification, "chatter_amplification", "1",
          "risk class chatter: accumulated amplification at or above this").above(1.0);
    t.add(&S::condition_tolerance, "condition_tolerance", "1",
          "relative tolerance: segments whose model parameters agree within it share one root").positive().at_most(0.1);
    t.add_table(&S::simulation, "simulation", "[feed_risk.simulation]: the simulation along the schedule",
                along_plan_table());
    t.add_optional_table(&S::optimise, "optimise", "[feed_risk.optimise]: search for a chatter-aware spindle speed",
                         optimise_table());
    return t;
  }();
  return table;
}

fs::path study_dir(const SourceMap& sources, const std::string& key) {
  return fs::path(sources.locate(key).file).parent_path();
}

struct PlanSource {
  planner::PlanTables tables;
  std::vector<SegmentConditions> segments;
};

std::vector<SegmentConditions> plan_at(const PlanSource& src, double spindle_rpm) {
  return planner::plan_feed_at(src.tables, spindle_rpm).segments;
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

PlanSource plan_source(const Json& document, const FeedRiskSettings& fr) {
  PlanSource src;
  if (fr.plan_dir) {
    planner::SavedPlan saved = planner::read_saved_plan(*fr.plan_dir);
    src.tables.machine = saved.machine;
    src.tables.part = saved.part;
    src.tables.wheel = saved.wheel;
    // The saved [plan] table (planner settings) for re-planning; read_saved_plan checked the file.
    InputFileStream in(fs::path(*fr.plan_dir) / "summary.json");
    src.tables.plan = Json::parse(in).at("plan");
    src.segments = std::move(saved.segments);
    return src;
  }
  src.tables = {document.at("machine"), document.at("part"), document.at("wheel"), document.at("plan")};
  src.segments = plan_at(src, planner::spindle_range_rpm(src.tables.machine).second);
  return src;
}

ProcessSettings process_settings(const Json& document, const FeedRiskSettings& fr, const Json& wheel) {
  ProcessSettings p;
  p.model = kit::build_model(document.at("model"));
  p.reference_contact_width_mm = fr.reference_contact_width_mm;
  p.reference_work_radius_mm = fr.reference_work_radius_mm;
  p.wheel_speed_rpm = fr.wheel_speed_rpm ? *fr.wheel_speed_rpm : process_model(p).nominal_conditions().wheel_speed_rpm;
  p.wheel_diameter_mm = wheel.at("diameter_mm").get<double>();
  p.profiled_wheel = wheel.at("type").get<std::string>() == "profiled";
  p.wheel_thickness_mm = wheel.at("thickness_mm").get<double>();
  if (wheel.contains("edge_radius_mm") && wheel["edge_radius_mm"].is_number())
    p.edge_radius_mm = wheel["edge_radius_mm"].get<double>();
  p.edge_angle_deg = wheel.value("edge_angle_deg", 180.0);
  p.depth_of_cut_mm = fr.depth_of_cut_mm;
  p.contact_width_mm = fr.contact_width_mm;
  p.speed_scaling = fr.speed_scaling;
  return p;
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
  // A margin beyond the marginal threshold, so the change lands clearly in the stable class.
  const double target = -1.5 * thresholds.marginal_growth_rate_per_s;
  Json rows = Json::array();
  for (const Lever& l : stability_levers(model, p, risk.process[worst], roots, target, speed_tolerance))
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
  return text + ".";
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

// A process stiffness of the segment's model parameters, for the table (NaN when the model has
// no such parameter: the plunge models of G1 have all three).
double stiffness_of(const Json& segment_model, const char* key) {
  const auto it = segment_model.find(key);
  return it != segment_model.end() && it->is_number() ? it->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

void write_segments(const fs::path& path, const Json& model, const ProcessSettings& p,
                    const std::vector<SegmentConditions>& plan, const PlanRisk& risk,
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
    const Json t = segment_model_table(model, p, s);
    const double row[] = {static_cast<double>(k), plan[k].start_s, plan[k].duration_s, plan[k].x_start_mm,
                          plan[k].x_end_mm, plan[k].radius_mm, plan[k].axial_speed_mm_per_s, s.work_speed_rpm,
                          s.work_surface_speed_m_per_s, s.speed_ratio, s.equivalent_diameter_mm,
                          s.contact_length_mm, s.contact_width_mm, s.axial_feed_per_rev_mm, s.overlap_ratio,
                          stiffness_of(t, "contact_stiffness_n_per_m"), stiffness_of(t, "wheel_wear_stiffness_n_per_m"),
                          stiffness_of(t, "work_removal_stiffness_n_per_m"), r.growth_rate_per_s, r.chatter_frequency_hz,
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

// The point's figures, rendered together: one gnuplot process per figure, two at a time on two
// threads (plot::render is safe to call concurrently for different stems); a figure that fails is
// named in the failures, in the order the figures were added.
struct Figures {
  std::vector<std::pair<std::string, plot::Curves>> figures;

  void add(const std::string& stem, plot::Curves figure) { figures.emplace_back(stem, std::move(figure)); }

  void render(const fs::path& dir, Json& failures) const {
    std::vector<std::string> errors(figures.size());
    const auto n = static_cast<long>(figures.size());
#pragma omp parallel for schedule(dynamic)
    for (long i = 0; i < n; ++i) {
      const auto& [stem, figure] = figures[static_cast<std::size_t>(i)];
      try {
        plot::render(figure, dir, stem);
      } catch (const std::exception& e) {
        errors[static_cast<std::size_t>(i)] = fmt::format("{}: {}", stem, e.what());
      }
    }
    for (const std::string& error : errors)
      if (!error.empty()) failures.push_back(error);
  }
};

void add_plots(const Json& document, const std::vector<SegmentConditions>& plan, const PlanRisk& risk,
               const AlongPlanSimulation* sim, const Waviness& predicted_um, Figures& figures) {
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
  figures.add("growth_along_x", std::move(growth));

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
  figures.add("waviness_along_x", std::move(waviness));

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
  figures.add("amplification_over_time", std::move(amplification));
}

// ------------------------------------------------------------------ validation steps

// [model]: any model whose parameters follow the process conditions and that has roots; a
// time-domain form too when the simulation along the plan is on.
Json validate_feed_risk_model(const Json& document, bool simulate, const SourceMap& sources) {
  Json model = validate_component(document, "model", model_registry(), sources);
  auto built = kit::build_model(model);
  if (!built->process_conditions() || !built->characteristic())
    throw InputError(fmt::format(
        "{}: model.type = \"{}\": feed_risk needs a model whose parameters follow the process conditions "
        "(the ProcessConditionsModel capability: plunge_regenerative, plunge_with_penetration_damping) "
        "and a characteristic function", sources.locate("model.type").str(), model["type"].get<std::string>()));
  if (simulate && !built->time_domain())
    throw InputError(fmt::format(
        "{}: model.type = \"{}\": the model has no time-domain form, so feed_risk cannot simulate along the "
        "plan: set [feed_risk.simulation] enabled = false (the roots need none)",
        sources.locate("model.type").str(), model["type"].get<std::string>()));
  return model;
}

// Feed-plan tables next to plan_dir must describe the same machine, wheel and part.
void check_tables_match_saved_plan(const Json& document, const planner::SavedPlan& saved, const fs::path& dir,
                                   const SourceMap& sources) {
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
}

// A saved plan (plan_dir made absolute in `fr`): its machine and wheel.
std::pair<Json, Json> validate_saved_plan(const Json& document, FeedRiskSettings& fr, const SourceMap& sources) {
  fs::path dir = *fr.plan_dir;
  if (dir.is_relative()) dir = fs::absolute(study_dir(sources, "feed_risk.plan_dir") / dir);
  fr.plan_dir = dir.string();
  const std::string where = sources.locate("feed_risk.plan_dir").str();
  planner::SavedPlan saved;
  try {
    saved = planner::read_saved_plan(dir);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: feed_risk.plan_dir = \"{}\": {}", where, dir.string(), e.what()));
  }
  if (saved.segments.empty())
    throw InputError(fmt::format("{}: feed_risk.plan_dir = \"{}\": the saved plan has no segments", where,
                                 dir.string()));
  check_tables_match_saved_plan(document, saved, dir, sources);
  const auto [from, to] = planner::spindle_range_rpm(saved.machine);
  const double rpm = saved.plan.spindle_speed_rpm;
  if (rpm < from * (1 - 1e-12) || rpm > to * (1 + 1e-12))
    throw InputError(fmt::format("{}: feed_risk.plan_dir = \"{}\": spindle range violated: the plan runs the "
                                 "spindle at {} rpm, outside the machine's range [{}, {}] rpm",
                                 where, dir.string(), rpm, from, to));
  return {saved.machine, saved.wheel};
}

// The plan made in the study from the feed_plan tables: its machine and wheel.
std::pair<Json, Json> validate_planned(Json& document, const SourceMap& sources) {
  for (const char* table : {"machine", "part", "wheel"})
    if (!document.contains(table))
      throw InputError(fmt::format("{}: missing table [{}]: feed_risk plans from [machine], [part], [wheel] "
                                   "(and [plan]) unless feed_risk.plan_dir names a saved plan",
                                   sources.locate("study").str(), table));
  planner::validate_feed_plan_tables(document, sources);
  return {document["machine"], document["wheel"]};
}

// Every modulation amplitude must leave a mean speed whose extremes stay in the spindle range.
void check_modulation_range(const OptimiseTable& optimise, const Json& machine, const SourceMap& sources) {
  const auto [from, to] = planner::spindle_range_rpm(machine);
  const std::string key = "feed_risk.optimise.modulation_amplitude_ratios";
  const std::string list = Json(optimise.modulation_amplitude_ratios).dump();
  for (const double ratio : optimise.modulation_amplitude_ratios) {
    if (!(ratio < 1.0))
      throw InputError(fmt::format("{}: {} = {}: an amplitude ratio {} would stop or reverse the spindle (must be < 1)",
                                   sources.locate(key).str(), key, list, ratio));
    if (from / (1.0 - ratio) > to / (1.0 + ratio) * (1 + 1e-12))
      throw InputError(fmt::format(
          "{}: {} = {}: spindle range violated: with amplitude ratio {} no mean speed keeps n (1 - a) >= {} rpm "
          "and n (1 + a) <= {} rpm", sources.locate(key).str(), key, list, ratio, from, to));
  }
}

// ------------------------------------------------------------------ one point, step by step

// What every step of a point needs: the settings, the plan, the process model and the rating.
struct PointSetup {
  FeedRiskSettings fr;
  PlanSource src;
  ProcessSettings p;
  std::unique_ptr<planner::Generatrix> generatrix;
  RiskThresholds thresholds;
  RootSettings roots;
  Waviness predicted_um{1.0, 1.0};
  Json model;
  AlongPlanSettings simulation;
};

PointSetup point_setup(const Json& document) {
  PointSetup in;
  in.fr = kit::read_settings(document, "feed_risk", feed_risk_table());
  in.src = plan_source(document, in.fr);
  in.p = process_settings(document, in.fr, in.src.tables.wheel);
  in.generatrix = planner::build_generatrix(in.src.tables.part);
  in.thresholds = {in.fr.marginal_growth_rate_per_s, in.fr.chatter_amplification};
  in.roots = {document.at("stability"), in.fr.condition_tolerance};
  in.predicted_um = {in.fr.initial_waviness_um, 1e3 * in.p.depth_of_cut_mm};
  in.model = document.at("model");
  const AlongPlanTable& t = in.fr.simulation;
  AlongPlanSettings& s = in.simulation;
  s.sample_rate_hz = t.sample_rate_hz;
  s.relative_tolerance = t.relative_tolerance;
  s.initial_waviness_m = 1e-6 * in.fr.initial_waviness_um;
  s.divergence_limit_m = 1e-3 * in.p.depth_of_cut_mm;
  s.seed = t.seed;
  s.samples_per_wave = t.samples_per_wave;
  s.random_initial_surfaces = t.random_initial_surfaces;
  s.fit_window_revolutions = t.fit_window_revolutions;
  return in;
}

// The plan as given: its roots and (unless disabled) its simulation.
struct Rated {
  PlanRisk risk;
  bool simulated = false;
  AlongPlanSimulation sim;
};

Rated rate_baseline(const PointSetup& in) {
  Rated r;
  r.risk = evaluate_roots(in.model, in.p, in.src.segments, *in.generatrix, in.roots, in.thresholds);
  r.simulated = in.fr.simulation.enabled;
  if (r.simulated) r.sim = simulate_along_plan(in.model, in.p, in.src.segments, r.risk, in.simulation);
  return r;
}

Json baseline_summary(const PointSetup& in, const Rated& base) {
  const PlanRisk& risk = base.risk;
  Json summary = {
      {"total_time_s", plan_time(in.src.segments)},
      {"segments", in.src.segments.size()},
      {"condition_groups", risk.groups},
      {"spindle_speed_rpm", in.src.segments.front().spindle_speed_rpm},
      {"wheel_speed_rpm", in.p.wheel_speed_rpm},
      {"max_growth_rate_per_s", risk.max_growth_rate_per_s},
      {"final_log_amplification", risk.final_log_amplification},
      {"max_log_amplification", risk.max_floored_log_amplification},
      {"max_predicted_waviness_um", in.predicted_um(risk.max_floored_log_amplification)},
      {"worst_risk", to_string(risk.worst)},
      {"time_in_risk_s", {{"stable", risk.time_in_risk_s[0]}, {"marginal", risk.time_in_risk_s[1]},
                          {"chatter", risk.time_in_risk_s[2]}}},
      {"thresholds", {{"marginal_growth_rate_per_s", in.thresholds.marginal_growth_rate_per_s},
                      {"chatter_amplification", in.thresholds.chatter_amplification}}},
  };
  const AlongPlanSimulation& sim = base.sim;
  if (base.simulated)
    summary["simulation"] = {{"outcome", simulation_outcome(sim)}, {"engine_status", sim.status},
                             {"failed", sim.failed}, {"diverged", sim.diverged},
                             {"end_time_s", sim.end_time_s}, {"steps", sim.steps},
                             {"wall_s", sim.wall_s}, {"revolutions", sim.revolutions.size()},
                             {"max_work_waviness_um", max_waviness_um(sim)}};
  return summary;
}

// The chatter-aware re-plan ([feed_risk.optimise]).
struct Replanned {
  OptimiseSettings settings;
  OptimiseResult result;
  Rated best;                // the chosen plan, rated at full resolution (and simulated when stable)
  bool stable = false;       // stable over the speed band: the plan is written
  std::string notice;
  Json summary;
  const Candidate& chosen() const { return result.candidates[result.best]; }
};

OptimiseSettings optimise_settings(const PointSetup& in) {
  const OptimiseTable& o = *in.fr.optimise;
  OptimiseSettings os;
  std::tie(os.spindle_min_rpm, os.spindle_max_rpm) = planner::spindle_range_rpm(in.src.tables.machine);
  os.speed_steps = o.speed_steps;
  os.amplitude_ratios = o.modulation_amplitude_ratios;
  os.modulation_frequency_hz = o.modulation_frequency_hz;
  os.phase_samples = o.phase_samples;
  os.max_time_factor = o.max_time_factor;
  os.condition_tolerance = o.condition_tolerance;
  os.speed_tolerance = o.speed_tolerance;
  return os;
}

Json candidate_rows(const OptimiseResult& result) {
  Json rows = Json::array();
  for (const Candidate& k : result.candidates)
    rows.push_back({{"spindle_speed_rpm", k.spindle_speed_rpm}, {"amplitude_ratio", k.amplitude_ratio},
                    {"total_time_s", k.total_time_s}, {"time_factor", k.time_factor},
                    {"max_growth_rate_per_s", k.max_growth_rate_per_s},
                    {"nominal_max_growth_rate_per_s", k.nominal_max_growth_rate_per_s},
                    {"exact_speed_ratio", k.exact_speed_ratio},
                    {"max_log_amplification", k.max_floored_log_amplification},
                    {"worst_risk", to_string(k.worst)}, {"admissible", k.admissible}});
  return rows;
}

Json replan_summary(const PointSetup& in, Replanned& re) {
  const Candidate& c = re.chosen();
  const OptimiseSettings& os = re.settings;
  const PlanRisk& best_risk = re.best.risk;
  Json optimised = {{"spindle_speed_rpm", c.spindle_speed_rpm},
                    {"modulation_amplitude_ratio", c.amplitude_ratio},
                    {"modulation_frequency_hz", c.amplitude_ratio > 0 ? os.modulation_frequency_hz : 0.0},
                    {"planning_speed_rpm", c.planning_speed_rpm},
                    {"total_time_s", c.total_time_s},
                    {"time_factor", c.time_factor},
                    {"max_time_factor", os.max_time_factor},
                    {"search_max_log_amplification", c.max_floored_log_amplification},
                    {"max_growth_rate_per_s", best_risk.max_growth_rate_per_s},
                    {"max_log_amplification", best_risk.max_floored_log_amplification},
                    {"max_predicted_waviness_um", in.predicted_um(best_risk.max_floored_log_amplification)},
                    {"worst_risk", to_string(best_risk.worst)},
                    {"speed_tolerance", os.speed_tolerance},
                    {"nominal_max_growth_rate_per_s", c.nominal_max_growth_rate_per_s},
                    {"exact_speed_ratio", c.exact_speed_ratio},
                    {"stable_over_speed_band", re.stable},
                    {"candidates", candidate_rows(re.result)}};
  if (re.result.stable_window_rpm)
    optimised["stable_window_rpm"] = {{"from", re.result.stable_window_rpm->first},
                                      {"to", re.result.stable_window_rpm->second},
                                      {"candidate_spacing_rpm", re.result.speed_spacing_rpm}};
  optimised["verdict"] = re.stable ? "stable" : "no stable candidate";
  optimised["plan_written"] = re.stable;
  if (!re.stable) {
    re.notice = no_stable_candidate_notice(re.result, os, best_risk, in.thresholds);
    optimised["levers"] = levers_at_worst_segment(in.model, in.p, best_risk, in.roots, in.thresholds, os.speed_tolerance);
    re.notice += levers_text(optimised["levers"]);
    optimised["notice"] = re.notice;
  }
  if (re.best.simulated)
    optimised["simulation"] = {{"outcome", simulation_outcome(re.best.sim)}, {"engine_status", re.best.sim.status},
                               {"failed", re.best.sim.failed}, {"diverged", re.best.sim.diverged},
                               {"max_work_waviness_um", max_waviness_um(re.best.sim)}};
  return optimised;
}

Replanned replan(const PointSetup& in) {
  Replanned re;
  re.settings = optimise_settings(in);
  const OptimiseSettings& os = re.settings;
  re.result = optimise(in.model, in.p, [&](double rpm) { return plan_at(in.src, rpm); }, plan_time(in.src.segments),
                       *in.generatrix, in.roots, in.thresholds, os);
  const Candidate& c = re.chosen();
  // The chosen plan rated at full resolution (roots at the mean speed; the modulation's frozen-
  // speed average is the candidate's own rating) and simulated with the exact modulated spindle.
  re.best.risk = evaluate_roots(in.model, in.p, re.result.best_plan, *in.generatrix, in.roots, in.thresholds,
                                os.speed_tolerance);
  re.stable = re.result.stable && re.best.risk.worst == Risk::stable;
  re.best.simulated = in.fr.simulation.enabled && re.stable;
  if (re.best.simulated) {
    AlongPlanSettings s = in.simulation;
    if (c.amplitude_ratio > 0)
      s.work_speed = make_modulated_speed(c.spindle_speed_rpm, SpeedModulation::sinusoidal, c.amplitude_ratio,
                                          os.modulation_frequency_hz);
    re.best.sim = simulate_along_plan(in.model, in.p, re.result.best_plan, re.best.risk, s);
  }
  re.summary = replan_summary(in, re);
  return re;
}

// ------------------------------------------------------------------ the point's files

void write_optimisation_table(const fs::path& path, const std::vector<Candidate>& cands) {
  std::vector<std::vector<double>> c(7, std::vector<double>(cands.size()));
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const double row[] = {cands[i].spindle_speed_rpm, cands[i].amplitude_ratio, cands[i].total_time_s,
                          cands[i].time_factor, cands[i].max_growth_rate_per_s,
                          cands[i].max_floored_log_amplification, cands[i].admissible ? 1.0 : 0.0};
    for (std::size_t j = 0; j < 7; ++j) c[j][i] = row[j];
  }
  write_file_atomically(path, csv_text({"spindle_speed_rpm", "amplitude_ratio", "total_time_s", "time_factor",
                                        "max_growth_rate_per_s", "max_log_amplification", "admissible"},
                                       c));
}

plot::Curves optimisation_figure(const Json& document, const Replanned& re) {
  const auto& cands = re.result.candidates;
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
  const Candidate& chosen = re.chosen();
  search.series.push_back({re.stable ? "chosen" : "least risk: no candidate is stable", {chosen.spindle_speed_rpm},
                           {chosen.max_floored_log_amplification}, "points"});
  return search;
}

plot::Series predicted_series(const std::string& label, const std::vector<SegmentConditions>& plan, const PlanRisk& r,
                              const Waviness& predicted_um) {
  plot::Series s{label, {plan.front().x_start_mm}, {predicted_um(0.0)}, "lines"};
  for (std::size_t k = 0; k < plan.size(); ++k) {
    s.x.push_back(plan[k].x_end_mm);
    s.y.push_back(predicted_um(r.segments[k].floored_log_amplification));
  }
  return s;
}

plot::Series simulated_series(const std::string& label, const AlongPlanSimulation& run) {
  plot::Series s{label, {}, {}, "lines"};
  for (const RevolutionRow& r : run.revolutions)
    if (r.work_waviness_m > 0) {
      s.x.push_back(r.x_mm);
      s.y.push_back(1e6 * r.work_waviness_m);
    }
  return s;
}

plot::Curves before_after_figure(const Json& document, const PointSetup& in, const Rated& base, const Replanned& re) {
  const Candidate& chosen = re.chosen();
  plot::Curves compare;
  compare.title = fmt::format("{}: predicted waviness before / after", title_of(document));
  compare.x_label = "axial contact position x [mm]";
  compare.y_label = "waviness amplitude [um]";
  compare.log_y = true;
  compare.series.push_back(predicted_series(fmt::format("before: {:.0f} rpm, {:.0f} s",
                                                        in.src.segments.front().spindle_speed_rpm,
                                                        plan_time(in.src.segments)),
                                            in.src.segments, base.risk, in.predicted_um));
  compare.series.push_back(predicted_series(fmt::format("{}: {:.1f} rpm, a = {}, {:.0f} s",
                                                        re.stable ? "after" : "least risk (NOT stable)",
                                                        chosen.spindle_speed_rpm, chosen.amplitude_ratio,
                                                        chosen.total_time_s),
                                            re.result.best_plan, re.best.risk, in.predicted_um));
  if (base.simulated) {
    compare.series.push_back(simulated_series("before, simulated", base.sim));
    if (re.stable) compare.series.push_back(simulated_series("after, simulated", re.best.sim));
  }
  return compare;
}

void write_replan_files(const Json& document, const PointContext& context, const PointSetup& in, const Rated& base,
                        const Replanned& re, Figures& figures) {
  const fs::path& dir = context.artifact_dir;
  if (re.stable) {
    // Re-planned once more at the chosen planning speed (deterministic: the same plan).
    write_pulses(dir / "optimised_pulses.csv", planner::plan_feed_at(in.src.tables, re.chosen().planning_speed_rpm).plan);
    write_segments(dir / "optimised_segments.csv", in.model, in.p, re.result.best_plan, re.best.risk, in.predicted_um);
  }
  write_optimisation_table(dir / "optimisation.csv", re.result.candidates);
  if (!context.plots) return;
  figures.add("optimisation", optimisation_figure(document, re));
  figures.add("before_after", before_after_figure(document, in, base, re));
}

void write_point_files(const Json& document, const PointContext& context, const PointSetup& in, const Rated& base,
                       const Replanned* re, Json& summary) {
  const fs::path& dir = context.artifact_dir;
  write_segments(dir / "segments.csv", in.model, in.p, in.src.segments, base.risk, in.predicted_um);
  if (base.simulated) write_along_x(dir / "along_x.csv", in.src.segments, base.risk, base.sim, in.predicted_um);
  Figures figures;
  if (context.plots)
    add_plots(document, in.src.segments, base.risk, base.simulated ? &base.sim : nullptr, in.predicted_um, figures);
  if (re) write_replan_files(document, context, in, base, *re, figures);
  Json failures = Json::array();
  figures.render(dir, failures);
  summary["plot_errors"] = failures;
  kit::write_summary(context, summary);
}

// The results.csv row; the optimised columns describe a plan only when one was written.
std::vector<Json> result_row(const PointSetup& in, const Rated& base, const Replanned* re, const Json& summary) {
  const PlanRisk& risk = base.risk;
  auto optional_number = [&](const char* key) {
    return re && re->stable && re->summary.contains(key) ? re->summary[key] : Json();
  };
  return {summary["total_time_s"],
          summary["segments"],
          summary["condition_groups"],
          number_or_null(risk.max_growth_rate_per_s),
          number_or_null(risk.final_log_amplification),
          number_or_null(risk.max_floored_log_amplification),
          number_or_null(in.predicted_um(risk.max_floored_log_amplification)),
          to_string(risk.worst),
          risk.time_in_risk_s[2],
          base.simulated && !base.sim.revolutions.empty() ? Json(max_waviness_um(base.sim)) : Json(),
          base.simulated ? Json(simulation_outcome(base.sim)) : Json("off"),
          optional_number("spindle_speed_rpm"),
          optional_number("modulation_amplitude_ratio"),
          optional_number("total_time_s"),
          optional_number("max_predicted_waviness_um"),
          re && re->best.simulated ? Json(max_waviness_um(re->best.sim)) : Json(),
          re ? Json(re->stable ? "stable" : "no stable candidate") : Json(),
          re ? re->notice : std::string()};
}

}  // namespace

PluginInfo FeedRiskKind::info() {
  return plugin_info("feed_risk", "P, G1, G3, G4, S2",
                     feed_risk_table().specs(),
                     {{"reference_contact_width_mm", 35.0}, {"reference_work_radius_mm", 50.0},
                      {"depth_of_cut_mm", 0.01}},
                     "chatter risk along a feed plan: rightmost root per segment, accumulated amplification, risk "
                     "class, simulation along the schedule, chatter-aware spindle speed");
}

void FeedRiskKind::validate(Json& document, const SourceMap& sources) const {
  if (!document.contains("feed_risk") || !document["feed_risk"].is_object())
    throw InputError(fmt::format("{}: missing table [feed_risk] (the feed_risk study needs it)",
                                 sources.locate("study").str()));
  // Also [feed_risk.simulation] (defaults filled in) and [feed_risk.optimise] (null if absent).
  FeedRiskSettings fr = kit::validate_settings(document, "feed_risk", feed_risk_table(), sources);
  Json model = validate_feed_risk_model(document, fr.simulation.enabled, sources);
  kit::validate_settings(document, "stability", kit::stability_settings_table(), sources);
  // The plan: saved, or planned here from the feed_plan tables.
  const auto [machine, wheel] = fr.plan_dir ? validate_saved_plan(document, fr, sources)
                                            : validate_planned(document, sources);
  if (fr.optimise) check_modulation_range(*fr.optimise, machine, sources);
  if (!wheel.contains("diameter_mm"))
    throw InputError(fmt::format("{}: the wheel has no diameter_mm", sources.locate("wheel").str()));
  document["model"] = std::move(model);
  document["feed_risk"]["plan_dir"] = fr.plan_dir ? Json(*fr.plan_dir) : Json();
}

std::vector<std::string> FeedRiskKind::output_columns(const Json& /*document*/) const {
  return {std::begin(columns), std::end(columns)};
}

std::vector<Json> FeedRiskKind::run_point(const Json& document, const PointContext& context) const {
  const PointSetup in = point_setup(document);
  const Rated base = rate_baseline(in);
  Json summary = baseline_summary(in, base);
  std::optional<Replanned> re;
  if (in.fr.optimise) {
    re = replan(in);
    summary["optimised"] = re->summary;
  }
  if (!context.artifact_dir.empty()) write_point_files(document, context, in, base, re ? &*re : nullptr, summary);
  return result_row(in, base, re ? &*re : nullptr, summary);
}

}  // namespace chatterlab::feed_risk

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::feed_risk::FeedRiskKind);
