#pragma once
// The validated study tables turned into planner objects (shared by the feed_plan kind and the
// saved-plan reader).
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/planner/feed_planning.hpp"
#include "planner/scheduler.hpp"
#include "planner/smoothing_spline.hpp"
#include "planner/tolerance.hpp"
#include "planner/wear.hpp"
#include "planner/wheel_limits.hpp"

namespace chatterlab::planner {

// Keys of [machine] that the planner (not the kinematics plugin) owns.
inline constexpr const char* machine_constraint_keys[] = {
    "max_relative_rate_change", "spindle_speed_rpm", "max_axial_advance_mm_per_100_rev"};

// The motor rules shared by feed_plan and cam_plan: [machine] max_relative_rate_change (delta)
// and [plan] start_stop_rate_hz (f_ss, default delta x the slowest motor's top rate, so the
// allowance never permits more than the seed rule permits at full speed).
ParamSpec relative_rate_change_spec();
// [plan] controller_tick_hz: time resolution of steps.csv; default 100 ticks per step at the
// fastest motor's top rate, rounded up to a power of ten, at least 1 MHz.
ParamSpec controller_tick_spec();
double controller_tick_hz(const Json& plan, const std::vector<MotorAxis>& motors);
ParamSpec start_stop_rate_spec();
RateRules build_rate_rules(const Json& machine, const Json& plan, const Kinematics& kinematics);

std::unique_ptr<Kinematics> build_kinematics(const Json& machine);

// The part: the generatrix the plan follows and, for a point table, the table itself, the
// interpolating spline through it and the smoothing fit ([part] smoothing = "cross_validated"
// (default for tables), "tolerance" with smoothing_tolerance_mm, or "none"; docs/planner.md,
// "Measured parts"). Missing keys take their defaults (geometry_resolution_mm 0.01).
struct PartGeometry {
  std::unique_ptr<Generatrix> generatrix;
  double resolution_mm = default_geometry_resolution_mm;
  std::string smoothing = "none";  // what was applied: none, cross_validated, tolerance
  std::vector<double> table_x_mm, table_y_mm;    // point tables only
  std::unique_ptr<Generatrix> interpolating;     // smoothed tables: the spline through the raw points
  std::optional<SmoothingSpline> fit;            // smoothed tables
};
PartGeometry build_part(const Json& part);
FeedConstraints build_constraints(const Json& machine, const Json& plan,
                                  const Kinematics& kinematics);
WheelSection build_wheel(const Json& wheel);
// Where contact coordinate s (mm along the working surface) is on the wheel: nullptr for a
// cylindrical face (s along the rails); on a profiled wheel's edge arc of radius r, arc angle
// phi = s / r: {r sin phi, r (1 - cos phi), phi}.
std::function<ToolContact(double)> wheel_contact(const WheelSection& wheel);
// Half the length of the working surface a sweep may use: a/2 (face) or r alpha/2 (edge arc).
double sweep_half_width_mm(const WheelSection& wheel);
WearSweep build_sweep(const Json& plan, const Json& wheel);
double segment_length_mm(const Json& plan, const FeedConstraints& constraints);
// [plan] max_profile_error_mm (default 0.005), segment_length_mm (the longest segment),
// min_segment_length_mm (default 0.005).
ToleranceSettings build_tolerance(const Json& plan, const FeedConstraints& constraints);

}  // namespace chatterlab::planner

namespace chatterlab::planner {

// The machine of MODELS.md P2 (R = 300 mm, b = 250 mm, 12 mm screws, 10:1 gears, 1 deg steps,
// 100 pulses/s) as three_table_revolution parameters, and its rules (300 rpm, 4 mm per 100 rev,
// delta = 0.1, start-stop rate 10 pulses/s): the tests' and benchmarks' reference machine.
Json p2_machine_params();
FeedConstraints p2_constraints();

}  // namespace chatterlab::planner
