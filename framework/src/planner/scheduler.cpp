#include "planner/scheduler.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace chatterlab::planner {

namespace {

// Bounds are met exactly in real arithmetic; durations computed as 1/s may round a rate a few ulp
// above its bound, so the certificate allows check_tolerance (relative) and reports the values
// actually used.
constexpr double check_tolerance = 1e-9;
// Knot choice: window (fraction of the nominal spacing) and candidates per half window.
constexpr double knot_window = 0.25;
constexpr int knot_candidates = 100;

double rate_change_allowed(double rate_before, double delta, double start_stop_hz) {
  return std::max(delta * std::abs(rate_before), start_stop_hz);
}

}  // namespace

double FeedPlan::total_time_s() const {
  return segments.empty() ? 0.0 : segments.back().start_s + segments.back().duration_s;
}

std::vector<double> FeedPlan::positions_after(std::size_t segment_count) const {
  std::vector<double> out = initial_position_mm;
  std::vector<std::int64_t> steps(motors.size(), 0);
  for (std::size_t k = 0; k < segment_count && k < segments.size(); ++k)
    for (std::size_t m = 0; m < motors.size(); ++m) steps[m] += segments[k].pulses[m];
  for (std::size_t m = 0; m < motors.size(); ++m)
    out[m] += static_cast<double>(steps[m]) * motors[m].mm_per_pulse;
  return out;
}

std::vector<double> uniform_knots(double a, double b, double segment_length_mm) {
  if (!(segment_length_mm > 0.0) || !(b > a))
    throw std::invalid_argument("plan_feed: empty x range or segment length");
  const auto segment_count =
      static_cast<std::size_t>(std::max(1.0, std::ceil((b - a) / segment_length_mm - 1e-9)));
  std::vector<double> knots(segment_count + 1);
  const double spacing = (b - a) / static_cast<double>(segment_count);
  for (std::size_t k = 0; k < segment_count; ++k) knots[k] = a + spacing * static_cast<double>(k);
  knots[segment_count] = b;
  return knots;
}

Schedule plan_feed(const Generatrix& generatrix, const Kinematics& kinematics,
                   const FeedConstraints& constraints, double segment_length_mm,
                   const std::function<double(double)>& contact_on_tool, bool choose_knots,
                   const std::function<ToolContact(double)>& tool_contact) {
  return plan_feed_on_knots(generatrix, kinematics, constraints,
                            uniform_knots(generatrix.x_min_mm(), generatrix.x_max_mm(), segment_length_mm),
                            contact_on_tool, choose_knots, tool_contact);
}

ExactTarget exact_target(const Generatrix& generatrix, const Kinematics& kinematics,
                         const std::function<double(double)>& contact_on_tool,
                         const std::function<ToolContact(double)>& tool_contact, double x) {
  ExactTarget t;
  t.x_mm = x;
  const GeneratrixValue v = generatrix.evaluate(x);
  t.contact_on_tool_mm = contact_on_tool ? contact_on_tool(x) : 0.0;
  t.positions_mm.resize(kinematics.motors().size());
  const ToolContact contact =
      tool_contact ? tool_contact(t.contact_on_tool_mm) : ToolContact{t.contact_on_tool_mm, 0.0, 0.0};
  kinematics.inverse({x, v.f, 1.0, v.d1}, contact, t.positions_mm);
  return t;
}

