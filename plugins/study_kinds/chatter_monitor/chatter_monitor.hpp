#pragma once
// Study kind `chatter_monitor` ([study] kind = "chatter_monitor"): runs the chatter detectors of
// MODELS.md C1-C3 over one recorded or simulated signal, as a monitor would in real time (every
// score uses only samples up to its time), and reports when each raises its alarm.
//
//   [input]   file = "...", column = "...", sample_rate_hz = ...  (optional for WAV files and for
//             tables with a uniformly spaced t_s column, e.g. a `simulate` study's timeseries.csv)
//   [monitor] snapshot_times_s = [...]                            (optional)
//             series_csv = "auto" | "always" | "never"            (alarms.csv, features.csv)
//   [monitor.bp_network]  parameters of the bp_network plugin      (present = detector enabled)
//   [monitor.rbf_density] parameters of the rbf_density plugin     (present = detector enabled)
//
// Writes summary.json, network_weights.json (when trained), plots and, for signals of up to 10^6
// samples unless series_csv says otherwise, alarms.csv and features.csv (streamed).
// docs/analysis/monitoring.md is the user documentation.
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {

class ChatterMonitor final : public StudyKind {
 public:
  static constexpr const char* detector_names[] = {"bp_network", "rbf_density"};

  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"input", "monitor"}; }
  std::vector<NestedAnalyses> nested_analyses() const override {
    return {{"monitor", {std::begin(detector_names), std::end(detector_names)}}};
  }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
};

// The [input] signal of a validated document (file resolved, sample rate known).
SampledSeries monitor_input_signal(const Json& input);

}  // namespace chatterlab
