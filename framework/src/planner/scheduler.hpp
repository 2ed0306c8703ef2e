#pragma once
// Time-optimal integer pulse schedule along a generatrix (MODELS.md P2, P4; docs/planner.md).
//
// 1. Knots x_0 = a < x_1 < ... < x_N = b about segment_length_mm apart (each interior knot moved
//    within +-25 % to where the rounding residues matter least); exact axis positions q_m(x_k)
//    from the kinematics (P4).
// 2. Integer positions P_m,k = round((q_m(x_k) - q_m(x_0)) / step): the rounding remainder is
//    carried (never accumulated), so at every segment end each axis is within half a step of
//    its target; pulses n_m,k = P_m,k+1 - P_m,k.
// 3. Segment speeds s_k = 1/duration_k: the greatest sequence meeting the per-segment bounds
//    (pulse rate, axial advance per spindle revolution) and the smoothness rule between
//    consecutive segments, found by forward/backward passes to a fixed point. All constraint
//    maps are monotone in s, so the feasible set is closed under componentwise max and the fixed
//    point is its greatest element: it minimises the total time sum 1/s_k for these knots.
// Smoothness rule for consecutive rates r (before) and r' (after) of one motor:
//    |r' - r| <= max(delta |r|, f_ss)
// i.e. the seed rule |r' - r| / |r| <= delta where the rate is meaningful, and a change of at
// most the start-stop rate f_ss (a stepper starts, stops or reverses within f_ss without losing
// steps) where it is not. A reversal (r, r' of opposite sign) is allowed with |r|, |r'| <= f_ss/2.
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/planner/generatrix.hpp"
#include "chatterlab/planner/plan.hpp"

