#pragma once
// Study kind `cam_plan` ([study] kind = "cam_plan"): X-C grinding of a cam from its lift table
// (MODELS.md K): closed cumulative-chord spline through chosen table rows (K1), adaptive insertion
// of rows until every row is fitted within a target (K3), tangent-point tracking on an X-C machine
// (K2, on any machine that declares the cam-grinding capability, e.g. xc_cam), integer pulses per motor per segment, replayed profile error.
// User documentation: docs/planner.md, section "Cams".
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/study_kind.hpp"

namespace chatterlab::planner {

class CamPlanKind final : public StudyKind {
 public:
  static PluginInfo info();
  std::vector<std::string> tables() const override { return {"machine", "part", "plan"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
};

}  // namespace chatterlab::planner
