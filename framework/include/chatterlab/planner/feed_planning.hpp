#pragma once
// The feed planner as study kinds use it (feed_plan, feed_risk): the study tables it reads
// ([machine], [part], [wheel], [plan]; docs/planner.md), one certified plan with its report files,
// and re-planning at another spindle speed. The planner's engine (generatrix analysis, schedules,
// tolerance, replay, controller output) stays inside the framework library.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <memory>

#include "chatterlab/params.hpp"
#include "chatterlab/planner/generatrix.hpp"
#include "chatterlab/planner/plan.hpp"

namespace chatterlab::planner {

// A real parameter > 0 (the planner kinds' settings).
inline ParamSpec positive_spec(std::string key, std::string unit, std::string description) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::real, std::move(unit), std::move(description));
  spec.min = 0.0;
  spec.min_exclusive = true;
  return spec;
}

// The [plan] table of a feed plan (segment lengths, tolerance, start-stop rate, wear sweep,
// controller tick).
std::vector<ParamSpec> feed_plan_settings_specs();

// Validates [machine] (a kinematics plugin plus the planner's rules), [part], [wheel] and [plan]
// of `document` and writes them back with defaults filled in; the wheel must fit the part and the
// machine reach every contact. Throws InputError naming the file, line, key and limit.
void validate_feed_plan_tables(Json& document, const SourceMap& sources);

// The generatrix of a validated [part] table (an expression, or a point table with its smoothing).
std::unique_ptr<Generatrix> build_generatrix(const Json& part);

// The machine's spindle range [from, to] of a validated [machine] (a single value: from = to).
std::pair<double, double> spindle_range_rpm(const Json& machine);

// What the feed_plan kind reports of one plan.
struct FeedPlanFigures {
  double total_time_s = 0.0, lower_bound_s = 0.0;
  std::size_t segments = 0;
  double max_profile_error_mm = 0.0, rms_profile_error_mm = 0.0;
  double max_edge_radius_mm = 0.0;
  bool schedule_certified = false;  // the motor rules after integerisation
  // The rules, the tolerance and zero interference all hold in the replay.
  bool certified = false;
  std::vector<std::string> certification_failures;
};

// Plans a validated feed_plan document; with a directory, writes pulses.csv, segments.csv,
// program.ngc, steps.csv, summary.json and (plots) the figures there. Throws PointFailure when no
// plan exists; an uncertified plan is returned (and written) with certified = false.
FeedPlanFigures plan_and_report(const Json& document, const std::filesystem::path& dir, bool plots);

// The validated tables a plan comes from.
struct PlanTables {
  Json machine, part, wheel, plan;
};
// The planner's plan at a spindle speed (without its reports), with where each segment runs on
// the part. Throws PointFailure naming the speed when no plan exists.
struct PlannedFeed {
  FeedPlan plan;
  std::vector<SegmentConditions> segments;
};
PlannedFeed plan_feed_at(const PlanTables& tables, double spindle_speed_rpm);

}  // namespace chatterlab::planner
