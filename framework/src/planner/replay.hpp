#pragma once
// Replay of a quantised plan (MODELS.md P7, seed 004): every machine state the plan passes
// through (pulses spread evenly in each segment: pulse j of n at fraction (j - 1/2)/n) goes
// through the forward kinematics; the tool's deviation from the generatrix, measured along the
// profile normal, is the produced-profile error. The same instants replayed with the exact
// (unrounded) targets interpolated linearly in each segment give the linearisation part; the
// difference per state is the quantisation part.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <utility>
#include <vector>

#include "planner/scheduler.hpp"

namespace chatterlab::planner {

// Every machine state of a quantised plan: visit(k, u, positions) at the start of segment k
// (u = 0) and after each distinct pulse instant u in (0, 1) of segment k (a motor's n pulses
// spread evenly: pulse j at u = (j - 1/2) / n; simultaneous pulses form one state). The time of
// a state is start_s + u duration_s.
template <class Visit>
void for_each_pulse_state(const FeedPlan& plan, Visit&& visit) {
  std::vector<double> position(plan.initial_position_mm);
  std::vector<std::pair<double, std::size_t>> events;
  for (std::size_t k = 0; k < plan.segments.size(); ++k) {
    const PlanSegment& seg = plan.segments[k];
    events.clear();
    for (std::size_t m = 0; m < plan.motors.size(); ++m) {
      const std::int64_t n = std::llabs(seg.pulses[m]);
      for (std::int64_t j = 1; j <= n; ++j)
        events.emplace_back((static_cast<double>(j) - 0.5) / static_cast<double>(n), m);
    }
    std::sort(events.begin(), events.end());
    visit(k, 0.0, static_cast<const std::vector<double>&>(position));
    for (std::size_t i = 0; i < events.size(); ++i) {
      const std::size_t m = events[i].second;
      position[m] += (seg.pulses[m] > 0 ? 1.0 : -1.0) * plan.motors[m].mm_per_pulse;
      if (i + 1 < events.size() && events[i + 1].first == events[i].first) continue;
      visit(k, events[i].first, static_cast<const std::vector<double>&>(position));
    }
  }
}

// Every machine state of a step/direction timing table (controller_export.hpp): the axis
// positions after each tick that holds a step, visit(k, u, positions) with k the plan segment that
// holds the tick and u its fraction of that segment; first the start, visit(0, 0, initial).
template <class Event, class Visit>
void for_each_step_state(const FeedPlan& plan, const std::vector<Event>& events, double tick_hz, Visit&& visit) {
  std::vector<double> position(plan.initial_position_mm);
  std::size_t k = 0;
  auto at = [&](double time) {
    while (k + 1 < plan.segments.size() && plan.segments[k + 1].start_s <= time) ++k;
    const PlanSegment& seg = plan.segments[k];
    visit(k, std::clamp((time - seg.start_s) / seg.duration_s, 0.0, 1.0),
          static_cast<const std::vector<double>&>(position));
  };
  at(0.0);
  for (std::size_t i = 0; i < events.size(); ++i) {
    const Event& e = events[i];
    position[e.motor] += e.direction * plan.motors[e.motor].mm_per_pulse;
    if (i + 1 < events.size() && events[i + 1].tick == e.tick) continue;
    at(static_cast<double>(e.tick) / tick_hz);
  }
}

struct ErrorStats {
  double max_abs_mm = 0.0, mean_mm = 0.0, mean_abs_mm = 0.0, rms_mm = 0.0;
};

struct ProfileErrors {
  ErrorStats total, linearisation, quantisation;
  double area_percent = 0.0;  // seed 004: area between produced and nominal / area under f, %
  std::size_t states = 0;
  double x_at_max_mm = 0.0;
  // Per segment (plots along x): segment middle, smallest and largest total deviation, and the
  // largest |linearisation| and |quantisation| parts.
  std::vector<double> segment_x_mm, segment_min_mm, segment_max_mm;
  std::vector<double> segment_linearisation_mm, segment_quantisation_mm;
  double segment_max_abs_mm(std::size_t k) const {
    return std::max(std::abs(segment_min_mm[k]), std::abs(segment_max_mm[k]));
  }
};

ProfileErrors replay_errors(const Schedule& schedule, const Generatrix& generatrix,
                            const Kinematics& kinematics);

// The same replay from a step/direction timing table (controller_export.hpp): the axis positions
// after every tick that holds a step go through the forward kinematics (the contact on the tool
// interpolated in the segment that holds the tick). Returns the statistics of the total error
// and the number of states.
struct StepTableReplay {
  ErrorStats total;
  std::size_t states = 0;
};
struct StepEvent;
StepTableReplay replay_step_events(const Schedule& schedule, const std::vector<StepEvent>& events,
                                   double tick_hz, const Generatrix& generatrix, const Kinematics& kinematics);

}  // namespace chatterlab::planner