Schedule plan_feed_on_knots(const Generatrix& generatrix, const Kinematics& kinematics,
                            const FeedConstraints& constraints, const std::vector<double>& nominal,
                            const std::function<double(double)>& contact_on_tool, bool choose_knots,
                            const std::function<ToolContact(double)>& tool_contact,
                            bool keep_first_segment) {
  if (nominal.size() < 2 || !(nominal.back() > nominal.front()))
    throw std::invalid_argument("plan_feed: fewer than two knots");
  const std::size_t segment_count = nominal.size() - 1;
  Schedule out;
  out.tool_contact = tool_contact;
  FeedPlan& plan = out.plan;
  plan.motors = kinematics.motors();
  plan.spindle_speed_rpm = constraints.spindle_speed_rpm;
  const std::size_t motors = plan.motors.size();

  // 1. Knots and exact targets.
  out.knots_mm.resize(segment_count + 1);
  out.contact_on_tool_mm.resize(segment_count + 1);
  out.target_mm.assign(segment_count + 1, std::vector<double>(motors));
  auto place = [&](std::size_t k, double x) {
    ExactTarget t = exact_target(generatrix, kinematics, contact_on_tool, tool_contact, x);
    out.knots_mm[k] = x;
    out.contact_on_tool_mm[k] = t.contact_on_tool_mm;
    out.target_mm[k] = std::move(t.positions_mm);
  };
  place(0, nominal.front());
  std::vector<double> behind(motors), ahead(motors), sensitivity(motors);
  for (std::size_t k = 1; k <= segment_count; ++k) {
    // x_1 stays nominal: the first segment is then the seed's (0.2 mm in 1 s at the bound),
    // comparable row for row with seed 000's table (MODELS.md P8).
    if ((k == 1 && keep_first_segment) || k == segment_count || !choose_knots) {
      place(k, nominal[k]);
      continue;
    }
    // Knot choice: within +-window of the local nominal spacing, the x where the rounding
    // residues of the axes, weighted by how far a step of each moves the tool off the profile,
    // are smallest. An axis is then off by at most |residue| + 1/2 step inside a segment (pulses
    // spread evenly) instead of up to a whole step. Positions over the window come from a
    // quadratic through three exact evaluations (error ~ w^3 q'''/6: micro-steps).
    const double w = knot_window * std::min(nominal[k] - nominal[k - 1], nominal[k + 1] - nominal[k]);
    const double centre = nominal[k];
    place(k, centre - w);
    behind = out.target_mm[k];
    place(k, centre + w);
    ahead = out.target_mm[k];
    place(k, centre);
    const ToolContact contact = out.contact_at(out.contact_on_tool_mm[k]);
    const double here = tool_deviation_mm(kinematics.forward(out.target_mm[k], contact), generatrix);
    for (std::size_t m = 0; m < motors; ++m) {
      std::vector<double> moved = out.target_mm[k];
      moved[m] += plan.motors[m].mm_per_pulse;
      sensitivity[m] =
          std::abs(tool_deviation_mm(kinematics.forward(moved, contact), generatrix) - here);
    }
    double best_cost = std::numeric_limits<double>::infinity(), best_t = 0.0;
    for (int c = -knot_candidates; c <= knot_candidates; ++c) {
      const double t = static_cast<double>(c) / knot_candidates;  // x = nominal + t w
      double cost = 0.0;
      for (std::size_t m = 0; m < motors; ++m) {
        const double q0 = out.target_mm[k][m];
        const double q = q0 + 0.5 * t * (ahead[m] - behind[m]) +
                         0.5 * t * t * (ahead[m] - 2 * q0 + behind[m]);
        const double steps = (q - out.target_mm[0][m]) / plan.motors[m].mm_per_pulse;
        cost += sensitivity[m] * std::abs(steps - std::round(steps));
      }
      if (cost < best_cost - 1e-15) {
        best_cost = cost;
        best_t = t;
      }
    }
    place(k, centre + best_t * w);
  }
  quantise_targets(plan, out.target_mm);

  // 3. Per-segment speed caps from the axial-advance rule (s = 1/duration), the continuous
  //    relaxation, and the time-optimal speeds under every motor rule.
  const double v_axial = constraints.max_axial_speed_mm_per_s();
  std::vector<double> cap(segment_count);
  for (std::size_t k = 0; k < segment_count; ++k)
    cap[k] = v_axial / (out.knots_mm[k + 1] - out.knots_mm[k]);
  out.lower_bound_s = relaxed_time_bound(plan, cap, out.target_mm);
  try {
    out.smoothing_passes = time_optimal_durations(plan, cap, constraints.rate_rules());
  } catch (const NoAdmissibleSpeed& e) {
    throw std::domain_error(
        fmt::format("no admissible speed for the segment at x = {} mm", out.knots_mm[e.segment]));
  }
  out.certificate = certify(out, constraints);
  return out;
}

void quantise_targets(FeedPlan& plan, const std::vector<std::vector<double>>& target_mm) {
  const std::size_t motors = plan.motors.size(), segment_count = target_mm.size() - 1;
  plan.initial_position_mm = target_mm[0];
  // Rounding the cumulative target (never the increments) carries the remainder: every axis
  // stays within half a step of its target at every segment end.
  std::vector<std::int64_t> previous(motors, 0), now(motors);
  plan.segments.assign(segment_count, PlanSegment{});
  for (std::size_t k = 0; k < segment_count; ++k) {
    plan.segments[k].pulses.resize(motors);
    for (std::size_t m = 0; m < motors; ++m) {
      now[m] = std::llround((target_mm[k + 1][m] - target_mm[0][m]) / plan.motors[m].mm_per_pulse);
      plan.segments[k].pulses[m] = now[m] - previous[m];
      previous[m] = now[m];
    }
  }
}

