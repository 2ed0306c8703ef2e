#pragma once
// Study kind `suppression_map` ([study] kind = "suppression_map"; MODELS.md S1-S3): at each grid
// point (typically suppression.amplitude_ratio x suppression.frequency_hz, optionally x
// suppression.shape) the [model] is simulated for n wheel revolutions with the [suppression]
// modulation, and compared with the same run at constant conditions (computed once per study and
// model, not per point). Outputs per point:
//   log10_amplitude_ratio       log10(A_n modulated / A_n constant), simulated (S2's measure)
//   s2_predicted_log10_ratio    the same from growth-rate averaging, 5-37 vs 5-38, with the
//                               rightmost root at the frozen conditions of each wheel revolution
//   s2_locked_lobe_log10_ratio  the same with the chatter pattern locked to its wave count (G3
//                               closed forms; wheel speed on a wheel-regenerative G1 only)
//   s2_phase_drift_rad          the approximation's small parameter (<< 1: 5-37 applies)
//   s3_energy_change            mean sin(phi) over the modulation periods in the run minus its
//                               constant-speed value: the energy per cycle of 5-45 in units of
//                               pi C' X^2 (< 0 helps)
//   s3_exciting_fraction        fraction of that time in the exciting zone 0 < phi < pi (5-40)
//   s1_frequency_swing_hz       range of the critical chatter frequency of 5-29 (corrected) as
//                               the modulation changes the relative thickness da/a
//   simulation_outcome          "completed" or "diverged"
// Heatmaps (per value of a string grid axis such as suppression.shape) use a diverging palette
// centred on "no effect". Any model works that has a characteristic function, a time-domain form
// and the process-conditions capability (chatterlab/process_conditions.hpp: the frozen modulated
// conditions); feed modulation with a thickness exponent also needs its G1 stiffness chain.
// docs/suppression.md is the user documentation.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"

namespace chatterlab {

class SuppressionMap final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"model", "suppression", "suppression_map"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document, const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
