#pragma once
// Study kind `feed_risk` ([study] kind = "feed_risk"): chatter risk of a feed plan (issue 5,
// MODELS.md P + G1/G3/G4/S2). The plan is planned in the same study ([machine], [part], [wheel],
// [plan] as for feed_plan) or read from a saved feed_plan run ([feed_risk] plan_dir); the
// [model] (plunge_regenerative) is mapped segment by segment to local G1 parameters; outputs the
// rightmost root per segment, the accumulated amplification, the risk class, a time-domain
// simulation along the whole schedule and, with [feed_risk.optimise], a chatter-aware plan.
// User documentation: docs/feed_risk.md.
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/study_kind.hpp"

namespace chatterlab::feed_risk {

class FeedRiskKind final : public StudyKind {
 public:
  static PluginInfo info();
  std::vector<std::string> tables() const override {
    return {"model", "stability", "feed_risk", "machine", "part", "wheel", "plan"};
  }
  void validate(Json& document, const SourceMap& sources) const override;
  std::vector<std::string> output_columns(const Json& document) const override;
  std::vector<Json> run_point(const Json& point_document, const PointContext& context) const override;
};

}  // namespace chatterlab::feed_risk
