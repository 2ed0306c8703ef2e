#pragma once
// The tables, reading and figures of a profile evaluation (docs/analysis/surface.md), shared by
// the `surface` study kind (tables [input], [filter], [process], [parameters]) and the
// `surface_profile` analysis (the same keys, flat): one declaration of each key, one reader
// (settings_from), one set of figures.
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "chatterlab/analysis.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/signal_io.hpp"
#include "shared/metrology/surface.hpp"

namespace chatterlab::surface {

// The keys of each table (the analysis takes unit, filter, process and parameters keys flat).
ParamSpec unit_spec();
std::vector<ParamSpec> input_specs();
std::vector<ParamSpec> filter_specs();
std::vector<ParamSpec> process_specs();
std::vector<ParamSpec> parameter_specs();

// The table `name` of the document (empty when absent) validated against `specs`.
Json validated_table(const Json& document, const std::string& name,
                     const std::vector<ParamSpec>& specs, const SourceMap& sources);

// The [process] keys' joint limits, shared by the study kind and the analysis plugin: both
// speeds or none, bands [from, to] with from <= to. `prefix` is how the caller names the keys
// ("process." in a surface study, "" for the flat analysis parameters); fail(key, message).
template <class Fail>
void check_process(const Json& process, const std::string& prefix, Fail&& fail) {
  const bool wheel = process["wheel_speed_rpm"].is_number(), work = process["work_speed_rpm"].is_number();
  if (wheel != work)
    fail(prefix + "wheel_speed_rpm",
         fmt::format("Wz|f needs both {0}wheel_speed_rpm and {0}work_speed_rpm", prefix));
  for (const char* key : {"low_band_upr", "high_band_upr"}) {
    const Json& band = process[key];
    if (!band.is_array()) continue;
    if (band.size() != 2 || band[0].get<double>() > band[1].get<double>())
      fail(prefix + key,
           fmt::format("{}{} = {}: expected [from, to] with from <= to", prefix, key, band.dump()));
  }
}

// Profile values per micrometre: 1 (um), 1e3 (mm), 1e6 (m).
double unit_to_um(const std::string& unit);

// The profile column's name: as given, or the only column that is not the x column.
std::string profile_column(const Json& input, const DataTable& table, const SourceMap* sources);

// The profile of a validated [input] as a sampled series (by angle when closed, by x in mm when
// open: spacing_mm or the x column's mean step). A view of the table's column, valid while
// `table` lives (a 10^7-sample profile is not copied).
SampledSeries series_from(const Json& input, const DataTable& table, const std::string& column);
SampledSeries series_from(const Json& input, DataTable&& table, const std::string& column) = delete;

// The evaluation settings of a document holding the four tables. `rows`: the profile's samples;
// for a closed profile given with spacing_mm (circumferential spacing) and cutoff_mm, the
// cut-off becomes cutoff_upr = circumference / cutoff_mm.
SurfaceSettings settings_from(const Json& document, std::size_t rows = 0);

// Uniform spacing of an x column: every step within 0.1 % of the mean step (and increasing).
void check_uniform(const DataTable& table, const std::string& x_column, const SourceMap& sources);

// Figures: profile with waviness and roughness; polar roundness plot with the four reference
// circles; amplitude per UPR with the Wz|f bands.
void plot_profiles(const SurfaceEvaluation& e, bool closed, const std::string& title,
                   const std::filesystem::path& dir);
void plot_polar(const SurfaceEvaluation& e, const std::string& title,
                const std::filesystem::path& dir, const std::string& stem = "polar");
void plot_bands(const SurfaceEvaluation& e, const std::string& title,
                const std::filesystem::path& dir, const std::string& stem = "wz_f_bands");

}  // namespace chatterlab::surface
