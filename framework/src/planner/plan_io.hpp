#pragma once
// One feed_plan run: the schedule and everything reported about it; its files (pulses.csv,
// segments.csv, summary.json, plots) and the reader of saved plans (chatterlab/planner/plan.hpp).
#include <filesystem>
#include <memory>

#include "planner/replay.hpp"
#include "planner/setup.hpp"

namespace chatterlab::planner {

struct PlanRun {
  std::unique_ptr<Generatrix> generatrix;
  std::unique_ptr<Kinematics> kinematics;
  FeedConstraints constraints;
  WearSweep sweep;
  Schedule schedule;
  ProfileErrors errors;
  EdgeRadiusLimit edge_limit;
  Interference interference;
  WearDistribution wear;
  std::size_t ramp_segments = 0;  // pre-motion ramp from rest (and, mirrored, the run-out)
  double ramp_time_s = 0.0;
};

// Plans the validated feed_plan document. Throws PointFailure when no plan exists.
PlanRun compute_plan(const Json& document);

void write_plan_files(const PlanRun& run, const Json& document, const std::filesystem::path& dir,
                      bool plots);

// profile, error_along_x, pulse_rates (and wear_histogram with a sweep) in dir; failures are
// appended to `failures` (a JSON array of messages).
void draw_plan_plots(const PlanRun& run, const Json& document, const std::filesystem::path& dir,
                     Json& failures);

// The summary.json content (also what read_saved_plan reads back).
Json plan_summary(const PlanRun& run, const Json& document);

}  // namespace chatterlab::planner
