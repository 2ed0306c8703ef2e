#pragma once
// Study kind `doe` ([study] kind = "doe"): range analysis and ANOVA of an orthogonal-array
// experiment read from a table (MODELS.md S4), and optional least-squares regression fits of a
// single-factor experiment. Tables [input], [doe], [regression]; docs/analysis/doe.md is the user
// documentation.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/study_kind.hpp"

namespace chatterlab {

class DoeKind final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override { return {"input", "doe", "regression"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
};

}  // namespace chatterlab
