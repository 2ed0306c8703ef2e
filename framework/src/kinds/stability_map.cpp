#include "kinds/stability_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "chatterlab/closed_form.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/plot.hpp"
#include "kinds/model_table.hpp"
#include "chatterlab/roots.hpp"

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

using kinds_detail::build_model;

// The model's closed-form indicators (chatterlab/closed_form.hpp), if it reports any.
const ClosedFormIndicators* closed_forms(const Model& model) {
  return dynamic_cast<const ClosedFormIndicators*>(&model);
}

std::vector<ClosedFormIndicatorSpec> indicator_specs(const Json& document) {
  auto model = build_model(document.at("model"));
  const ClosedFormIndicators* indicators = closed_forms(*model);
  return indicators ? indicators->indicator_specs() : std::vector<ClosedFormIndicatorSpec>{};
}

// ---------------------------------------------------------------- plots
bool numeric_axis(const GridAxis& axis) {
  for (const auto& v : axis.values)
    if (!v.is_number()) return false;
  return true;
}

// A log axis when the values are a geometric, not an arithmetic, progression (what
// `{ from, to, steps, log = true }` produces, or a hand-written 1, 10, 100).
bool log_spaced(const std::vector<double>& v) {
  if (v.size() < 3) return false;
  auto same = [](double a, double b) {
    return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
  };
  bool geometric = true, arithmetic = true;
  for (std::size_t i = 0; i + 1 < v.size(); ++i) {
    if (v[i] <= 0 || v[i + 1] <= 0) return false;
    geometric = geometric && same(v[i + 1] / v[i], v[1] / v[0]);
    arithmetic = arithmetic && same(v[i + 1] - v[i], v[1] - v[0]);
  }
  return geometric && !arithmetic;
}

std::vector<double> numbers(const std::vector<Json>& values) {
  std::vector<double> out;
  for (const auto& v : values) out.push_back(v.get<double>());
  return out;
}

std::size_t column_index(const ResultTable& results, const std::string& name) {
  for (std::size_t c = 0; c < results.output_columns.size(); ++c)
    if (results.output_columns[c] == name) return results.grid_columns.size() + c;
  throw std::logic_error("stability_map: no column " + name);
}

// The value of a numeric output of row r, NaN for a failed point (a blank/grey cell in plots).
double cell(const ResultTable& results, std::size_t r, std::size_t column) {
  const Json& v = results.rows[r][column];
  return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

std::string study_title(const Study& study) {
  auto it = study.document.find("study");
  if (it != study.document.end() && it->is_object() && it->contains("name") &&
      (*it)["name"].is_string())
    return (*it)["name"].get<std::string>();
  return study.file.stem().string();
}

// Draws every figure even when one fails (e.g. gnuplot rejects a title), then reports all
// failures together: the runner records them in meta.json.
class Figures {
 public:
  template <class Figure>
  void render(const Figure& figure, const fs::path& out_dir, const std::string& stem) {
    try {
      plot::render(figure, out_dir, stem);
    } catch (const std::exception& e) {
      errors_ += fmt::format("{}{}: {}", errors_.empty() ? "" : "; ", stem, e.what());
    }
  }
  void finish() const {
    if (!errors_.empty()) throw plot::PlotError(errors_);
  }

 private:
  std::string errors_;
};

struct PlotAxis {
  std::string label;
  std::vector<double> values;
  bool log = false;
};

// `log = true` as written in the study's [grid] table (Study::document keeps that table).
bool declared_log(const Study& study, const GridAxis& axis) {
  auto grid = study.document.find("grid");
  if (grid == study.document.end() || !grid->is_object()) return false;
  auto range = grid->find(axis.key);
  if (range == grid->end() || !range->is_object()) return false;
  auto log = range->find("log");
  return log != range->end() && *log == Json(true);
}

PlotAxis plot_axis(const Study& study, const GridAxis& axis) {
  PlotAxis out{axis.key, numbers(axis.values), false};
  out.log = declared_log(study, axis) || log_spaced(out.values);
  return out;
}

// 1-D grid: growth rate and chatter frequency against the grid key. Points without a certificate
// are marked separately so a reader sees where the curve rests on an unproven search.
void plot_curves(const Study& study, const ResultTable& results, std::size_t axis_index,
                 const fs::path& out_dir, Figures& figures) {
  const PlotAxis axis = plot_axis(study, study.grid[axis_index]);
  const std::size_t growth = column_index(results, col_growth_rate);
  const std::size_t frequency = column_index(results, col_chatter_frequency);
  const std::size_t certified = column_index(results, col_certified);
  const std::string title = study_title(study);

  auto figure = [&](std::size_t column, const std::string& what, const std::string& y_label) {
    plot::Curves curves;
    curves.title = fmt::format("{}: {}", title, what);
    curves.x_label = axis.label;
    curves.y_label = y_label;
    curves.log_x = axis.log;
    plot::Series main{what, {}, {}, "linespoints"};
    plot::Series uncertified{"no certificate", {}, {}, "points"};
    for (std::size_t r = 0; r < results.rows.size(); ++r) {
      double y = cell(results, r, column);
      if (!std::isfinite(y)) continue;  // failed point: listed in results.csv and meta.json
      double x = results.rows[r][axis_index].get<double>();
      main.x.push_back(x);
      main.y.push_back(y);
      if (results.rows[r][certified] == Json(false)) {
        uncertified.x.push_back(x);
        uncertified.y.push_back(y);
      }
    }
    curves.series.push_back(std::move(main));
    if (!uncertified.x.empty()) curves.series.push_back(std::move(uncertified));
    return curves;
  };

  plot::Curves growth_plot = figure(growth, "growth rate Re s", "growth rate Re s [1/s]");
  growth_plot.reference_y = 0.0;
  growth_plot.reference_label = "stability limit (Re s = 0)";
  figures.render(growth_plot, out_dir, "growth_rate");
  figures.render(figure(frequency, "chatter frequency |Im s|/2 pi", "chatter frequency [Hz]"),
                 out_dir, "chatter_frequency");
}

// 2-D grid: growth-rate map with the stability boundary (contour Re s = 0) and the chatter
// frequency map. x = the faster (later) grid axis, so results rows are already z's order.
void plot_maps(const Study& study, const ResultTable& results, std::size_t slow_axis,
               std::size_t fast_axis, const fs::path& out_dir, Figures& figures) {
  const PlotAxis x = plot_axis(study, study.grid[fast_axis]);
  const PlotAxis y = plot_axis(study, study.grid[slow_axis]);
  const std::string title = study_title(study);
  auto map = [&](const char* column, const std::string& what, const std::string& z_label) {
    plot::Heatmap h;
    h.title = fmt::format("{}: {}", title, what);
    h.x_label = x.label;
    h.y_label = y.label;
    h.z_label = z_label;
    h.x = x.values;
    h.y = y.values;
    h.log_x = x.log;
    h.log_y = y.log;
    const std::size_t c = column_index(results, column);
    for (std::size_t r = 0; r < results.rows.size(); ++r) h.z.push_back(cell(results, r, c));
    return h;
  };

  // A map has no marker for single cells: the title says how many rest on an unproven search.
  const std::size_t certified = column_index(results, col_certified);
  std::size_t uncertified = 0;
  for (const auto& row : results.rows) uncertified += row[certified] == Json(false) ? 1 : 0;
  const std::string growth_what =
      uncertified == 0
          ? std::string("growth rate Re s")
          : fmt::format("growth rate Re s ({}/{} uncertified)", uncertified, results.rows.size());
  plot::Heatmap growth = map(col_growth_rate, growth_what, "growth rate Re s [1/s]");
  growth.contour_level = 0.0;
  growth.contour_label = "stability boundary (Re s = 0)";
  growth.diverging = true;
  // The palette stretches each side of 0 over its own range, but the colour bar is linear: when
  // the stable side is tiny next to the chatter side (roots of a regeneration chain decaying
  // slowly) its ticks vanish, so the colour-bar label states the most stable value.
  double most_stable = 0.0;
  for (double z : growth.z)
    if (std::isfinite(z)) most_stable = std::min(most_stable, z);
  if (most_stable < 0.0)
    growth.z_label = fmt::format("growth rate Re s [1/s]  (most stable: {:.3g})", most_stable);
  growth.low_label = "stable";
  growth.high_label = "chatter";
  figures.render(growth, out_dir, "growth_rate_map");
  figures.render(
      map(col_chatter_frequency, "chatter frequency |Im s|/2 pi", "chatter frequency [Hz]"),
      out_dir, "chatter_frequency_map");
}

// Closed-form chatter margins (ClosedFormIndicatorSpec::chatter_margin): drawn like the growth
// rate, with their own zero line, and the title counts the points where the closed form's verdict
// (margin > 0: chatter) differs from the rightmost root's (Re s > 0).
void plot_closed_form_margins(const Study& study, const ResultTable& results,
                              const std::vector<std::size_t>& varying, const fs::path& out_dir,
                              Figures& figures) {
  const std::size_t growth = column_index(results, col_growth_rate);
  for (const ClosedFormIndicatorSpec& spec : indicator_specs(study.document)) {
    if (!spec.chatter_margin) continue;
    const std::size_t margin = column_index(results, spec.name);
    std::size_t compared = 0, disagree = 0;
    for (std::size_t r = 0; r < results.rows.size(); ++r) {
      const double g = cell(results, r, growth), m = cell(results, r, margin);
      if (!std::isfinite(g) || !std::isfinite(m)) continue;
      ++compared;
      disagree += (g > 0.0) != (m > 0.0) ? 1 : 0;
    }
    const std::string what =
        fmt::format("{} ({}/{} points disagree with the root)", spec.name, disagree, compared);
    const std::string stem = spec.name;  // results.csv column = file name
    if (varying.size() == 1) {
      const PlotAxis axis = plot_axis(study, study.grid[varying[0]]);
      plot::Curves curves;
      curves.title = what;  // long enough without the study name
      curves.x_label = axis.label;
      curves.y_label = spec.name + " (> 0: chatter)";
      curves.log_x = axis.log;
      plot::Series series{spec.name, {}, {}, "linespoints"};
      for (std::size_t r = 0; r < results.rows.size(); ++r) {
        const double y = cell(results, r, margin);
        if (!std::isfinite(y)) continue;
        series.x.push_back(results.rows[r][varying[0]].get<double>());
        series.y.push_back(y);
      }
      curves.series.push_back(std::move(series));
      curves.reference_y = 0.0;
      curves.reference_label = "closed-form boundary";
      figures.render(curves, out_dir, stem);
    } else if (varying.size() == 2) {
      const PlotAxis x = plot_axis(study, study.grid[varying[1]]);
      const PlotAxis y = plot_axis(study, study.grid[varying[0]]);
      plot::Heatmap h;
      h.title = what;
      h.x_label = x.label;
      h.y_label = y.label;
      h.z_label = spec.name;
      h.x = x.values;
      h.y = y.values;
      h.log_x = x.log;
      h.log_y = y.log;
      for (std::size_t r = 0; r < results.rows.size(); ++r) h.z.push_back(cell(results, r, margin));
      h.contour_level = 0.0;
      h.contour_label = "closed-form boundary (margin = 0)";
      h.diverging = true;
      h.low_label = "stable";
      h.high_label = "chatter";
      figures.render(h, out_dir, stem);
    }
  }
}

}  // namespace

