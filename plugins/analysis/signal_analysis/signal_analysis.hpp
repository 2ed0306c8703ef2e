#pragma once
// Study kind `signal_analysis` ([study] kind = "signal_analysis"): reads one signal column from
// [input] (CSV/whitespace table, WAV, or a `simulate` study's timeseries.csv) and runs the
// analyses listed in [analysis] methods (registered analysis plugins, MODELS.md N and others) in
// order with a shared context, so later methods reuse the delay and dimension chosen earlier.
// Writes summary.json with the headline estimates (delay_samples, embedding_dimension,
// correlation_dimension, lyapunov_max_per_s, each with CI and quality) and every method's full
// result, and each method's plots. docs/analysis/chaos.md, section "Study kind".
//
//   [input]
//   file = "data/henon.csv"      # relative to the study file
//   column = "x"                 # header name or 1-based index
//   sample_rate_hz = 1.0         # required unless the file is WAV
//   [analysis]
//   methods = ["embedding", "correlation_dimension", "lyapunov"]
//   [analysis.lyapunov]          # optional overrides: that plugin's own parameters
//   max_reference_points = 2000
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {

class SignalAnalysis final : public StudyKind {
 public:
  static PluginInfo info();
  std::vector<std::string> tables() const override { return {"input", "analysis"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;

  // The series of a validated document (file re-read), named after its column.
  static SampledSeries load_series(const Json& input);
  // Runs the methods; returns the summary (headline estimates + "methods"). Plots go to
  // plot_dir when it is not empty.
  static Json analyse(const Json& point_document, const std::filesystem::path& plot_dir);
};

}  // namespace chatterlab
