#include "study_kinds/stability_lobes/stability_lobes.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/modal_fit.hpp"
#include "chatterlab/plugin_info.hpp"
#include "study_kinds/stability_lobes/lobe_results.hpp"

namespace chatterlab {

using namespace lobes;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// ---------------------------------------------------------------- validation

[[noreturn]] void refuse(const SourceMap& sources, const std::string& path, const std::string& what) {
  throw InputError(fmt::format("{}: {}", sources.locate(path).str(), what));
}

// The limited parameter and the speed name numeric keys of [model], and differ.
void check_keys(const Json& document, const LobesSettings& s, const SourceMap& sources) {
  const Json& model = document.at("model");
  std::vector<std::string> numeric;
  for (const auto& [key, value] : model.items())
    if (value.is_number()) numeric.push_back(key);
  for (const auto& [name, key] : {std::pair{"parameter", s.parameter}, std::pair{"speed", s.speed}}) {
    const std::string path = model_path(key);
    const Json::json_pointer pointer = pointer_of(path);
    if (!model.contains(pointer) || !model.at(pointer).is_number())
      refuse(sources, fmt::format("lobes.{}", name),
             fmt::format("lobes.{} = \"{}\": [model] ({}) has no number at '{}'; its numeric keys: {}", name, key,
                         model.at("type").get<std::string>(), path, fmt::join(numeric, ", ")));
  }
  if (model_path(s.parameter) == model_path(s.speed))
    refuse(sources, "lobes.speed", fmt::format("lobes.speed = \"{}\" is also the limited parameter", s.speed));
}

void check_ranges(const LobesSettings& s, const SourceMap& sources) {
  if (s.parameter_range.size() != 2 || !(s.parameter_range[0] < s.parameter_range[1]))
    refuse(sources, "lobes.parameter_range",
           fmt::format("lobes.parameter_range = [{}]: needs two values, low < high", fmt::join(s.parameter_range, ", ")));
  if (s.speed_values.has_value() == s.speed_range.has_value())
    refuse(sources, "lobes", "[lobes] needs exactly one of speed_values and speed_range");
  if (s.speed_range && !(s.speed_range->from < s.speed_range->to))
    refuse(sources, "lobes.speed_range",
           fmt::format("lobes.speed_range: from = {} must be below to = {}", s.speed_range->from, s.speed_range->to));
  if (speeds_of(s).size() < 2) refuse(sources, "lobes.speed_values", "lobes.speed_values: needs two distinct speeds");
}

Route check_route(const LobesSettings& s, const Model& model, const SourceMap& sources) {
  const Route route = route_of(s, model);
  if (route == Route::roots && !model.characteristic())
    refuse(sources, "lobes.route", "lobes.route = \"roots\": the model has no characteristic function (try \"nyquist\")");
  if (route == Route::nyquist && !model.return_difference())
    refuse(sources, "lobes.route",
           s.route == RouteChoice::nyquist
               ? "lobes.route = \"nyquist\": the model has no return difference (try \"roots\")"
               : "[model] has no stability route: neither a characteristic function nor a return difference");
  return route;
}

double natural_scale_hz(const Model& model, Route route) {
  if (route == Route::roots) return model.characteristic()->natural_frequency_scale_hz();
  return model.return_difference()->natural_frequency_scale_hz();
}

double band_of(const Json& document, const Model& model, Route route) {
  const kit::StabilitySettings st = kit::read_settings(document, "stability", kit::stability_settings_table());
  return st.max_frequency_hz ? *st.max_frequency_hz : kit::default_band_multiple * natural_scale_hz(model, route);
}

// The model must accept the parameter and speed at the ends of their ranges: its declared limits
// and its construction.
void check_extremes(const Json& document, const LobesSettings& s, const SourceMap& sources) {
  const VariedModel varied(document.at("model"), model_path(s.parameter), model_path(s.speed));
  const std::vector<double> speeds = speeds_of(s);
  const PluginInfo& info = model_registry().at(document.at("model").at("type").get<std::string>()).info;
  struct NoLines final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  } no_lines;
  for (double p : s.parameter_range)
    for (double v : {speeds.front(), speeds.back()}) {
      try {
        Json table = document.at("model");
        table[pointer_of(model_path(s.parameter))] = p;
        table[pointer_of(model_path(s.speed))] = v;
        table.erase("type");
        validate_params(table, info.params, "model", no_lines);
        varied.at(p, v);
      } catch (const std::exception& e) {
        std::string why = e.what();
        const std::string unlocated = SourceLocation{}.str() + ": ";  // validate_params' prefix without lines
        if (why.rfind(unlocated, 0) == 0) why.erase(0, unlocated.size());
        refuse(sources, "lobes", fmt::format("[lobes]: the model at {} = {:g}, {} = {:g} cannot be built: {}", s.parameter,
                                             p, s.speed, v, why));
      }
    }
}

