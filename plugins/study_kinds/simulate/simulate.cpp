#include "study_kinds/simulate/simulate.hpp"

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/plugin_info.hpp"
#include "study_kinds/simulate/closed_form_columns.hpp"
#include "study_kinds/simulate/simulate_point.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;

constexpr const char* col_growth = "fitted_growth_rate_per_s";
constexpr const char* col_frequency = "dominant_frequency_hz";
constexpr const char* col_max_displacement = "max_displacement_m";
constexpr const char* col_contact_loss = "contact_loss_fraction";
constexpr const char* col_outcome = "simulation_outcome";
constexpr const char* col_fit_valid = "fit_valid";
constexpr const char* col_fit_regime = "fit_regime";
constexpr const char* col_fit_reason = "fit_reason";
constexpr const char* col_work_wt = "work_waviness_wt_um";
constexpr const char* col_work_wz = "work_waviness_wz_um";
constexpr const char* col_work_ront = "work_roundness_ront_um";

// The engine run of a point; settings the engine refuses are the point's failure.
SimulationResult run_engine(const TimeDomainModel& model, const kit::SimulationTable& table) {
  try {
    return simulate(model, kit::simulation_settings(table, model));
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
}

}  // namespace

const ParamTable<SimulateSettings>& simulate_settings_table() {
  using S = SimulateSettings;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add_fields(&S::simulation, kit::simulation_table());
    t.add_choice(&S::timeseries_format, "timeseries_format",
                 "time-series file: csv (timeseries.csv) or npy (timeseries.npy, a NumPy structured array with "
                 "one float64 field per column: long runs)",
                 {{"csv", TimeSeriesFormat::csv}, {"npy", TimeSeriesFormat::npy}});
    t.add(&S::timeseries_decimation, "timeseries_decimation", "1",
          "write every k-th output sample to the time-series file (exact samples, no filter; the fit and "
          "spectrum use every sample)")
        .at_least(1);
    t.add(&S::measurement_noise_m, "measurement_noise_m", "m",
          "rms of white Gaussian sensor noise added to x in timeseries.csv column measured_displacement_m "
          "(seeded by seed; 0: no column)")
        .non_negative();
    t.add(&S::write_point_files, "write_point_files", "1", "in a grid, also write each point's files into points/<i>/");
    return t;
  }();
  return table;
}

PluginInfo Simulate::info() {
  return plugin_info("simulate", "G1, G5, G6, G7",
                     simulate_settings_table().specs(),
                     {{"duration_s", 0.2}, {"sample_rate_hz", 10000.0}},
                     "time-domain simulation of the model (angle-indexed regenerative surfaces, "
                     "one-sided contact): growth rate, chatter frequency, surfaces");
}

void Simulate::validate(Json& document, const SourceMap& sources) const {
  auto model = kit::validate_model(document, kit::ModelNeeds::time_domain, "simulate", sources);
  SimulateSettings settings = kit::validate_settings(document, "simulation", simulate_settings_table(), sources);
  kit::check_simulation(settings.simulation, *model->time_domain(), "simulation", sources);
  document["simulation"] = simulate_settings_table().write(settings);  // with the default snapshot
  validate_surface(document, sources);
}

void Simulate::validate_surface(Json& document, const SourceMap& sources) {
  // [surface] (optional): the settings of the profile-quality measurement (for the surface
  // metrology: the surface study's [filter]/[process]/[parameters] keys, flat), checked by the
  // measuring analysis itself: its limits, its joint checks, and what a closed profile refuses.
  const auto* entry = simulate_point::profile_quality_analysis();
  if (!entry) {
    if (document.contains("surface"))
      throw InputError(fmt::format("{}: [surface] needs an analysis plugin that measures profile quality "
                                   "(Analysis::profile_quality()); none is registered in this build",
                                   sources.locate("surface").str()));
    return;
  }
  const auto probe = entry->create(ParamValues(kit::example_parameters(entry->info)));
  Json table = validate_params(kit::table_or_empty(document, "surface", sources),
                               probe->profile_quality()->measurement_params(), "surface", sources);
  std::unique_ptr<Analysis> measuring;
  try {
    measuring = entry->create(ParamValues(kit::plugin_parameters(entry->info, table)));
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: [surface]: {}", sources.locate("surface").str(), e.what()));
  }
  if (const auto problem = measuring->profile_quality()->setting_problem(/*closed_profile=*/true))
    throw InputError(fmt::format("{}: surface.{} = {}: a simulated work surface is a closed profile (one "
                                 "revolution); {}",
                                 sources.locate("surface." + problem->key).str(), problem->key,
                                 problem->value.dump(), problem->reason));
  document["surface"] = std::move(table);
}

