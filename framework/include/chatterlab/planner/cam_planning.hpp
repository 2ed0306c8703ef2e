#pragma once
// The cam planner (MODELS.md K2, K3) as the cam_plan study kind uses it: tangent-point tracking of
// a fitted closed profile on a cam-grinding machine (Kinematics::cam_grinding()), integer pulses
// per motor per segment under every machine rule, the replayed profile and lift errors, and the
// controller output read back. docs/planner.md, section "Cams".
#include <cstddef>
#include <string>
#include <vector>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/planner/parametric_spline.hpp"
#include "chatterlab/planner/plan.hpp"

namespace chatterlab::planner {

// The planner's rules in [machine] (the kinematics plugin does not know them): cam_speed_rpm,
// max_relative_rate_change.
std::vector<ParamSpec> cam_machine_rule_specs();
// The [plan] table of a cam plan: segment_angle_deg, start_stop_rate_hz, controller_tick_hz.
std::vector<ParamSpec> cam_plan_settings_specs();

// K3's lift requirements on the ground surface.
inline constexpr double cam_total_lift_error_limit_mm = 0.015;
inline constexpr double cam_per_degree_lift_error_limit_mm = 0.004;

struct CamPlan {
  std::size_t segments = 0;
  FeedPlan plan;                             // pulses per motor (rotary, slide) per segment
  std::vector<std::vector<double>> targets;  // exact axis positions at the segment ends (C unwrapped)
  std::size_t smoothing_passes = 0;
  double total_time_s = 0.0, lower_bound_s = 0.0;
  double max_c_speed_deg_per_s = 0.0, c_speed_limit_deg_per_s = 0.0;
  bool rules_ok = false;
  std::vector<std::string> rule_violations;
  Json certificate;  // the motor rules and the C-speed path rule (summary.json "certificate")
  std::size_t ramp_segments = 0;
  double ramp_time_s = 0.0;
  // Replay of every pulse state: normal profile error, and the lift error of the surface the
  // wheel leaves per 0.1 deg of cam angle (the deepest state), its largest change per degree.
  std::size_t replayed_states = 0;
  double max_profile_error_mm = 0.0, rms_profile_error_mm = 0.0;
  std::vector<double> lift_bin_angle_deg, lift_error_mm;
  double max_lift_error_mm = 0.0, max_per_degree_lift_error_mm = 0.0;
  bool meets_requirements = false;
  // Tightest concave radius of the fitted profile (+inf: convex) and where.
  double min_concave_radius_mm = 0.0, min_concave_radius_at_deg = 0.0;
  // program.ngc and steps.csv, read back; the step table's states replayed.
  double tick_hz = 0.0;
  std::string gcode, step_table;
  Json controller_round_trip;  // the read-back checks (summary.json controller_export.round_trip)
  double shortest_step_interval_s = 0.0;
  bool controller_exact = false;
  // Every rule after integerisation, the lift requirements and the exact controller read-back.
  bool certified = false;
  std::vector<std::string> certification_failures;
};

// Plans one revolution of the cam profile `spline` on `kinematics` (a cam-grinding machine) with
// the validated [machine] rules and [plan] settings. Throws PointFailure when no admissible speed
// exists at some contact angle.
CamPlan plan_cam(const ParametricSpline& spline, const Kinematics& kinematics, const Json& machine,
                 const Json& plan_settings);

}  // namespace chatterlab::planner