PluginInfo StabilityMap::info() {
  const RootSearchOptions defaults;
  PluginInfo info;
  info.name = "stability_map";
  info.description =
      "rightmost characteristic root per grid point: growth rate, chatter frequency, stability "
      "and a certificate that no root lies further right";
  info.models_md_ids = "G1, G3";
  ParamSpec band = param_spec(
      "max_frequency_hz", ValueKind::real, "Hz",
      fmt::format("search band |Im s| <= 2 pi max_frequency_hz (default: {} x the model's highest "
                  "structural natural frequency)",
                  default_band_multiple));
  band.min = 0.0;
  band.min_exclusive = true;
  band.optional = true;
  ParamSpec iterations =
      param_spec("max_newton_iterations", ValueKind::integer, "1",
                 "Newton iterations per starting guess before the guess is abandoned");
  iterations.default_value = defaults.max_newton_iterations;
  iterations.min = 1;
  iterations.max = 100000;
  ParamSpec tolerance = param_spec("newton_relative_tolerance", ValueKind::real, "1",
                                   "Newton stops when its step is below this times |s|");
  tolerance.default_value = defaults.newton_relative_tolerance;
  tolerance.min = 0.0;
  tolerance.min_exclusive = true;
  tolerance.max = 1e-3;
  ParamSpec budget = param_spec(
      "max_function_evaluations", ValueKind::integer, "1",
      "work budget per grid point (evaluations of the characteristic function): beyond it the "
      "point is reported uncertified, or failed if no root was found yet");
  budget.default_value = defaults.max_function_evaluations;
  budget.min = 1;
  info.params = {band, iterations, tolerance, budget};
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_frequency_hz", 500.0}};
  return info;
}

void StabilityMap::validate(Json& document, const SourceMap& sources) const {
  Json model = validate_component(document, "model", model_registry(), sources);
  Json stability = document.contains("stability") ? document["stability"] : Json::object();
  if (!stability.is_object())
    throw InputError(fmt::format("{}: stability = {}: expected a table [stability]",
                                 sources.locate("stability").str(), stability.dump()));
  stability = validate_params(stability, info().params, "stability", sources);

  // Checked here, not per point: a model that cannot give a characteristic function, or no band,
  // is a study error (exit 2), not thousands of failed points.
  const std::string type = model["type"].get<std::string>();
  auto characteristic = build_model(model)->characteristic();
  if (!characteristic)
    throw InputError(fmt::format(
        "{}: model.type = \"{}\": this model has no characteristic function (linear stability), "
        "which the stability_map study needs",
        sources.locate("model.type").str(), type));
  if (stability["max_frequency_hz"].is_null()) {
    double scale = characteristic->natural_frequency_scale_hz();
    if (!(std::isfinite(scale) && scale > 0))
      throw InputError(fmt::format(
          "{}: missing key 'stability.max_frequency_hz': model '{}' has no structural frequency "
          "to derive the default search band from",
          sources.locate("stability").str(), type));
  }
  document["model"] = std::move(model);
  document["stability"] = std::move(stability);
}

std::vector<std::string> StabilityMap::output_columns(const Json& document) const {
  std::vector<std::string> columns{col_growth_rate, col_chatter_frequency};
  // Growth per wheel revolution (G3) only for models with a wheel.
  if (build_model(document.at("model"))->wheel_period_s())
    columns.push_back(col_growth_per_wheel_rev);
  for (const char* c : {col_stable, col_certified, col_certified_real_part, col_certificate})
    columns.push_back(c);
  // Closed-form indicators last: a property of the model type, like the wheel column.
  for (const ClosedFormIndicatorSpec& spec : indicator_specs(document)) columns.push_back(spec.name);
  return columns;
}

std::vector<Json> StabilityMap::run_point(const Json& point_document,
                                          const PointContext& /*context*/) const {
  const Json& model_table = point_document.at("model");
  auto model = build_model(model_table);
  const RightmostRoot found = kinds_detail::rightmost_root(*model, point_document.at("stability"));

  const double growth = found.root.real();
  std::vector<Json> out{growth, std::abs(found.root.imag()) / (2 * std::numbers::pi)};
  // Same rule as output_columns(): having a wheel is a property of the model type.
  if (auto wheel_period = model->wheel_period_s())
    out.emplace_back(*wheel_period * growth / (2 * std::numbers::pi));
  out.emplace_back(growth < 0);
  out.emplace_back(found.certified);
  out.push_back(found.certified ? Json(found.certified_real_part) : Json());
  out.emplace_back(found.certificate);
  if (const ClosedFormIndicators* indicators = closed_forms(*model)) {
    std::vector<Json> values = indicators->indicator_values();
    if (values.size() != indicators->indicator_specs().size())
      throw std::logic_error("stability_map: a model reported a wrong number of indicators");
    for (Json& v : values) {
      // A closed form that overflowed is "does not apply" here, never a silent inf in results.csv.
      if (v.is_number() && !std::isfinite(v.get<double>())) v = Json();
      out.push_back(std::move(v));
    }
  }
  return out;
}

void StabilityMap::write_artifacts(const Study& study, const ResultTable& results,
                                   const fs::path& out_dir) const {
  // Axes with one value are fixed parameters, not dimensions of the map.
  std::vector<std::size_t> varying;
  for (std::size_t a = 0; a < study.grid.size(); ++a)
    if (study.grid[a].values.size() > 1) varying.push_back(a);
  for (std::size_t a : varying)
    if (!numeric_axis(study.grid[a])) return;  // documented: no plot over non-numeric values
  Figures figures;
  if (varying.size() == 1) plot_curves(study, results, varying[0], out_dir, figures);
  if (varying.size() == 2) plot_maps(study, results, varying[0], varying[1], out_dir, figures);
  plot_closed_form_margins(study, results, varying, out_dir, figures);
  figures.finish();
  // A single point has nothing to draw; 3+ varying axes have no faithful 2-D picture: both are
  // documented, and results.csv holds every number.
}

bool StabilityMap::requires_serial(const Json& document) const {
  return model_is_serial(document.at("model"));
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::StabilityMap);
