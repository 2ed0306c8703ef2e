#pragma once
// Study kind `surface` ([study] kind = "surface"): reads one measured (or simulated) profile,
// filters it into waviness and roughness and writes filtered.csv, summary.json and plots.
// docs/analysis/surface.md is the user documentation (tables [input], [filter], [process],
// [parameters]; every key and output).
#include <filesystem>
#include <string>
#include <vector>

#include "shared/metrology/surface.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::surface {

class SurfaceStudy final : public StudyKind {
 public:
  static PluginInfo info();

  std::vector<std::string> tables() const override {
    return {"input", "filter", "process", "parameters"};
  }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
  void write_artifacts(const Study& study, const ResultTable& results,
                       const std::filesystem::path& out_dir) const override;
};

}  // namespace chatterlab::surface
