#include "study_kinds/stability_map/stability_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "chatterlab/closed_form.hpp"
#include "chatterlab/delay_system.hpp"
#include "chatterlab/plugin_info.hpp"
#include "study_kinds/stability_map/floquet_route.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;

// Output columns, in results.csv order.
constexpr const char* col_growth_rate = "growth_rate_per_s";
constexpr const char* col_chatter_frequency = "chatter_frequency_hz";
constexpr const char* col_growth_per_wheel_rev = "growth_rate_per_wheel_rev";
constexpr const char* col_stable = "stable";
constexpr const char* col_certified = "certified";
constexpr const char* col_certified_real_part = "certified_real_part_per_s";
constexpr const char* col_certificate = "certificate";
// Over the speed-tolerance band (models with process conditions).
constexpr const char* col_band_growth = "band_worst_growth_rate_per_s";
constexpr const char* col_band_frequency = "band_worst_chatter_frequency_hz";
constexpr const char* col_band_stable = "stable_over_speed_band";
constexpr const char* col_exact_ratio = "exact_speed_ratio";
// Which route gave the growth rate: "characteristic" (a model's hand-written characteristic
// function), "derived" (the characteristic function derived from its linearisation) or "floquet".
constexpr const char* col_route = "route";
// The Floquet route (a [suppression] table): the dominant multiplier, the constant-speed root it
// is compared with, and the discretisation's convergence figures (chatterlab/floquet.hpp).
constexpr const char* col_constant_growth = "constant_speed_growth_rate_per_s";
constexpr const char* col_growth_change = "growth_rate_change_per_s";
constexpr const char* col_multiplier = "floquet_multiplier_modulus";
constexpr const char* col_period = "floquet_period_s";
constexpr const char* col_converged = "floquet_converged";
constexpr const char* col_error = "floquet_error_per_s";
constexpr const char* col_steps = "floquet_steps_per_period";
constexpr const char* col_dimension = "floquet_dimension";

bool floquet_route(const Json& document) { return document.contains("suppression"); }
// A model whose linearisation has periodic coefficients at constant speeds (G7) has no
// characteristic function: every point takes the Floquet route over the coefficients' period.
bool periodic_model(const Model& model) { return stability_floquet::coefficient_period_s(model).has_value(); }
bool periodic_model(const Json& document) { return periodic_model(*kit::build_model(document.at("model"))); }

std::string characteristic_route(const CharacteristicFunction& characteristic) {
  return dynamic_cast<const DelayCharacteristic*>(&characteristic) ? "derived" : "characteristic";
}

bool has_speed_band(const Model& model) { return model.process_conditions() != nullptr; }

std::vector<ClosedFormIndicatorSpec> indicator_specs(const Json& document) {
  auto model = kit::build_model(document.at("model"));
  const ClosedFormIndicators* indicators = model->closed_forms();
  return indicators ? indicators->indicator_specs() : std::vector<ClosedFormIndicatorSpec>{};
}

// The closed-form indicators' values; a closed form that overflowed is "does not apply" here,
// never a silent inf in results.csv.
std::vector<Json> indicator_values(const Model& model) {
  const ClosedFormIndicators* indicators = model.closed_forms();
  if (!indicators) return {};
  std::vector<Json> values = indicators->indicator_values();
  if (values.size() != indicators->indicator_specs().size())
    throw std::logic_error("stability_map: a model reported a wrong number of indicators");
  for (Json& v : values)
    if (v.is_number() && !std::isfinite(v.get<double>())) v = Json();
  return values;
}

std::size_t count_uncertified(const ResultTable& results) {
  const std::size_t certified = kit::column_index(results, col_certified);
  return static_cast<std::size_t>(std::count_if(results.rows.begin(), results.rows.end(),
                                                [&](const auto& row) { return row[certified] == Json(false); }));
}

// Growth rate and chatter frequency over the grid. A map has no marker for single cells: its
// title says how many points rest on an unproven search; a curve marks them.
void plot_roots(const std::vector<kit::PlotAxis>& axes, const Study& study, const ResultTable& results,
                const fs::path& out_dir, kit::Figures& figures) {
  const std::string title = kit::study_title(study);
  const bool map = axes.size() == 2;
  kit::ColumnFigure growth{col_growth_rate, title + ": growth rate Re s", "growth rate Re s [1/s]"};
  growth.reference = 0.0;
  growth.reference_label = map ? "stability boundary (Re s = 0)" : "stability limit (Re s = 0)";
  growth.flag_column = col_certified;
  growth.flag_label = "no certificate";
  if (map) {
    if (const std::size_t n = count_uncertified(results); n > 0)
      growth.title += fmt::format(" ({}/{} uncertified)", n, results.rows.size());
    growth.diverging = true;
    growth.low_label = "stable";
    growth.high_label = "chatter";
    // The palette stretches each side of 0 over its own range, but the colour bar is linear: when
    // the stable side is tiny next to the chatter side (roots of a regeneration chain decaying
    // slowly) its ticks vanish, so the colour-bar label states the most stable value.
    const std::size_t c = kit::column_index(results, col_growth_rate);
    double most_stable = 0.0;
    for (std::size_t r = 0; r < results.rows.size(); ++r)
      if (const double z = kit::cell(results, r, c); std::isfinite(z)) most_stable = std::min(most_stable, z);
    if (most_stable < 0.0)
      growth.value_label = fmt::format("growth rate Re s [1/s]  (most stable: {:.3g})", most_stable);
  }
  kit::plot_column(axes, results, growth, out_dir, map ? "growth_rate_map" : "growth_rate", figures);
  kit::ColumnFigure frequency{col_chatter_frequency, title + ": chatter frequency |Im s|/2 pi",
                              "chatter frequency [Hz]"};
  frequency.flag_column = col_certified;
  frequency.flag_label = "no certificate";
  kit::plot_column(axes, results, frequency, out_dir, map ? "chatter_frequency_map" : "chatter_frequency",
                   figures);
  if (std::find(results.output_columns.begin(), results.output_columns.end(), col_band_growth) ==
      results.output_columns.end())
    return;
  const double tol = study.document.at("stability").at("speed_tolerance").get<double>();
  kit::ColumnFigure band{col_band_growth,
                         fmt::format("{}: worst over ±{:g} % speed", title, 100.0 * tol),
                         "worst growth rate in the speed band [1/s]"};
  band.reference = 0.0;
  band.reference_label = map ? "robust stability boundary" : "stability limit (Re s = 0)";
  band.diverging = true;
  band.low_label = "stable";
  band.high_label = "chatter";
  kit::plot_column(axes, results, band, out_dir, map ? "band_growth_rate_map" : "band_growth_rate", figures);
}

// The Floquet route: the growth rate ln|mu|/T (its zero line the stability boundary) and its
// change against constant speed (blue: the modulation stabilises). Points whose discretisation
// did not converge are flagged.
void plot_floquet(const std::vector<kit::PlotAxis>& axes, const Study& study, const ResultTable& results,
                  const fs::path& out_dir, kit::Figures& figures) {
  const std::string title = kit::study_title(study);
  const bool map = axes.size() == 2;
  struct Spec {
    const char *column, *what, *value_label, *reference_label, *low, *high, *stem;
  };
  const Spec specs[] = {
      {col_growth_rate, "Floquet growth rate ln|mu|/T", "Floquet growth rate [1/s]",
       map ? "stability boundary (|mu| = 1)" : "stability limit (|mu| = 1)", "stable", "chatter", "floquet_growth_rate"},
      {col_growth_change, "Floquet growth rate - constant speed", "growth rate change [1/s]", "no effect",
       "modulation stabilises", "modulation destabilises", "growth_rate_change"},
  };
  for (const Spec& spec : specs) {
    // A model with periodic coefficients has no constant-speed comparison (no change column).
    if (std::find(results.output_columns.begin(), results.output_columns.end(), spec.column) ==
        results.output_columns.end())
      continue;
    kit::ColumnFigure figure{spec.column, title + ": " + spec.what, spec.value_label};
    figure.reference = 0.0;
    figure.reference_label = spec.reference_label;
    figure.flag_column = col_converged;
    figure.flag_label = "not converged";
    figure.diverging = map;
    figure.low_label = spec.low;
    figure.high_label = spec.high;
    kit::plot_column(axes, results, figure, out_dir, map ? std::string(spec.stem) + "_map" : spec.stem, figures);
  }
}

