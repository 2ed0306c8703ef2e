#include "study_kinds/feed_plan/feed_plan.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/planner/feed_planning.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab::planner {

namespace {

constexpr const char* columns[] = {"total_time_s", "lower_bound_s", "gap_percent", "segments",
                                   "max_profile_error_mm", "rms_profile_error_mm",
                                   "max_edge_radius_mm", "certified"};

}  // namespace

PluginInfo FeedPlanKind::info() {
  return plugin_info("feed_plan", "P1-P8",
                     feed_plan_settings_specs(),
                     {{"segment_length_mm", 0.2}},
                     "certified time-optimal stepper pulse schedule for a solid of revolution, with replayed "
                     "profile error, wheel limits and wear distribution");
}

void FeedPlanKind::validate(Json& document, const SourceMap& sources) const {
  validate_feed_plan_tables(document, sources);
}

std::vector<std::string> FeedPlanKind::output_columns(const Json& /*document*/) const {
  return {std::begin(columns), std::end(columns)};
}

std::vector<Json> FeedPlanKind::run_point(const Json& doc, const PointContext& context) const {
  const FeedPlanFigures f = plan_and_report(doc, context.artifact_dir, context.plots);
  // A plan that breaks a rule, misses the tolerance or lets the wheel cut in is never "ok": its
  // files are written (for inspection, `certified` false in summary.json) and the point fails.
  if (!f.certified)
    throw PointFailure(fmt::format("plan not certified: {}", fmt::join(f.certification_failures, "; ")));
  return {f.total_time_s,
          f.lower_bound_s,
          100.0 * (f.total_time_s - f.lower_bound_s) / f.lower_bound_s,
          static_cast<double>(f.segments),
          f.max_profile_error_mm,
          f.rms_profile_error_mm,
          f.max_edge_radius_mm,
          f.schedule_certified};
}

}  // namespace chatterlab::planner

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::planner::FeedPlanKind);
