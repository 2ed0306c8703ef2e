#pragma once
// Study kind `error_separation` ([study] kind = "error_separation"): roundness of a part and the
// spindle's error motion from two to eight displacement probes (MODELS.md E1-E5), and with a
// section column the cylindricity of the part (E6). Tables [input], [probes], [separation];
// docs/analysis/error_separation.md is the user documentation (keys, outputs, equations).
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/study_kind.hpp"

namespace chatterlab {

class ErrorSeparationKind final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"input", "probes", "separation"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
};

}  // namespace chatterlab
