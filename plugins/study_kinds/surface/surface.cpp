#include "study_kinds/surface/surface.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>

#include "chatterlab/errors.hpp"
#include "chatterlab/kit/data.hpp"
#include "chatterlab/kit/output.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"
#include "chatterlab/signal_io.hpp"
#include "shared/metrology/surface_report.hpp"

namespace chatterlab::surface {
namespace fs = std::filesystem;

namespace {

// filtered.csv holds four numbers per sample (about 60 bytes of text): written by default up to
// 10^6 samples, above that only on request ([parameters] filtered_csv = "always").
const kit::OnRequestFile filtered_csv_file{
    "parameters", "filtered_csv",
    "filtered.csv (position, profile, waviness, roughness per sample)", 1'000'000};

// The kind's own [parameters] keys beside those the surface_profile analysis shares.
std::vector<ParamSpec> kind_parameter_specs() {
  std::vector<ParamSpec> specs = parameter_specs();
  specs.push_back(filtered_csv_file.spec());
  return specs;
}

// filtered.csv streamed: the same text csv_text gives, without holding it.
void write_filtered_csv(const fs::path& path, const SurfaceEvaluation& e, bool closed) {
  kit::write_csv_streamed(path, {closed ? "angle_deg" : "x_mm", "profile_um", "waviness_um", "roughness_um"},
                          e.samples(), [&](std::size_t i, std::span<double> cells) {
                            cells[0] = e.position(i);
                            cells[1] = e.profile_um[i];
                            cells[2] = e.waviness_um[i];
                            cells[3] = e.roughness_um(i);
                          });
}

// Reports a violated limit: fail(key, message) throws InputError at the key's line.
using Fail = std::function<void(const std::string& key, const std::string& message)>;

// A closed profile: one revolution (samples_per_rev = rows), its cut-off in UPR.
void check_closed_keys(const Json& input, const Json& filter, const DataTable& table,
                       const fs::path& file, const Fail& fail) {
  if (input["samples_per_rev"].is_number_integer() &&
      static_cast<std::size_t>(input["samples_per_rev"].get<std::int64_t>()) != table.rows())
    fail("input.samples_per_rev",
         fmt::format("input.samples_per_rev = {}: {} has {} rows; a closed profile is exactly "
                     "one revolution",
                     input["samples_per_rev"].get<std::int64_t>(), file.string(), table.rows()));
  if (filter["cutoff_mm"].is_number() && filter["cutoff_upr"].is_number())
    fail("filter.cutoff_mm", "filter.cutoff_mm and filter.cutoff_upr: give one cut-off");
  if (filter["cutoff_mm"].is_number() && !input["spacing_mm"].is_number())
    fail("filter.cutoff_mm", "filter.cutoff_mm: a closed profile takes its cut-off in "
                             "undulations per revolution: use cutoff_upr (or give "
                             "input.spacing_mm, the circumferential spacing, to convert)");
}

// An open profile: a cut-off in mm and a spacing (spacing_mm or a uniform x column, agreeing
// when both are given).
void check_open_keys(const Json& input, const Json& filter, const DataTable& table,
                     const std::string& column, const SourceMap& sources, const Fail& fail) {
  if (input["samples_per_rev"].is_number())
    fail("input.samples_per_rev", "input.samples_per_rev needs closed = true (an open profile "
                                  "takes spacing_mm or x_column)");
  if (filter["cutoff_upr"].is_number())
    fail("filter.cutoff_upr", "filter.cutoff_upr needs closed = true (an open profile takes "
                              "cutoff_mm)");
  if (!filter["cutoff_mm"].is_number())
    fail("filter", "missing key 'filter.cutoff_mm': the cut-off wavelength of an open profile "
                   "(e.g. 0.8 or 2.5 mm)");
  if (!input["spacing_mm"].is_number() && !input["x_column"].is_string())
    fail("input", "missing key 'input.spacing_mm' (or input.x_column): the sample spacing of "
                  "an open profile");
  if (input["x_column"].is_string()) {
    check_uniform(table, input["x_column"].get<std::string>(), sources);
    if (input["spacing_mm"].is_number()) {
      const SampledSeries s = series_from(input, table, column);
      Json without_spacing = input;
      without_spacing["spacing_mm"] = nullptr;
      const double from_x = series_from(without_spacing, table, column).sample_interval;
      if (std::abs(from_x - s.sample_interval) > 1e-3 * from_x)
        fail("input.spacing_mm",
             fmt::format("input.spacing_mm = {} disagrees with the x column's spacing {} mm",
                         s.sample_interval, from_x));
    }
  }
}

}  // namespace

PluginInfo SurfaceStudy::info() {
  return plugin_info("surface", "W1, W2",
                     filter_specs(),  // the [filter] table; [input], [process], [parameters]: docs
                     {{"type", "gaussian"}, {"cutoff_mm", 0.8}},
                     "surface metrology of one profile: ISO Gaussian/robust filters, waviness and MOTIF "
                     "parameters, roundness about LS/MZ/MC/MI circles, Wz|f bands");
}

void SurfaceStudy::validate(Json& document, const SourceMap& sources) const {
  if (!document.contains("input"))
    throw InputError(fmt::format("{}: missing table [input] (file, column, spacing_mm or "
                                 "samples_per_rev with closed = true)",
                                 sources.locate("input").str()));
  kit::integer_columns_as_names(document["input"], {"column", "x_column"});
  Json input = validated_table(document, "input", input_specs(), sources);
  Json filter = validated_table(document, "filter", filter_specs(), sources);
  Json process = validated_table(document, "process", process_specs(), sources);
  Json parameters = validated_table(document, "parameters", kind_parameter_specs(), sources);
  const Fail fail = [&](const std::string& key, const std::string& what) {
    throw InputError(fmt::format("{}: {}", sources.locate(key).str(), what));
  };

  const fs::path file = kit::resolve_data_file(input["file"], "input.file", sources);
  input["file"] = file.string();
  // The run's parsed table itself, not a copy (a profile of 10^7 samples is 80 MB per column).
  std::shared_ptr<const DataTable> shared_table;
  try {
    shared_table = read_shared_data_table(file);
  } catch (const InputError& e) {
    fail("input.file", fmt::format("input.file: {}", e.what()));
  }
  const DataTable& table = *shared_table;
  const bool closed = input["closed"].get<bool>();
  if (input["x_column"].is_string()) {
    if (closed) fail("input.x_column", "input.x_column: closed profiles are sampled by angle "
                                       "(samples_per_rev); x_column is for open profiles");
    try {
      table.column(input["x_column"].get<std::string>());
    } catch (const InputError& e) {
      fail("input.x_column", fmt::format("input.x_column: {}", e.what()));
    }
  }
  const std::string column = profile_column(input, table, &sources);
  try {
    table.column(column);
  } catch (const InputError& e) {
    fail("input.column", fmt::format("input.column = \"{}\": {}", column, e.what()));
  }
  input["column"] = column;

  if (closed)
    check_closed_keys(input, filter, table, file, fail);
  else
    check_open_keys(input, filter, table, column, sources, fail);
  if (process["wheel_speed_rpm"].is_number() && !closed)
    fail("process.wheel_speed_rpm", "process.wheel_speed_rpm: Wz|f bands need a closed "
                                    "(circumferential) profile, closed = true");
  check_process(process, "process.", fail);

  document["input"] = input;
  document["filter"] = filter;
  document["process"] = process;
  document["parameters"] = parameters;
  // The filter checks on the real series: samples per cut-off, cut-off against profile length.
  try {
    Json ignored;
    resolve_filter(series_from(input, table, column), settings_from(document, table.rows()),
                   ignored);
  } catch (const InputError& e) {
    fail(closed ? "filter.cutoff_upr" : "filter.cutoff_mm", e.what());
  }
}

std::vector<std::string> SurfaceStudy::output_columns(const Json& document) const {
  std::vector<std::string> columns{"Wa_um", "Wq_um", "Wz_um", "Wt_um", "Wz_five_um"};
  if (document.at("input").at("closed").get<bool>()) {
    columns.emplace_back("RONt_um");
    columns.emplace_back("RONt_minimum_zone_um");
  }
  return columns;
}

std::vector<Json> SurfaceStudy::run_point(const Json& point_document,
                                          const PointContext& context) const {
  const Json& input = point_document.at("input");
  const std::shared_ptr<const DataTable> table = read_shared_data_table(input.at("file").get<std::string>());
  const std::string column = input.at("column").get<std::string>();
  const SampledSeries series = series_from(input, *table, column);  // a view of the table's column
  const SurfaceEvaluation e =
      evaluate_surface_profile(series, settings_from(point_document, series.values.size()));
  const Json& s = e.summary;
  std::vector<Json> out{s["Wa_um"], s["Wq_um"], s["Wz_um"], s["Wt_um"], s["Wz_five_um"]};
  if (series.closed) {
    out.push_back(s["RONt_um"]);
    out.push_back(s["roundness"]["minimum_zone"]["RONt_um"]);
  }
  if (context.artifact_dir.empty()) return out;

  const fs::path& dir = context.artifact_dir;
  Json summary = s;
  const std::string filtered_csv = point_document.at("parameters").at("filtered_csv").get<std::string>();
  if (const auto skipped = filtered_csv_file.skipped(filtered_csv, e.samples()))
    summary["filtered_csv"] = *skipped;
  else
    write_filtered_csv(dir / "filtered.csv", e, series.closed);
  if (series.closed && point_document.at("filter")["cutoff_mm"].is_number()) {
    summary["filter"]["cutoff_mm"] = point_document.at("filter")["cutoff_mm"];
    summary["filter"]["circumference_mm"] =
        static_cast<double>(series.values.size()) * input.at("spacing_mm").get<double>();
  }
  if (context.plots) {
    const std::string title = column;
    std::string errors;
    auto attempt = [&](auto&& draw) {
      try {
        draw();
      } catch (const std::exception& err) {
        errors += (errors.empty() ? "" : "; ") + std::string(err.what());
      }
    };
    attempt([&] { plot_profiles(e, series.closed, title, dir); });
    if (series.closed) attempt([&] { plot_polar(e, title, dir); });
    if (s.contains("Wz_f")) attempt([&] { plot_bands(e, title, dir); });
    if (!errors.empty()) summary["plot_errors"] = errors;
  }
  write_json_file(dir / "summary.json", summary);
  return out;
}

void SurfaceStudy::write_artifacts(const Study& study, const ResultTable& results,
                                   const fs::path& out_dir) const {
  // Figures of one profile are drawn by run_point next to its summary.json. A grid over one
  // numeric key (e.g. filter.cutoff_upr) also gets the parameters against that key.
  std::vector<std::size_t> varying;
  for (std::size_t a = 0; a < study.grid.size(); ++a)
    if (study.grid[a].values.size() > 1) varying.push_back(a);
  if (varying.size() != 1) return;
  const std::size_t axis = varying.front();
  for (const auto& v : study.grid[axis].values)
    if (!v.is_number()) return;
  plot::Curves curves;
  curves.title = "surface parameters against " + study.grid[axis].key;
  curves.x_label = study.grid[axis].key;
  curves.y_label = "parameter [um]";
  for (std::size_t c = 0; c < results.output_columns.size(); ++c) {
    plot::Series series{results.output_columns[c], {}, {}, "linespoints"};
    for (const auto& row : results.rows) {
      const Json& y = row[results.grid_columns.size() + c];
      if (!y.is_number()) continue;  // failed point: listed in results.csv
      series.x.push_back(row[axis].get<double>());
      series.y.push_back(y.get<double>());
    }
    curves.series.push_back(std::move(series));
  }
  plot::render(curves, out_dir, "parameters");
}

}  // namespace chatterlab::surface

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::surface::SurfaceStudy);
