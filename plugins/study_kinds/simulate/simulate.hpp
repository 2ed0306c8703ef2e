#pragma once
// Study kind `simulate` ([study] kind = "simulate"): integrates the [model]'s time-domain form
// with the dynamics engine (chatterlab/dynamics.hpp) under the [simulation] settings (the study
// kit's simulation table, chatterlab/kit/simulation.hpp) and reports the fitted growth rate with
// its validity (fit_valid, fit_regime, fit_reason: chatterlab/fit_validity.hpp), the dominant
// frequency, the largest displacement and the fraction of time out of contact. A single point
// also writes timeseries.csv (or .npy), surface snapshots, spectrum.csv, summary.json and plots
// into its artefact directory (grid points only with write_point_files). The final work surface
// is measured for waviness and roundness by the analysis that has the profile-quality capability
// (Analysis::profile_quality(); the surface metrology's `surface_profile`), with its settings in
// the optional [surface] table: summary.json "work_surface_quality", results.csv
// work_waviness_wt_um, work_waviness_wz_um, work_roundness_ront_um.
// docs/studies.md, section "simulate", and docs/dynamics.md are the user documentation.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"
#include "chatterlab/time_series_file.hpp"

namespace chatterlab {

// The [simulation] table: the kit's simulation settings and the kind's own outputs.
struct SimulateSettings {
  kit::SimulationTable simulation;
  // The time-series file: timeseries.csv or timeseries.npy (long runs), every k-th sample.
  TimeSeriesFormat timeseries_format = TimeSeriesFormat::csv;
  std::size_t timeseries_decimation = 1;
  // rms of white Gaussian sensor noise added to x in timeseries.csv (measured_displacement_m).
  double measurement_noise_m = 0.0;
  bool write_point_files = false;  // grid points also write their files into points/<i>/
};
const ParamTable<SimulateSettings>& simulate_settings_table();

class Simulate final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"model", "simulation", "surface"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document, const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;

 private:
  // The optional [surface] table (part quality of the final work surface).
  static void validate_surface(Json& document, const SourceMap& sources);
};

}  // namespace chatterlab
