#pragma once
// Study kind `simulate` ([study] kind = "simulate"): integrates the [model]'s time-domain form
// with the dynamics engine (chatterlab/dynamics.hpp) under the [simulation] settings and reports
// the fitted growth rate, the dominant frequency, the largest displacement and the fraction of
// time out of contact. A single point also writes timeseries.csv, surface snapshots, spectrum.csv,
// summary.json and plots into its artefact directory (grid points only with write_point_files).
// The final work surface is evaluated for waviness and roundness (the surface metrology's
// `surface_profile` analysis, settings in the optional [surface] table): summary.json
// "work_surface_quality", results.csv work_waviness_wt_um, work_waviness_wz_um,
// work_roundness_ront_um.
// docs/studies.md, section "simulate", and docs/dynamics.md are the user documentation.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {

class Simulate final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"model", "simulation", "surface"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document, const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
  bool requires_serial(const Json& document) const override;

  // The engine settings of a validated document ([simulation] + the model's nominal speeds).
  static SimulationSettings settings(const Json& document, const TimeDomainModel& model);

 private:
  // The optional [surface] table (part quality of the final work surface).
  static void validate_surface(Json& document, const SourceMap& sources);
};

}  // namespace chatterlab