// Closed-form chatter margins (ClosedFormIndicatorSpec::chatter_margin): drawn like the growth
// rate, with their own zero line, and the title counts the points where the closed form's verdict
// (margin > 0: chatter) differs from the rightmost root's (Re s > 0).
void plot_closed_form_margins(const std::vector<kit::PlotAxis>& axes, const Study& study,
                              const ResultTable& results, const fs::path& out_dir, kit::Figures& figures) {
  const std::size_t growth = kit::column_index(results, col_growth_rate);
  for (const ClosedFormIndicatorSpec& spec : indicator_specs(study.document)) {
    if (!spec.chatter_margin) continue;
    const std::size_t margin = kit::column_index(results, spec.name);
    std::size_t compared = 0, disagree = 0;
    for (std::size_t r = 0; r < results.rows.size(); ++r) {
      const double g = kit::cell(results, r, growth), m = kit::cell(results, r, margin);
      if (!std::isfinite(g) || !std::isfinite(m)) continue;
      ++compared;
      disagree += (g > 0.0) != (m > 0.0) ? 1 : 0;
    }
    if (compared == 0) continue;  // the closed form applies nowhere in this study (G3 with the work chain on)
    kit::ColumnFigure figure{spec.name,
                             fmt::format("{} ({}/{} points disagree with the root)", spec.name, disagree, compared),
                             axes.size() == 1 ? spec.name + " (> 0: chatter)" : spec.name};
    figure.reference = 0.0;
    figure.reference_label = axes.size() == 1 ? "closed-form boundary" : "closed-form boundary (margin = 0)";
    figure.diverging = true;
    figure.low_label = "stable";
    figure.high_label = "chatter";
    kit::plot_column(axes, results, figure, out_dir, spec.name, figures);  // file = column name
  }
}

// One point of a Floquet route (floquet_columns order): the Floquet growth rate ln|mu|/T, the
// constant-speed rightmost root to compare with when there is one (a [suppression] study: the same
// model at its nominal speeds), and the discretisation's convergence figures.
std::vector<Json> floquet_row(const Model& model, const stability_floquet::FloquetPoint& f,
                              std::optional<double> constant_speed_growth_per_s) {
  const double growth = f.floquet.growth_rate_per_s;
  std::vector<Json> out{growth};
  if (const auto wheel_period = model.wheel_period_s()) out.emplace_back(growth * *wheel_period / (2.0 * std::numbers::pi));
  out.emplace_back(growth < 0.0);
  out.emplace_back("floquet");
  if (constant_speed_growth_per_s) {
    out.emplace_back(*constant_speed_growth_per_s);
    out.emplace_back(growth - *constant_speed_growth_per_s);
  }
  out.emplace_back(std::abs(f.floquet.multiplier));
  out.emplace_back(f.period_s);
  out.emplace_back(f.floquet.converged);
  out.emplace_back(f.floquet.growth_rate_error_per_s);
  out.emplace_back(f.floquet.steps_per_period);
  out.emplace_back(f.floquet.dimension);
  return out;
}

std::vector<Json> floquet_point(const Model& model, const Json& document, const kit::StabilitySettings& settings) {
  const stability_floquet::FloquetPoint f = stability_floquet::growth_rate(model, document.at("suppression"));
  return floquet_row(model, f, kit::rightmost_root(model, settings).root.real());
}

// A model with periodic coefficients (G7): one period of its coefficients at constant speeds.
std::vector<Json> periodic_model_point(const Model& model) {
  return floquet_row(model, stability_floquet::periodic_model_growth_rate(model), std::nullopt);
}

// The columns of the Floquet routes: a [suppression] table adds the constant-speed comparison.
std::vector<std::string> floquet_columns(const Json& document, bool with_constant_speed) {
  std::vector<std::string> columns{col_growth_rate};
  if (kit::build_model(document.at("model"))->wheel_period_s()) columns.push_back(col_growth_per_wheel_rev);
  columns.push_back(col_stable);
  columns.push_back(col_route);
  if (with_constant_speed)
    for (const char* c : {col_constant_growth, col_growth_change}) columns.push_back(c);
  for (const char* c : {col_multiplier, col_period, col_converged, col_error, col_steps, col_dimension})
    columns.push_back(c);
  return columns;
}

}  // namespace