namespace chatterlab::planner {

// The machine's rate rules (every motor): the smoothness rule above with delta and f_ss.
struct RateRules {
  double max_relative_rate_change = 0.1;  // delta
  double start_stop_rate_hz = 10.0;       // f_ss
};

// Defaults: MODELS.md P2's rules (300 rpm, 4 mm per 100 rev, delta 0.1, f_ss 10 pulses/s).
struct FeedConstraints {
  double spindle_speed_rpm = 300.0;
  double max_axial_advance_mm_per_100_rev = 4.0;
  double max_relative_rate_change = 0.1;  // delta
  double start_stop_rate_hz = 10.0;       // f_ss
  double max_axial_speed_mm_per_s() const {
    return max_axial_advance_mm_per_100_rev / 100.0 * spindle_speed_rpm / 60.0;
  }
  RateRules rate_rules() const { return {max_relative_rate_change, start_stop_rate_hz}; }
};

// Every segment and motor checked after integerisation, with the largest values used.
struct Certificate {
  bool ok = true;
  std::vector<double> max_pulse_rate_hz;     // per motor
  double max_axial_speed_mm_per_s = 0.0;
  double max_relative_rate_change = 0.0;     // largest |r'-r|/|r| where the relative rule applied
  double max_rate_change_at_low_rate_hz = 0.0;  // largest |r'-r| where the f_ss allowance applied
  std::size_t rate_changes_under_start_stop_allowance = 0;
  std::size_t reversals = 0;
  double max_position_drift_steps = 0.0;     // |integer - exact| position at segment ends
  std::vector<std::string> violations;       // empty when ok (first few listed)
  void add_violation(std::string what) {
    ok = false;
    if (violations.size() < 10) violations.push_back(std::move(what));
  }
};

struct Schedule {
  FeedPlan plan;
  std::vector<double> knots_mm;                   // x_k, k = 0..N
  std::vector<double> contact_on_tool_mm;         // contact coordinate s on the tool at the knots
  std::function<ToolContact(double)> tool_contact;  // s -> where on the tool (default {s, 0, 0})
  ToolContact contact_at(double s) const { return tool_contact ? tool_contact(s) : ToolContact{s, 0.0, 0.0}; }
  std::vector<std::vector<double>> target_mm;     // q_m(x_k) [k][m]
  double lower_bound_s = 0.0;                     // continuous relaxation (no smoothness)
  std::size_t smoothing_passes = 0;
  Certificate certificate;
};

// contact_on_tool(x) gives the contact's coordinate s on the tool along the path (nullptr: 0), and
// tool_contact(s) where that is on the tool (nullptr: s along the rails, no tilt: a cylindrical
// wheel's face). choose_knots: place each interior knot within +-25 % of its local nominal
// spacing where the axes' rounding residues move the tool least off the profile (false: the
// nominal knots). keep_first_segment: x_1 stays nominal (the seed's first segment, MODELS.md P8)
// even when knots are chosen. Throws std::domain_error when the constraints admit no plan (naming
// the constraint and where).
Schedule plan_feed_on_knots(const Generatrix& generatrix, const Kinematics& kinematics,
                            const FeedConstraints& constraints, const std::vector<double>& nominal_knots_mm,
                            const std::function<double(double)>& contact_on_tool = nullptr,
                            bool choose_knots = true,
                            const std::function<ToolContact(double)>& tool_contact = nullptr,
                            bool keep_first_segment = true);

// Knots a = x_0 < ... < x_N = b equally spaced, at most segment_length_mm apart.
std::vector<double> uniform_knots(double a, double b, double segment_length_mm);

// plan_feed_on_knots on uniform_knots.
Schedule plan_feed(const Generatrix& generatrix, const Kinematics& kinematics,
                   const FeedConstraints& constraints, double segment_length_mm,
                   const std::function<double(double)>& contact_on_tool = nullptr,
                   bool choose_knots = true,
                   const std::function<ToolContact(double)>& tool_contact = nullptr);

// The exact axis positions (P4 inverse kinematics) of the contact at x, with its place on the
// tool.
struct ExactTarget {
  double x_mm = 0.0, contact_on_tool_mm = 0.0;
  std::vector<double> positions_mm;
};
ExactTarget exact_target(const Generatrix& generatrix, const Kinematics& kinematics,
                         const std::function<double(double)>& contact_on_tool,
                         const std::function<ToolContact(double)>& tool_contact, double x_mm);

// The parts of the scheduler that do not depend on the geometry (shared by feed_plan and
// cam_plan, MODELS.md P2/K2):
//
// Integer pulses from exact axis targets target_mm[k][m] (k = 0..N): positions rounded from the
// cumulative targets, remainders carried; sets plan.initial_position_mm = target_mm[0].
void quantise_targets(FeedPlan& plan, const std::vector<std::vector<double>>& target_mm);

// Time-optimal durations for the plan's integer pulses: the greatest speeds s_k = 1/duration_k
// with s_k <= speed_cap[k] (the path's own rule: axial advance, cam speed), every motor's pulse
// rate, starts, stops and reversals, and the smoothness rule between consecutive segments;
// periodic: the last segment is also followed by the first (a cam ground revolution after
// revolution). Sets start_s and duration_s; returns the number of smoothing passes. Throws
// std::domain_error("segment k: ...") when a segment admits no speed.
struct NoAdmissibleSpeed : std::domain_error {
  explicit NoAdmissibleSpeed(std::size_t k)
      : std::domain_error("segment " + std::to_string(k) + ": no admissible speed"), segment(k) {}
  std::size_t segment;
};
std::size_t time_optimal_durations(FeedPlan& plan, const std::vector<double>& speed_cap,
                                   const RateRules& rules, bool periodic = false);

// Continuous relaxation: every segment at the largest speed its own bounds allow (speed_cap and
// the pulse rate of the exact, unrounded axis travel), no smoothness: a lower bound on the time.
double relaxed_time_bound(const FeedPlan& plan, const std::vector<double>& speed_cap,
                          const std::vector<std::vector<double>>& target_mm);

// Certificate of the motor rules after integerisation: pulse rate, smoothness (with the pair
// last -> first when periodic), position drift against target_mm at segment ends.
Certificate certify_motor_rules(const FeedPlan& plan, const std::vector<std::vector<double>>& target_mm,
                                const RateRules& rules, bool periodic = false);

// Pre-motion (P2: "the plan starts after a short pre-motion"): segments of a ramp from rest to
// the first segment's rates (all rates scaled by f_ss / max|r|, then by 1 + delta per segment);
// the run-out mirrors it.
std::size_t ramp_segments(const FeedPlan& plan, const RateRules& rules);

// Signed normal distance of the tool from the generatrix (positive: material left).
double tool_deviation_mm(const ToolInPart& tool, const Generatrix& generatrix);

// Re-checks a plan against the constraints (used by plan_feed and the tests).
Certificate certify(const Schedule& schedule, const FeedConstraints& constraints);

}  // namespace chatterlab::planner