std::vector<std::string> Simulate::output_columns(const Json& document) const {
  std::vector<std::string> columns{col_growth,           col_fit_valid,    col_fit_regime, col_fit_reason,
                                   col_frequency,        col_max_displacement, col_contact_loss, col_outcome,
                                   col_work_wt,          col_work_wz,      col_work_ront};
  // Closed forms that predict a simulated quantity (G6's forced amplitude), beside it.
  for (std::string& c : simulate_closed_forms::columns(*kit::build_model(document.at("model"))))
    columns.push_back(std::move(c));
  return columns;
}

std::vector<Json> Simulate::run_point(const Json& document, const PointContext& context) const {
  const SimulateSettings settings = kit::read_settings(document, "simulation", simulate_settings_table());
  const auto full_model = kit::build_model(document.at("model"));
  auto model = full_model->time_domain();
  if (!model) throw PointFailure("the model has no time-domain form here");
  const SimulationResult result = run_engine(*model, settings.simulation);
  const simulate_point::PointAnalysis a =
      simulate_point::analyse(result, settings.simulation, kit::longest_delay_s(*model));
  const simulate_point::WorkSurfaceQuality quality = simulate_point::measure_work_surface(
      result, document.value("surface", Json::object()), settings.simulation.contact.infeed_rate_m_per_s);
  if (!context.artifact_dir.empty() && (context.single_point() || settings.write_point_files))
    simulate_point::write_point_files(result, a, quality, document, settings, context);
  std::vector<Json> row{a.fit ? Json(a.fit->growth_rate_per_s) : Json(),
                        a.validity ? Json(a.validity->valid) : Json(false),
                        a.validity ? to_string(a.validity->regime) : "no fit",
                        a.validity ? a.validity->reason : a.fit_problem,
                        a.peaks.empty() ? Json() : Json(a.peaks.front().frequency_hz),
                        a.max_displacement,
                        result.end_time_s > 0 ? result.contact_loss_time_s / result.end_time_s : 0.0,
                        result.diverged ? std::string("diverged") : std::string("completed"),
                        quality.wt_um,
                        quality.wz_um,
                        quality.ront_um};
  for (Json& v : simulate_closed_forms::values(*full_model, *model, result)) row.push_back(std::move(v));
  return row;
}

void Simulate::write_artifacts(const Study& study, const ResultTable& results, const fs::path& out_dir) const {
  // Fitted growth rate and dominant frequency over the grid: a curve over one varying axis, a map
  // over two (a single point's figures are its own).
  const std::vector<kit::PlotAxis> axes = kit::varying_axes(study);
  const std::string title = kit::study_title(study);
  kit::Figures figures;
  kit::ColumnFigure growth{col_growth, title + ": fitted growth rate", "fitted growth rate [1/s]"};
  growth.reference = 0.0;
  growth.reference_label = "growth = 0";
  growth.diverging = true;
  growth.low_label = "decays";
  growth.high_label = "grows";
  kit::plot_column(axes, results, growth, out_dir, "fitted_growth_rate", figures);
  kit::plot_column(axes, results, {col_frequency, title + ": dominant frequency", "dominant frequency [Hz]"},
                   out_dir, "dominant_frequency", figures);
  figures.finish();
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::Simulate);