double relaxed_time_bound(const FeedPlan& plan, const std::vector<double>& speed_cap,
                          const std::vector<std::vector<double>>& target_mm) {
  double bound_s = 0.0;
  for (std::size_t k = 0; k < plan.segments.size(); ++k) {
    double relaxed = speed_cap[k];
    for (std::size_t m = 0; m < plan.motors.size(); ++m) {
      const double exact = std::abs(target_mm[k + 1][m] - target_mm[k][m]) / plan.motors[m].mm_per_pulse;
      if (exact > 0) relaxed = std::min(relaxed, plan.motors[m].max_pulse_rate_hz / exact);
    }
    bound_s += 1.0 / relaxed;
  }
  return bound_s;
}

namespace {

// Consecutive segment pairs (k, next): k + 1, and N-1 -> 0 when periodic.
std::vector<std::pair<std::size_t, std::size_t>> segment_pairs(std::size_t count, bool periodic) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t k = 0; k + 1 < count; ++k) pairs.emplace_back(k, k + 1);
  if (periodic && count > 1) pairs.emplace_back(count - 1, 0);
  return pairs;
}

}  // namespace

std::size_t time_optimal_durations(FeedPlan& plan, const std::vector<double>& speed_cap,
                                   const RateRules& rules, bool periodic) {
  const std::size_t motors = plan.motors.size(), segment_count = plan.segments.size();
  const double delta = rules.max_relative_rate_change, fss = rules.start_stop_rate_hz;
  auto pulses = [&](std::size_t k, std::size_t m) { return static_cast<double>(plan.segments[k].pulses[m]); };
  // Per-segment bounds: the path's cap and every motor's pulse rate.
  std::vector<double> s(segment_count);
  for (std::size_t k = 0; k < segment_count; ++k) {
    s[k] = speed_cap[k];
    for (std::size_t m = 0; m < motors; ++m)
      if (pulses(k, m) != 0) s[k] = std::min(s[k], plan.motors[m].max_pulse_rate_hz / std::abs(pulses(k, m)));
  }
  const auto pairs = segment_pairs(segment_count, periodic);
  // Smoothness rules that bound one segment alone: starts, stops and reversals.
  for (const auto& [k, next] : pairs)
    for (std::size_t m = 0; m < motors; ++m) {
      const double n0 = pulses(k, m), n1 = pulses(next, m);
      if (n0 == 0 && n1 != 0) s[next] = std::min(s[next], fss / std::abs(n1));
      if (n1 == 0 && n0 != 0) s[k] = std::min(s[k], fss / std::abs(n0));
      if (n0 * n1 < 0) {
        s[k] = std::min(s[k], 0.5 * fss / std::abs(n0));
        s[next] = std::min(s[next], 0.5 * fss / std::abs(n1));
      }
    }
  // Same-sign rate changes: forward (acceleration) and backward (deceleration) passes.
  // The smallest of a bound over the motors that turn the same way in segments k and next; bound
  // takes |n0| and |n1|, the pulse counts of k and next.
  auto same_sign_bound = [&](std::size_t k, std::size_t next, auto bound) {
    double smallest = std::numeric_limits<double>::infinity();
    for (std::size_t m = 0; m < motors; ++m) {
      const double n0 = pulses(k, m), n1 = pulses(next, m);
      if (n0 * n1 <= 0) continue;
      smallest = std::min(smallest, bound(std::abs(n0), std::abs(n1)));
    }
    return smallest;
  };
  auto forward_bound = [&](std::size_t k, std::size_t next) {  // largest s[next] given s[k]
    return same_sign_bound(k, next, [&](double n0, double n1) {
      const double r = n0 * s[k];
      return (r + rate_change_allowed(r, delta, fss)) / n1;
    });
  };
  auto backward_bound = [&](std::size_t k, std::size_t next) {  // largest s[k] given s[next]
    return same_sign_bound(k, next, [&](double n0, double n1) {
      const double r1 = n1 * s[next];
      return std::max(r1 / (1.0 - delta), r1 + fss) / n0;
    });
  };
  std::size_t passes = 0;
  for (std::size_t pass = 0; pass < 1000; ++pass) {
    bool changed = false;
    auto lower = [&](std::size_t k, double bound) {
      if (bound < s[k] * (1.0 - 1e-13)) changed = true;
      s[k] = std::min(s[k], bound);
    };
    for (const auto& [k, next] : pairs) lower(next, forward_bound(k, next));
    for (auto it = pairs.rbegin(); it != pairs.rend(); ++it) lower(it->first, backward_bound(it->first, it->second));
    passes = pass + 1;
    if (!changed) break;
  }

  double t = 0.0, carry = 0.0;  // compensated sum: 3000 segments end at the bound's time
  for (std::size_t k = 0; k < segment_count; ++k) {
    if (!(s[k] > 0.0) || !std::isfinite(1.0 / s[k])) throw NoAdmissibleSpeed(k);
    plan.segments[k].start_s = t;
    plan.segments[k].duration_s = 1.0 / s[k];
    const double y = plan.segments[k].duration_s - carry, sum = t + y;
    carry = (sum - t) - y;
    t = sum;
  }
  return passes;
}

