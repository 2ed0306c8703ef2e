#pragma once
// Study kind `compliance_chart` ([study] kind = "compliance_chart"): the stability chart of book
// fig 2-4 (MODELS.md G1 eq 2-21). On s = j w the characteristic equation 2-16 splits into
// Re H(jw) = -(1/2)(2/kc + 1/kg + 1/kw) (the process line eta) and an imaginary part fixed by the
// speeds; if the machine compliance curve H(jw) never reaches the line, no root can cross the
// imaginary axis: stable at every wheel and work speed (kc counts double). For every model with a
// G1 stiffness chain and a structural compliance (Model::stiffness_chain(),
// Model::structural_compliance(): plunge_regenerative, thompson). Per point: the leftmost point
// of the compliance curve, the line, and whether they meet; a single-point study also writes
// chart.csv and the chart plot. docs/models/closed_forms.md.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"

namespace chatterlab {

struct ComplianceChart {
  double leftmost_real_m_per_n = 0.0;  // min over 0 <= w <= band of Re H(jw)
  double leftmost_frequency_hz = 0.0;
  double process_line_m_per_n = 0.0;   // -(1/2)(2/kc + 1/kg + 1/kw), chains that are on
  bool intersects = false;             // leftmost_real < process_line
  std::vector<double> frequency_hz, real_m_per_n, imag_m_per_n;  // the curve
};

// The chart of a model's stiffness chain and structural compliance over 0..max_frequency_hz,
// `points` samples (the minimum refined by golden section between the samples next to the
// smallest).
ComplianceChart compliance_chart(const StiffnessChain& chain, const StructuralCompliance& compliance,
                                 double max_frequency_hz, int points);

// The [chart] table.
struct ComplianceChartSettings {
  std::optional<double> max_frequency_hz;  // default: 4 x the highest structural mode
  int points = 20000;
};
const ParamTable<ComplianceChartSettings>& compliance_chart_settings_table();

class ComplianceChartKind final : public StudyKind {
 public:
  static PluginInfo info();
  std::vector<std::string> tables() const override { return {"model", "chart"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document, const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