// ---------------------------------------------------------------- one point

LobeStudy read_study(const Json& document) {
  const LobesSettings s = kit::read_settings(document, "lobes", lobes_settings_table());
  LobeStudy study(s, VariedModel(document.at("model"), model_path(s.parameter), model_path(s.speed)));
  if (document.contains("time_to_chatter"))
    study.time_to_chatter = kit::read_settings(document, "time_to_chatter", time_to_chatter_table());
  const auto model = kit::build_model(document.at("model"));
  study.route = route_of(s, *model);
  study.band_hz = band_of(document, *model, study.route);
  study.speeds = speeds_of(s);
  study.window_value = s.window_value ? *s.window_value : study.model.value(model_path(s.parameter));
  study.operating_speed = study.model.value(model_path(s.speed));
  study.title = kit::study_title(document, "stability_lobes");
  return study;
}

// Elasticities of the limit at every speed: (q/p) dp/dq for every other real model parameter q.
void add_sensitivities(const LobeStudy& study, LobeResults& r) {
  r.sensitivity_keys = study.model.other_real_keys();
  const ModelAt model_at = study.model.model_at();
  r.elasticities.assign(study.speeds.size(), std::vector<double>(r.sensitivity_keys.size(), NAN));
  for_each_index(study.speeds.size(), [&](std::size_t i) {
    const auto& limit = r.diagram.at[i].limit;
    if (!limit) return;
    try {
      const BoundaryDerivatives d = boundary_derivatives(model_at, *limit, study.route);
      const Complex g0 = axis_value(*model_at(limit->parameter, limit->speed), limit->omega_rad_s, study.route);
      for (std::size_t k = 0; k < r.sensitivity_keys.size(); ++k) {
        const double q = study.model.value(r.sensitivity_keys[k]), dq = 1e-6 * q;
        const auto m = study.model.at(limit->parameter, limit->speed, r.sensitivity_keys[k], q + dq);
        const Complex g_q = (axis_value(*m, limit->omega_rad_s, study.route) - g0) / dq;
        r.elasticities[i][k] = parameter_derivative(d, g_q) * q / limit->parameter;
      }
    } catch (const std::exception&) {
      // a model that cannot be built with a changed key: that speed's row stays empty
    }
  });
}

LobeResults compute(const LobeStudy& study) {
  LobeResults r;
  TraceSettings t;
  t.parameter_min = study.settings.parameter_range[0];
  t.parameter_max = study.settings.parameter_range[1];
  t.max_frequency_hz = study.band_hz;
  t.route = study.route;
  r.diagram = trace_lobes(study.model.model_at(), study.speeds, t);
  if (std::none_of(r.diagram.at.begin(), r.diagram.at.end(), [](const SpeedResult& s) { return s.limit.has_value(); }) &&
      std::none_of(r.diagram.at.begin(), r.diagram.at.end(), [](const SpeedResult& s) {
        return s.note.rfind("no crossing", 0) == 0 || s.note.rfind("unstable", 0) == 0;
      }))
    throw PointFailure("no speed could be computed: " + r.diagram.at.front().note);
  r.windows = chatter_free_windows(r.diagram, study.window_value);
  if (study.settings.sensitivities) add_sensitivities(study, r);
  if (const auto& ttc = study.time_to_chatter) {
    const std::vector<double>& range = ttc->parameter_range ? *ttc->parameter_range : study.settings.parameter_range;
    r.growth = growth_map(study.model, spread(study.speeds.front(), study.speeds.back(), ttc->speed_steps),
                          spread(range[0], range[1], ttc->parameter_steps), study.band_hz);
  }
  return r;
}

