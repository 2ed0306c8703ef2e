#pragma once
// Study kind `feed_plan` ([study] kind = "feed_plan"): a certified time-optimal pulse schedule for
// grinding a solid of revolution on the three-table stepper machine (MODELS.md P1-P7), with its
// error analysis, wheel limits and wear distribution. User documentation: docs/planner.md.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/study_kind.hpp"

namespace chatterlab::planner {

class FeedPlanKind final : public StudyKind {
 public:
  static PluginInfo info();
  std::vector<std::string> tables() const override { return {"machine", "part", "wheel", "plan"}; }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document,
                              const PointContext& context) const override;
};

}  // namespace chatterlab::planner