Certificate certify_motor_rules(const FeedPlan& plan, const std::vector<std::vector<double>>& target_mm,
                                const RateRules& rules, bool periodic) {
  const std::size_t motors = plan.motors.size();
  Certificate c;
  c.max_pulse_rate_hz.assign(motors, 0.0);
  const double delta = rules.max_relative_rate_change, fss = rules.start_stop_rate_hz;
  auto rate = [&](std::size_t k, std::size_t m) {
    return static_cast<double>(plan.segments[k].pulses[m]) / plan.segments[k].duration_s;
  };
  std::vector<std::int64_t> position(motors, 0);
  std::vector<int> last_sign(motors, 0);
  for (std::size_t k = 0; k < plan.segments.size(); ++k)
    for (std::size_t m = 0; m < motors; ++m) {
      if (plan.segments[k].pulses[m] != 0) {  // reversals: sign changes of the moving segments
        const int sign = plan.segments[k].pulses[m] > 0 ? 1 : -1;
        if (last_sign[m] != 0 && sign != last_sign[m]) ++c.reversals;
        last_sign[m] = sign;
      }
      const double r = std::abs(rate(k, m));
      c.max_pulse_rate_hz[m] = std::max(c.max_pulse_rate_hz[m], r);
      if (r > plan.motors[m].max_pulse_rate_hz * (1 + check_tolerance))
        c.add_violation(fmt::format("segment {}: {} motor at {} pulses/s > {}", k, plan.motors[m].name,
                                    r, plan.motors[m].max_pulse_rate_hz));
      position[m] += plan.segments[k].pulses[m];
      const double exact = (target_mm[k + 1][m] - target_mm[0][m]) / plan.motors[m].mm_per_pulse;
      c.max_position_drift_steps = std::max(c.max_position_drift_steps,
                                            std::abs(static_cast<double>(position[m]) - exact));
    }
  for (const auto& [k, next] : segment_pairs(plan.segments.size(), periodic))
    for (std::size_t m = 0; m < motors; ++m) {
      const double before = rate(k, m), after = rate(next, m), change = std::abs(after - before);
      if (change <= delta * std::abs(before)) {
        if (before != 0.0) c.max_relative_rate_change = std::max(c.max_relative_rate_change, change / std::abs(before));
      } else {
        ++c.rate_changes_under_start_stop_allowance;
        c.max_rate_change_at_low_rate_hz = std::max(c.max_rate_change_at_low_rate_hz, change);
        if (change > rate_change_allowed(before, delta, fss) * (1 + check_tolerance))
          c.add_violation(fmt::format("segments {}-{}: {} motor rate {} -> {} pulses/s changes by more "
                                      "than max({} x {}, start-stop rate {})",
                                      k, next, plan.motors[m].name, before, after, delta,
                                      std::abs(before), fss));
      }
    }
  if (c.max_position_drift_steps > 0.5 + 1e-6)
    c.add_violation(fmt::format("positions drift by {} steps", c.max_position_drift_steps));
  return c;
}

Certificate certify(const Schedule& schedule, const FeedConstraints& constraints) {
  Certificate c = certify_motor_rules(schedule.plan, schedule.target_mm, constraints.rate_rules());
  const double v_axial = constraints.max_axial_speed_mm_per_s();
  for (std::size_t k = 0; k < schedule.plan.segments.size(); ++k) {
    const double axial = std::abs(schedule.knots_mm[k + 1] - schedule.knots_mm[k]) /
                         schedule.plan.segments[k].duration_s;
    c.max_axial_speed_mm_per_s = std::max(c.max_axial_speed_mm_per_s, axial);
    if (axial > v_axial * (1 + check_tolerance))
      c.add_violation(fmt::format("segment {}: axial speed {} mm/s > {} mm/s", k, axial, v_axial));
  }
  return c;
}

std::size_t ramp_segments(const FeedPlan& plan, const RateRules& rules) {
  if (plan.segments.empty()) return 0;
  double fastest = 0.0;
  const PlanSegment& first = plan.segments.front();
  for (std::size_t m = 0; m < plan.motors.size(); ++m)
    fastest = std::max(fastest, std::abs(static_cast<double>(first.pulses[m])) / first.duration_s);
  double scale = fastest > 0 ? rules.start_stop_rate_hz / fastest : 1.0;
  std::size_t n = 0;
  while (scale < 1.0) {
    ++n;
    scale *= 1.0 + rules.max_relative_rate_change;
  }
  return n;
}

}  // namespace chatterlab::planner
