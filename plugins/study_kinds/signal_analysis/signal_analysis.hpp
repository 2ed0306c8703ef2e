#pragma once
// Study kind `signal_analysis` ([study] kind = "signal_analysis"): reads one signal column from
// [input] (CSV/whitespace table, WAV, or a `simulate` study's timeseries.csv) and runs the
// analyses listed in [analysis] methods (registered analysis plugins, MODELS.md N and others) in
// order with a shared context, so later methods reuse the delay and dimension chosen earlier.
// Writes summary.json with the headline estimates (delay_samples, embedding_dimension,
// correlation_dimension, lyapunov_max_per_s or _per_sample without a sample rate, each with CI
// and quality), the verdict on chaos and every method's full result, and each method's plots.
// docs/analysis/chaos.md, section "Study kind".
//
//   [input]
//   file = "data/henon.csv"      # relative to the study file
//   column = "x"                 # header name or 1-based index
//   sample_rate_hz = 1.0         # optional: without it time is counted in samples
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

  // The series of a validated document (file re-read), named after its column; without a sample
  // rate its unit is "sample" (interval 1).
  static SampledSeries load_series(const Json& input);
  // Runs the methods; returns the summary (headline estimates, verdict, "methods"). Plots go to
  // plot_dir when it is not empty.
  static Json analyse(const Json& point_document, const std::filesystem::path& plot_dir);
  // The same for a series in memory and a validated [analysis] table (methods + their tables).
  static Json analyse_series(const SampledSeries& series, const Json& analysis,
                             const std::filesystem::path& plot_dir);
  // The verdict on chaos from the methods' results (keyed by method name):
  //   "deterministic chaos": a positive largest exponent whose interval excludes zero (from
  //     divergence curves that showed exponential divergence), a saturating correlation
  //     dimension, and surrogate tests rejecting a linear stochastic process for both;
  //   "linear stochastic": surrogates ran and none of their statistics rejects the null;
  //   "periodic or quasi-periodic": no exponential divergence;
  //   "noise-dominated": nonlinear structure (a statistic rejects) without a saturating
  //     dimension or common exponent, noise detected;
  //   "not determined": anything else. `reason` lists the evidence and what is missing.
  static Json chaos_verdict(const Json& context);
};

}  // namespace chatterlab
