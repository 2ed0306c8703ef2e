#pragma once
// Study kind `stability_map` ([study] kind = "stability_map"): at every grid point the rightmost
// characteristic root of the [model] (MODELS.md G1 for plunge_regenerative), its growth rate,
// chatter frequency, growth per wheel revolution (G3) and a certificate that no root lies further
// right, plus the model's closed-form indicators (G2) when it has them. docs/studies.md, section
// "stability_map", is the user documentation. With a [suppression] table (a speed modulation,
// MODELS.md S2/S3) the growth rate is the Floquet exponent of the periodic linearisation
// (floquet_route.hpp); the `route` column says which route gave each point.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"

namespace chatterlab {

class StabilityMap final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"model", "stability", "suppression"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