// ---------------------------------------------------------------- files

void write_tables(const LobeStudy& study, const LobeResults& r, const PointContext& context) {
  const std::string& speed = study.settings.speed;
  std::vector<std::vector<double>> lobes(4), limit(2);
  for (const Lobe& lobe : r.diagram.lobes)
    for (const Crossing& c : lobe.points) {
      lobes[0].push_back(c.speed);
      lobes[1].push_back(c.parameter);
      lobes[2].push_back(c.omega_rad_s / kTwoPi);
      lobes[3].push_back(lobe.id);
    }
  kit::write_table(context, "lobes.csv", {speed, "critical_value", "chatter_frequency_hz", "lobe"}, lobes);
  for (std::size_t i = 0; i < study.speeds.size(); ++i) {
    limit[0].push_back(study.speeds[i]);
    limit[1].push_back(r.diagram.at[i].limit ? r.diagram.at[i].limit->parameter : NAN);
  }
  kit::write_table(context, "limit.csv", {speed, "critical_value"}, limit);
  if (!r.sensitivity_keys.empty()) {
    std::vector<std::string> header{speed, "critical_value", "chatter_frequency_hz"};
    for (const std::string& key : r.sensitivity_keys) header.push_back("elasticity " + key);
    std::vector<std::vector<double>> columns(header.size());
    for (std::size_t i = 0; i < study.speeds.size(); ++i) {
      const auto& c = r.diagram.at[i].limit;
      if (!c) continue;
      columns[0].push_back(c->speed);
      columns[1].push_back(c->parameter);
      columns[2].push_back(c->omega_rad_s / kTwoPi);
      for (std::size_t k = 0; k < r.sensitivity_keys.size(); ++k) columns[3 + k].push_back(r.elasticities[i][k]);
    }
    kit::write_table(context, "sensitivity.csv", header, columns);
  }
  if (const auto& g = r.growth) {
    const TimeToChatterSettings& s = *study.time_to_chatter;
    std::vector<std::vector<double>> columns(7);
    for (std::size_t k = 0; k < g->growth_rate_per_s.size(); ++k) {
      const double t = time_to_chatter_s(g->growth_rate_per_s[k], s);
      const double finite_t = std::isnan(g->growth_rate_per_s[k]) ? NAN : t;
      columns[0].push_back(g->speeds[k % g->speeds.size()]);
      columns[1].push_back(g->parameters[k / g->speeds.size()]);
      columns[2].push_back(g->growth_rate_per_s[k]);
      columns[3].push_back(g->chatter_frequency_hz[k]);
      columns[4].push_back(finite_t);
      columns[5].push_back(std::isfinite(finite_t) ? static_cast<double>(parts_before_chatter(t, s)) : NAN);
      columns[6].push_back(std::isnan(finite_t) ? NAN : dressed_in_time(t, s) ? 1.0 : 0.0);
    }
    kit::write_table(context, "time_to_chatter.csv",
                     {speed, study.settings.parameter, "growth_rate_per_s", "chatter_frequency_hz", "time_to_chatter_s",
                      "parts_before_chatter", "dressed_in_time"},
                     columns);
  }
}

Json speed_json(const Crossing& c) {
  return {{"speed", c.speed}, {"critical_value", c.parameter}, {"chatter_frequency_hz", c.omega_rad_s / kTwoPi}};
}

