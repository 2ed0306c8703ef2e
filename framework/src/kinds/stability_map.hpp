#pragma once
// Study kind `stability_map` ([study] kind = "stability_map"): at every grid point the rightmost
// characteristic root of the [model] (MODELS.md G1 for plunge_regenerative), its growth rate,
// chatter frequency, growth per wheel revolution (G3) and a certificate that no root lies further
// right. docs/studies.md, section "stability_map", is the user documentation.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/registry.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {

class StabilityMap final : public StudyKind {
 public:
  // Default search band: |Im s| <= 2 pi * this multiple * the model's highest structural natural
  // frequency (CharacteristicFunction::natural_frequency_scale_hz). Regenerative chatter locks
  // onto a structural mode; at 4 x its frequency the structure's dynamic compliance is down to
  // about 1/15 of its static value, so roots beyond the band belong to the (stable) delay chains.
  static constexpr double default_band_multiple = 4.0;

  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"model", "stability"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                            const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
  bool requires_serial(const Json& document) const override;
};

}  // namespace chatterlab
