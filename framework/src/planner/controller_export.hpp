#pragma once
// Controller output of a plan (docs/planner.md, "Controller output"): what a machine controller or
// a motion simulator reads, besides pulses.csv.
//
// - program.ngc: G-code (RS274/NGC as LinuxCNC and grbl read it). G21 G90 (mm, absolute), the
//   work spindle (S.. M3), a rapid G0 to the plan's start, then G93 (inverse-time feed): one
//   `G1 <axes> F..` per segment with every axis' absolute position at the segment's end and
//   F = 60 / duration_s (the move takes 1/F minutes), so that every axis moves linearly in time
//   over the segment, as the plan's evenly spread pulses do. Positions carry 9 decimals (far
//   below a step), F 12 significant digits. G94 M5 M2 at the end.
// - steps.csv: the step/direction timing table: `tick,motor,direction`, one row per step pulse in
//   time order; tick = round(t * tick_hz) with t the pulse time of the plan (pulse j of n in a
//   segment at start + (j - 1/2) duration / n); direction +1 moves the axis towards larger
//   positions. Ticks count from the plan's start (the first segment), 1 MHz by default.
//
// Both are read back here and the result compared with the plan (round trip): the G-code's
// positions rounded to steps give the plan's pulse counts, its F the durations; the step table's
// events give the plan's machine states, which the caller replays through the forward kinematics.
#include <cstdint>
#include <string>
#include <vector>

#include "chatterlab/planner/plan.hpp"

namespace chatterlab::planner {

// G-code letters per motor: three_table_revolution X (lower table), Y (middle table), Z (the
// upper table's nut: a linear axis, theta = atan(-Z/R), not a vertical axis); xc_cam C (degrees)
// and X; otherwise X, Y, Z, A, B, C, U, V, W in motor order.
std::vector<char> gcode_letters(const FeedPlan& plan);

// The G-code program; `comments` become comment lines at the top.
std::string gcode_program(const FeedPlan& plan, const std::vector<std::string>& comments);

// Reads a program written by gcode_program back into a plan with `like`'s motors: the start from
// the G0, every G1's end positions rounded to whole steps from the start, its duration 60 / F.
// Throws std::invalid_argument naming the line for anything else.
FeedPlan read_gcode_program(const std::string& text, const FeedPlan& like);

struct StepEvent {
  std::int64_t tick = 0;
  std::size_t motor = 0;
  int direction = 1;
};

std::vector<StepEvent> step_events(const FeedPlan& plan, double tick_hz);
std::string step_table_csv(const FeedPlan& plan, double tick_hz);
// Throws std::invalid_argument naming the line (unknown motor, direction not +-1, ticks not in
// order).
std::vector<StepEvent> read_step_table(const std::string& text, const FeedPlan& like);

// What the round trip found.
struct ExportCheck {
  bool gcode_pulses_identical = false;      // every segment's pulse counts equal the plan's
  double gcode_max_duration_error_s = 0.0;  // largest |duration from F - planned duration|
  std::size_t step_events = 0;
  bool step_positions_identical = false;    // axis positions at every segment end equal the plan's
  double step_max_time_error_s = 0.0;       // largest |tick / tick_hz - planned pulse time|
  double shortest_step_interval_s = 0.0;    // between two steps of one motor
  double shortest_direction_setup_s = 0.0;  // from a direction change to that motor's next step
};
ExportCheck check_export(const FeedPlan& plan, const FeedPlan& from_gcode,
                         const std::vector<StepEvent>& events, double tick_hz);

// Both files of a plan, read back and checked (what the study kinds write and report).
struct ControllerExport {
  double tick_hz = 1e6;
  std::string gcode, step_table;
  FeedPlan from_gcode;             // the program read back
  std::vector<StepEvent> events;   // the table read back
  ExportCheck check;
  bool exact() const { return check.gcode_pulses_identical && check.step_positions_identical; }
};
ControllerExport export_plan(const FeedPlan& plan, const std::vector<std::string>& comments, double tick_hz);

}  // namespace chatterlab::planner
