#pragma once
// A feed plan (MODELS.md P4, issue 4): integer pulse counts per motor per time segment, pulses
// spread evenly inside each segment, starting from the exact P4 positions of the first contact
// point. This is what `feed_plan` writes (pulses.csv + summary.json) and what later studies (chatter
// risk along the plan) read back with read_saved_plan().
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::planner {

struct PlanSegment {
  double start_s = 0.0, duration_s = 0.0;
  std::vector<std::int64_t> pulses;  // signed count per motor (FeedPlan::motors order)
};

struct FeedPlan {
  std::vector<MotorAxis> motors;
  std::vector<double> initial_position_mm;  // per motor, before the first segment
  double spindle_speed_rpm = 0.0;           // work spindle, constant over the plan
  std::vector<PlanSegment> segments;

  double total_time_s() const;
  // Axis positions (mm) after `segment_count` segments: initial + cumulative pulses * step.
  std::vector<double> positions_after(std::size_t segment_count) const;
};

// Where a plan runs on the part, segment by segment: what a process model needs (chatter risk).
struct SegmentConditions {
  double start_s = 0.0, duration_s = 0.0;
  double x_start_mm = 0.0, x_end_mm = 0.0;  // axial contact position at the segment's ends
  double radius_mm = 0.0;                   // local work radius f(x) at the segment's middle
  double axial_speed_mm_per_s = 0.0;        // (x_end - x_start) / duration
  double spindle_speed_rpm = 0.0;
  double contact_on_wheel_mm = 0.0;         // contact position on the wheel face (wear sweep)
};

// A plan saved by `feed_plan` in `dir` (pulses.csv, summary.json), with the per-segment
// conditions recovered by replaying the pulses through the saved machine's forward kinematics.
struct SavedPlan {
  FeedPlan plan;
  Json machine;  // the validated [machine], [part], [wheel] tables of the run that wrote it
  Json part;
  Json wheel;
  std::vector<SegmentConditions> segments;
};

// Throws InputError naming the file and the problem (missing file, missing column or key,
// pulses that are not integers, a motor count that does not match the machine).
SavedPlan read_saved_plan(const std::filesystem::path& dir);

}  // namespace chatterlab::planner
