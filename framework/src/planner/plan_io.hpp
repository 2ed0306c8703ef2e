#pragma once
// One feed_plan run: the schedule and everything reported about it; its files (pulses.csv,
// segments.csv, summary.json, plots) and the reader of saved plans (chatterlab/planner/plan.hpp).
#include <filesystem>
#include <memory>
#include <string>

#include "planner/controller_export.hpp"
#include "planner/replay.hpp"
#include "planner/setup.hpp"

namespace chatterlab::planner {

// The interpolating spline's plan beside the smoothed one (measured point tables): what the
// measurement noise would cost if it were ground in.
struct NoiseEffect {
  bool planned = false;
  std::string failure;  // why no plan, when planned = false
  double total_time_s = 0.0, max_profile_error_mm = 0.0, max_edge_radius_mm = 0.0;
  std::size_t reversals = 0, segments = 0;
  bool tolerance_met = false;
};

struct PlanRun {
  std::unique_ptr<Generatrix> generatrix;  // what the plan follows (the smoothed curve of a table)
  PartGeometry part;                       // the part's table, fit and interpolating spline
  GeometryAnalysis geometry;
  std::unique_ptr<Kinematics> kinematics;
  FeedConstraints constraints;
  WearSweep sweep;
  ToleranceSettings tolerance_settings;
  TolerancePlan tolerance;  // the schedule, its replay and how the tolerance was met
  Schedule& schedule = tolerance.schedule;
  ProfileErrors& errors = tolerance.errors;
  EdgeRadiusLimit edge_limit;             // from the part (+inf: nothing limits it)
  double wheel_edge_radius_limit_mm = 0.0;  // from the wheel's own geometry
  // Reported max_edge_radius_mm: the part's limit where the part sets one (concave part or a
  // distant part of the profile), otherwise the wheel's own limit; what limits it.
  double max_edge_radius_mm = 0.0;
  std::string max_edge_radius_limited_by;
  Interference interference;
  WearDistribution wear;
  std::size_t ramp_segments = 0;  // pre-motion ramp from rest (and, mirrored, the run-out)
  double ramp_time_s = 0.0;
  NoiseEffect noise;  // smoothed point tables only
  // program.ngc and steps.csv, read back; both replayed through the forward kinematics.
  ControllerExport controller;
  double gcode_replay_max_error_mm = 0.0;
  StepTableReplay step_replay;
  // Certified: the motor rules, the tolerance and zero interference all hold in the replay.
  bool certified = false;
  std::vector<std::string> certification_failures;

  PlanRun() = default;
  PlanRun(const PlanRun&) = delete;
  PlanRun& operator=(const PlanRun&) = delete;
};

// Plans the validated feed_plan document into `run`. Throws PointFailure when no plan exists.
void compute_plan(const Json& document, PlanRun& run);

// pulses.csv, segments.csv, program.ngc and steps.csv (with their round trip), summary.json and
// the plots.
void write_plan_files(const PlanRun& run, const Json& document, const std::filesystem::path& dir,
                      bool plots);

// profile, error_along_x, pulse_rates (and wear_histogram with a sweep) in dir; failures are
// appended to `failures` (a JSON array of messages).
void draw_plan_plots(const PlanRun& run, const Json& document, const std::filesystem::path& dir,
                     Json& failures);

// A certificate as JSON: the motor rules (shared by feed_plan and cam_plan) and the kind's own
// path rule entries (`path_rule`: what it is, the largest value used, the limit).
Json certificate_json(const Certificate& c, const FeedPlan& plan, const RateRules& rules,
                      const Json& path_rule);

// The summary.json content (also what read_saved_plan reads back).
Json plan_summary(const PlanRun& run, const Json& document);

}  // namespace chatterlab::planner