// The machine a measured_frf model was built from: the fit's modes with their uncertainties.
Json machine_json(const Model& model) {
  const MeasuredMachine* machine = model.measured_machine();
  if (!machine) return nullptr;
  const MeasuredFrf& frf = machine->measured_frf();
  Json out = {{"frf_lines", frf.frequency_hz.size()},
              {"frf_band_hz", {frf.frequency_hz.front(), frf.frequency_hz.back()}},
              {"measured_as", std::string(to_string(frf.measured_as))}};
  if (const ModalFit* fit = machine->modal_fit()) {
    Json modes = Json::array();
    for (const FittedMode& m : fit->modes)
      modes.push_back({{"frequency_hz", m.frequency_hz}, {"frequency_sd_hz", m.frequency_sd_hz},
                       {"damping_ratio", m.damping_ratio}, {"damping_ratio_sd", m.damping_ratio_sd},
                       {"stiffness_n_per_m", m.stiffness_n_per_m}, {"stiffness_sd_n_per_m", m.stiffness_sd_n_per_m},
                       {"stable_orders", m.stable_orders}});
    out["modal_fit"] = {{"modes", modes}, {"relative_misfit", fit->relative_misfit},
                        {"upper_residual_m_per_n", fit->upper_residual_m_per_n}, {"orders", fit->orders.back()}};
  }
  return out;
}

void write_summary(const LobeStudy& study, const LobeResults& r, const PointContext& context) {
  Json notes = Json::object();
  for (std::size_t i = 0; i < study.speeds.size(); ++i)
    if (!r.diagram.at[i].note.empty()) notes[r.diagram.at[i].note] = notes.value(r.diagram.at[i].note, 0) + 1;
  Json windows = Json::array();
  for (const Window& w : r.windows)
    windows.push_back({{"from", w.from}, {"to", w.to}, {"peak_critical_value", w.peak_value}, {"peak_speed", w.peak_speed}});
  Json summary = {{"parameter", study.settings.parameter},
                  {"speed", study.settings.speed},
                  {"route", study.route == Route::roots ? "roots" : "nyquist"},
                  {"band_hz", study.band_hz},
                  {"speeds", study.speeds.size()},
                  {"lobes", r.diagram.lobes.size()},
                  {"seeds", r.diagram.seeds},
                  {"corrections", r.diagram.corrections},
                  {"speeds_without_limit", notes},
                  {"window_value", study.window_value},
                  {"chatter_free_windows", windows}};
  const auto lowest = std::min_element(r.diagram.at.begin(), r.diagram.at.end(), [](const auto& a, const auto& b) {
    return a.limit && (!b.limit || a.limit->parameter < b.limit->parameter);
  });
  if (lowest != r.diagram.at.end() && lowest->limit) {
    summary["lowest_limit"] = speed_json(*lowest->limit);
    const std::size_t i = static_cast<std::size_t>(lowest - r.diagram.at.begin());
    if (!r.elasticities.empty())
      for (std::size_t k = 0; k < r.sensitivity_keys.size(); ++k)
        summary["lowest_limit"]["elasticities"][r.sensitivity_keys[k]] = r.elasticities[i][k];
  }
  if (Json machine = machine_json(*study.model.at(study.window_value, study.speeds.front())); !machine.is_null())
    summary["machine"] = machine;
  if (study.time_to_chatter) summary["time_to_chatter"] = time_to_chatter_table().write(*study.time_to_chatter);
  kit::write_summary(context, summary);
}

void draw(const LobeStudy& study, const LobeResults& r, const std::filesystem::path& dir) {
  kit::Figures figures;
  plot_lobe_diagram(study, r, dir, figures);
  if (r.growth) plot_time_to_chatter(study, r, dir, figures);
  const auto model = study.model.at(study.window_value, study.speeds.front());
  if (const MeasuredMachine* machine = model->measured_machine()) kit::plot_measured_machine(*machine, study.title, dir, figures);
  figures.finish();
}

// results.csv: the diagram in a few numbers.
std::vector<Json> outputs(const LobeStudy& study, const LobeResults& r) {
  const SpeedResult* lowest = nullptr;
  const SpeedResult* highest = nullptr;
  int with_limit = 0;
  for (const SpeedResult& s : r.diagram.at) {
    if (!s.limit) continue;
    ++with_limit;
    if (!lowest || s.limit->parameter < lowest->limit->parameter) lowest = &s;
    if (!highest || s.limit->parameter > highest->limit->parameter) highest = &s;
  }
  double free = 0.0;
  for (const Window& w : r.windows) free += w.to - w.from;
  const double span = study.speeds.back() - study.speeds.front();
  auto value = [](const SpeedResult* s, auto member) { return s ? Json(member(*s->limit)) : Json(); };
  return {value(lowest, [](const Crossing& c) { return c.parameter; }),
          value(lowest, [](const Crossing& c) { return c.speed; }),
          value(lowest, [](const Crossing& c) { return c.omega_rad_s / kTwoPi; }),
          value(highest, [](const Crossing& c) { return c.parameter; }),
          value(highest, [](const Crossing& c) { return c.speed; }),
          with_limit,
          static_cast<int>(r.diagram.lobes.size()),
          static_cast<int>(r.windows.size()),
          free / span,
          study.route == Route::roots ? "roots" : "nyquist"};
}

}  // namespace