PluginInfo StabilityMap::info() {
  return plugin_info("stability_map", "G1, G3, G5, G6, G7, S2, S3",
                     kit::stability_settings_table().specs(),
                     {{"max_frequency_hz", 500.0}},
                     "rightmost characteristic root per grid point: growth rate, chatter frequency, stability "
                     "and a certificate that no root lies further right; with [suppression] (modulated wheel or "
                     "work speed), or for a model whose coefficients repeat once per revolution (G7), the Floquet "
                     "growth rate of the periodic linearisation");
}

void StabilityMap::validate(Json& document, const SourceMap& sources) const {
  if (auto model = kit::validate_model(document, kit::ModelNeeds::nothing, "stability_map", sources);
      periodic_model(*model)) {
    kit::validate_settings(document, "stability", kit::stability_settings_table(), sources);
    stability_floquet::validate_periodic_model(document, *model, sources);
    return;
  }
  auto model = kit::validate_model(document, kit::ModelNeeds::characteristic, "stability_map", sources);
  kit::validate_stability(document, *model, sources);
  if (floquet_route(document)) stability_floquet::validate(document, *model, sources);
}

std::vector<std::string> StabilityMap::output_columns(const Json& document) const {
  if (periodic_model(document)) return floquet_columns(document, false);
  if (floquet_route(document)) return floquet_columns(document, true);
  std::vector<std::string> columns{col_growth_rate, col_chatter_frequency};
  // Growth per wheel revolution (G3) only for models with a wheel.
  if (kit::build_model(document.at("model"))->wheel_period_s())
    columns.push_back(col_growth_per_wheel_rev);
  for (const char* c : {col_stable, col_certified, col_certified_real_part, col_certificate, col_route})
    columns.push_back(c);
  if (has_speed_band(*kit::build_model(document.at("model"))))
    for (const char* c : {col_band_growth, col_band_frequency, col_band_stable, col_exact_ratio})
      columns.push_back(c);
  // Closed-form indicators last: a property of the model type, like the wheel column.
  for (const ClosedFormIndicatorSpec& spec : indicator_specs(document)) columns.push_back(spec.name);
  return columns;
}

std::vector<Json> StabilityMap::run_point(const Json& point_document,
                                          const PointContext& /*context*/) const {
  auto model = kit::build_model(point_document.at("model"));
  if (periodic_model(*model)) return periodic_model_point(*model);
  const kit::StabilitySettings settings =
      kit::read_settings(point_document, "stability", kit::stability_settings_table());
  if (floquet_route(point_document)) return floquet_point(*model, point_document, settings);
  const RightmostRoot found = kit::rightmost_root(*model, settings);
  const kit::StabilityVerdict v = kit::verdict(found, *model);
  std::vector<Json> out{v.growth_rate_per_s, v.chatter_frequency_hz};
  // Same rule as output_columns(): having a wheel is a property of the model type.
  if (v.growth_rate_per_wheel_rev) out.emplace_back(*v.growth_rate_per_wheel_rev);
  out.emplace_back(v.stable);
  out.emplace_back(found.certified);
  out.push_back(found.certified ? Json(found.certified_real_part) : Json());
  out.emplace_back(found.certificate);
  out.emplace_back(characteristic_route(*model->characteristic()));
  if (has_speed_band(*model)) {
    const kit::SpeedBandVerdict band = kit::speed_band_verdict(point_document.at("model"), *model, settings, found);
    out.emplace_back(band.worst_growth_rate_per_s);
    out.emplace_back(band.worst_chatter_frequency_hz);
    out.emplace_back(band.stable_over_band);
    out.emplace_back(band.exact_speed_ratio);
  }
  for (Json& value : indicator_values(*model)) out.push_back(std::move(value));
  return out;
}

void StabilityMap::write_artifacts(const Study& study, const ResultTable& results,
                                   const fs::path& out_dir) const {
  // A single point has nothing to draw; 3+ varying axes have no faithful 2-D picture: both are
  // documented, and results.csv holds every number.
  const std::vector<kit::PlotAxis> axes = kit::varying_axes(study);
  if (axes.empty() || axes.size() > 2) return;
  kit::Figures figures;
  if (floquet_route(study.document) || periodic_model(study.document)) {
    plot_floquet(axes, study, results, out_dir, figures);
    figures.finish();
    return;
  }
  plot_roots(axes, study, results, out_dir, figures);
  plot_closed_form_margins(axes, study, results, out_dir, figures);
  figures.finish();
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::StabilityMap);
