#pragma once
// Plans to a profile tolerance (docs/planner.md, "Plans to a tolerance"): segment lengths adapt to
// the curvature of the axis paths and the contact's motion on the wheel until the replayed normal
// profile error is within max_profile_error_mm, or the planner says what stops it.
//
// 1. Segmentation. Inside a segment every axis moves linearly (pulses spread evenly), so the
//    contact leaves the profile by the chord error of the axis paths: for a probe segment of
//    length l around x, e(x, l) (forward kinematics of the linearly interpolated exact targets at
//    1/4, 1/2, 3/4, against the generatrix) grows like c(x) l^2. The allowed length is
//    L(x) = sqrt(share * tolerance / c(x)), clamped to [min_segment_length, segment_length], and
//    the knots are placed with density 1/L(x) (equally spaced where nothing binds).
// 2. Replay (MODELS.md P7) of the quantised, scheduled plan: every segment whose replayed error
//    exceeds the tolerance is split in two while its linearisation part still matters (and once,
//    in the first round, where its motor steps dominate: the new knot may round better), and the
//    plan is scheduled and replayed again.
// 3. The result is met, or not met with the achieved error and what limits it: the motor steps
//    (the quantisation part alone exceeds the tolerance: no segmentation helps), the shortest
//    allowed segment, or the number of rounds.
#include <functional>
#include <string>
#include <vector>

#include "planner/replay.hpp"

namespace chatterlab::planner {

struct ToleranceSettings {
  double max_profile_error_mm = 0.005;
  double segment_length_mm = 0.2;       // longest segment
  double min_segment_length_mm = 0.005;  // shortest segment
  double linearisation_share = 0.25;    // of the tolerance, for the first segmentation
  int max_rounds = 8;                   // schedule + replay rounds
};

struct TolerancePlan {
  Schedule schedule;
  ProfileErrors errors;
  std::vector<double> nominal_knots_mm;  // before the knot choice moved them (+-25 % locally)
  bool met = false;
  int rounds = 0;                    // schedule + replay rounds run
  std::size_t segments_split = 0;    // by the replay rounds
  bool first_knot_chosen = false;    // x_1 moved off the seed's place for the tolerance
  std::string limited_by;            // when not met: motor_step, min_segment_length, rounds
  std::string limit_note;            // what that means here (achieved error, where)
  double shortest_segment_mm = 0.0, longest_segment_mm = 0.0;
  std::size_t binding_segments = 0;  // segments whose replayed error uses >= 90 % of the tolerance
};

// The chord error of one segment: the largest |normal deviation| of the contact with the axes
// interpolated linearly between the exact targets of its ends (u = 1/4, 1/2, 3/4).
double chord_error_mm(const Generatrix& generatrix, const Kinematics& kinematics,
                      const std::function<ToolContact(double)>& tool_contact, const ExactTarget& from,
                      const ExactTarget& to);

// Step 1: the nominal knots for a linearisation budget (mm).
std::vector<double> tolerance_knots(const Generatrix& generatrix, const Kinematics& kinematics,
                                    const std::function<double(double)>& contact_on_tool,
                                    const std::function<ToolContact(double)>& tool_contact,
                                    double budget_mm, double segment_length_mm,
                                    double min_segment_length_mm);

// Steps 1-3. Throws std::domain_error as plan_feed when the constraints admit no plan.
TolerancePlan plan_to_tolerance(const Generatrix& generatrix, const Kinematics& kinematics,
                                const FeedConstraints& constraints, const ToleranceSettings& settings,
                                const std::function<double(double)>& contact_on_tool = nullptr,
                                const std::function<ToolContact(double)>& tool_contact = nullptr);

}  // namespace chatterlab::planner