PluginInfo StabilityLobes::info() {
  return plugin_info("stability_lobes", "G1, G3, G8",
                     lobes_settings_table().specs(),
                     {{"parameter", "model.contact_stiffness_n_per_m"},
                      {"parameter_range", {1e5, 1e9}},
                      {"speed", "work_speed_rpm"},
                      {"speed_values", {40, 55, 70}}},
                     "lobe diagram: the critical value of one model parameter over a speed, traced along each lobe, with chatter "
                     "frequency, sensitivities, chatter-free windows and time to chatter");
}

void StabilityLobes::validate(Json& document, const SourceMap& sources) const {
  auto model = kit::validate_model(document, kit::ModelNeeds::nothing, "stability_lobes", sources);
  const LobesSettings s = kit::validate_settings(document, "lobes", lobes_settings_table(), sources);
  check_keys(document, s, sources);
  check_ranges(s, sources);
  const Route route = check_route(s, *model, sources);
  kit::validate_settings(document, "stability", kit::stability_settings_table(), sources);
  try {
    if (!(band_of(document, *model, route) > 0.0))
      refuse(sources, "stability", "[stability]: the model gives no frequency scale: set max_frequency_hz");
  } catch (const PointFailure& e) {
    refuse(sources, "model", fmt::format("[model]: {}", e.what()));
  }
  if (document.contains("time_to_chatter")) {
    kit::validate_settings(document, "time_to_chatter", time_to_chatter_table(), sources);
    if (route != Route::roots)
      refuse(sources, "time_to_chatter",
             "[time_to_chatter] needs growth rates, which only the roots route gives (a measured_frf model: "
             "machine_compliance = \"fitted_modes\")");
    const auto range = kit::read_settings(document, "time_to_chatter", time_to_chatter_table()).parameter_range;
    if (range && !((*range)[0] < (*range)[1]) )
      refuse(sources, "time_to_chatter.parameter_range", "time_to_chatter.parameter_range: needs low < high");
  }
  check_extremes(document, s, sources);
}

std::vector<std::string> StabilityLobes::output_columns(const Json&) const {
  return {"lowest_critical_value", "lowest_at_speed",      "chatter_frequency_at_lowest_hz",
          "highest_critical_value", "highest_at_speed",    "speeds_with_limit",
          "lobes",                  "chatter_free_windows", "chatter_free_fraction",
          "route"};
}

std::vector<Json> StabilityLobes::run_point(const Json& point_document, const PointContext& context) const {
  const LobeStudy study = read_study(point_document);
  const LobeResults r = compute(study);
  write_tables(study, r, context);
  write_summary(study, r, context);
  if (context.plots && !context.artifact_dir.empty()) draw(study, r, context.artifact_dir);
  return outputs(study, r);
}

void StabilityLobes::write_artifacts(const Study& study, const ResultTable& results,
                                     const std::filesystem::path& out_dir) const {
  // A grid of lobe diagrams (e.g. over the wheel speed): the lowest limit over the grid.
  const std::vector<kit::PlotAxis> axes = kit::varying_axes(study);
  if (axes.empty() || axes.size() > 2) return;
  kit::Figures figures;
  kit::ColumnFigure figure{"lowest_critical_value", kit::study_title(study) + ": lowest critical value over the speeds",
                           "lowest critical value"};
  kit::plot_column(axes, results, figure, out_dir, "lowest_critical_value", figures);
  figures.finish();
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::StabilityLobes);
