#pragma once
// Study kind `stability_lobes` ([study] kind = "stability_lobes"): the lobe diagram of a [model]
// (any model with a stability route: a characteristic function, or a return difference for the
// Nyquist count): for every speed the critical value of one model parameter where a root crosses
// Re s = 0, traced along each lobe (lobe_tracer.hpp), the chatter frequency on the boundary, the
// boundary's sensitivity to the other model parameters, chatter-free windows, and optionally the
// time until chatter exceeds a waviness tolerance over speed x parameter (time_to_chatter.hpp).
// docs/studies.md, section "stability_lobes", is the user documentation.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"

namespace chatterlab {

class StabilityLobes final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"model", "lobes", "stability", "time_to_chatter"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document, const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab
