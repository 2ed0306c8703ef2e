#include "chatterlab/planner/cam_planning.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "planner/controller_export.hpp"
#include "planner/plan_io.hpp"
#include "planner/replay.hpp"
#include "planner/setup.hpp"

namespace chatterlab::planner {

namespace {

constexpr double pi = std::numbers::pi;

// Signed distance from the closed profile to the wheel centre minus the wheel radius (positive:
// material left), nearest point by Newton on the spline parameter from `l`.
struct CamDeviation {
  double normal_mm;  // signed normal distance minus the wheel radius (+: material left)
  double lift_mm;    // the same as a radial (lift) deviation at the foot point
  double angle_deg;  // polar angle of the foot point, [0, 360)
};

CamDeviation cam_deviation(const ParametricSpline& spline, const ToolInPart& wheel, double& l) {
  // Safeguarded Newton: steps of at most 0.5 mm, a fixed downhill step where the distance is not
  // locally convex in l (concave flanks seen from a large wheel).
  std::array<double, 2> p{}, d1{}, d2{};
  for (int i = 0; i < 40; ++i) {
    spline.evaluate(l, p, d1, d2);
    const double rx = p[0] - wheel.x_mm, ry = p[1] - wheel.y_mm;
    const double g = rx * d1[0] + ry * d1[1];
    const double dg = d1[0] * d1[0] + d1[1] * d1[1] + rx * d2[0] + ry * d2[1];
    const double step = dg > 0 ? std::clamp(-g / dg, -0.5, 0.5) : (g > 0 ? -0.1 : 0.1);
    l += step;
    if (std::abs(step) < 1e-12) break;
  }
  spline.evaluate(l, p, d1, d2);
  const double distance = std::hypot(p[0] - wheel.x_mm, p[1] - wheel.y_mm);
  // Outside (wheel side) when the centre lies along the outward normal (d1.y, -d1.x).
  const double side = (wheel.x_mm - p[0]) * d1[1] - (wheel.y_mm - p[1]) * d1[0];
  const double normal = (side >= 0 ? distance : -distance) - wheel.radius_mm;
  // Radial deviation: the produced profile lies `normal` along the unit normal n; along the
  // radius r_hat that is normal / (n . r_hat).
  const double speed = std::hypot(d1[0], d1[1]), rho = std::hypot(p[0], p[1]);
  const double cos_angle = (d1[1] * p[0] - d1[0] * p[1]) / (speed * rho);
  return {normal, normal / cos_angle, std::fmod(std::atan2(p[1], p[0]) * 180.0 / pi + 360.0, 360.0)};
}

// Tangent-point tracking at equal steps of the contact's polar angle: the axis targets and the
// spline parameter of each contact.
void track_tangent_points(const ParametricSpline& spline, const Kinematics& kinematics, double step_deg,
                          CamPlan& out, std::vector<double>& contact_l) {
  out.segments = static_cast<std::size_t>(std::ceil(360.0 / step_deg - 1e-9));
  const std::size_t segments = out.segments;
  out.targets.assign(segments + 1, std::vector<double>(2));
  contact_l.assign(segments + 1, 0.0);
  auto& q = out.targets;
  for (std::size_t k = 0; k <= segments; ++k) {
    const double phi = 2 * pi * static_cast<double>(k) / static_cast<double>(segments);
    contact_l[k] = spline.parameter_at_polar_angle(phi);
    std::array<double, 2> p{}, d1{}, d2{};
    spline.evaluate(contact_l[k], p, d1, d2);
    kinematics.inverse({p[0], p[1], d1[0], d1[1]}, {}, q[k]);
    if (k > 0) q[k][0] += 360.0 * std::round((q[k - 1][0] - q[k][0]) / 360.0);  // unwrap C
  }
}

// Integer positions (remainders carried) and time-optimal durations under every machine rule
// (the feed planner's scheduler, docs/planner.md): C speed <= cam_speed_rpm, every motor's
// pulse rate, and the smoothness rule with starts, stops and reversals (the X slide reverses
// at the nose and the base circle), periodic because the cam is ground revolution after
// revolution. Then the same certificate after integerisation.
void schedule_pulses(const Kinematics& kinematics, const Json& machine, const Json& plan_settings, CamPlan& out) {
  const auto& q = out.targets;
  const std::size_t segments = out.segments;
  const auto motors = kinematics.motors();
  FeedPlan& plan = out.plan;
  plan.motors = motors;
  quantise_targets(plan, q);
  const double c_speed_deg_s = machine.at("cam_speed_rpm").get<double>() * 6.0;
  std::vector<double> cap(segments), exact_cap(segments);
  for (std::size_t k = 0; k < segments; ++k) {
    const double pulses_c = static_cast<double>(std::llabs(plan.segments[k].pulses[0]));
    cap[k] = pulses_c > 0 ? c_speed_deg_s / (pulses_c * motors[0].mm_per_pulse)
                          : std::numeric_limits<double>::infinity();
    exact_cap[k] = c_speed_deg_s / std::abs(q[k + 1][0] - q[k][0]);
  }
  const RateRules rules = build_rate_rules(machine, plan_settings, kinematics);
  try {
    out.smoothing_passes = time_optimal_durations(plan, cap, rules, true);
  } catch (const NoAdmissibleSpeed& e) {
    throw PointFailure(fmt::format("no plan: no admissible speed at contact angle {} deg",
                                   360.0 * static_cast<double>(e.segment) / static_cast<double>(segments)));
  }
  out.lower_bound_s = relaxed_time_bound(plan, exact_cap, q);
  Certificate certificate = certify_motor_rules(plan, q, rules, true);
  for (std::size_t k = 0; k < segments; ++k) {
    const PlanSegment& seg = plan.segments[k];
    const double c_speed = static_cast<double>(std::llabs(seg.pulses[0])) * motors[0].mm_per_pulse / seg.duration_s;
    out.max_c_speed_deg_per_s = std::max(out.max_c_speed_deg_per_s, c_speed);
    if (c_speed > c_speed_deg_s * (1 + 1e-9))
      certificate.add_violation(fmt::format("segment {}: C speed {} deg/s > {} deg/s", k, c_speed, c_speed_deg_s));
  }
  out.c_speed_limit_deg_per_s = c_speed_deg_s;
  out.total_time_s = plan.total_time_s();
  out.rules_ok = certificate.ok;
  out.rule_violations = certificate.violations;
  out.certificate = certificate_json(certificate, plan, rules,
                                     {{"path_rule", "C speed <= cam_speed_rpm"},
                                      {"max_c_speed_deg_per_s", out.max_c_speed_deg_per_s},
                                      {"c_speed_limit_deg_per_s", c_speed_deg_s}});
  out.ramp_segments = ramp_segments(plan, rules);
  out.ramp_time_s = static_cast<double>(out.ramp_segments) *
                    (plan.segments.front().duration_s + plan.segments.back().duration_s);
}

// Replay every state (pulses spread evenly per segment) through the forward kinematics: the
// normal deviation of each state, and the lift error of the surface the wheel leaves: the
// radial deviation (normal deviation / cos of the angle between the profile normal and the
// radius), and per 0.1 deg bin of the cam angle the deepest state (the envelope: a state that
// leaves material there is ground away by a deeper one).
void replay_lift_error(const ParametricSpline& spline, const Kinematics& kinematics,
                       const std::vector<double>& contact_l, CamPlan& out) {
  constexpr std::size_t bins_per_degree = 10;
  std::vector<double> envelope(360 * bins_per_degree, std::numeric_limits<double>::infinity());
  double sum_sq = 0.0;
  double l = contact_l[0];
  for_each_pulse_state(out.plan, [&](std::size_t k, double u, const std::vector<double>& position) {
    if (u == 0.0) l = contact_l[k];
    const CamDeviation d = cam_deviation(spline, kinematics.forward(position, {}), l);
    auto& bin = envelope[std::min(envelope.size() - 1, static_cast<std::size_t>(d.angle_deg * bins_per_degree))];
    bin = std::min(bin, d.lift_mm);
    out.max_profile_error_mm = std::max(out.max_profile_error_mm, std::abs(d.normal_mm));
    sum_sq += d.normal_mm * d.normal_mm;
    ++out.replayed_states;
  });
  out.rms_profile_error_mm =
      out.replayed_states ? std::sqrt(sum_sq / static_cast<double>(out.replayed_states)) : 0.0;
  for (std::size_t i = 0; i < envelope.size(); ++i)
    if (std::isfinite(envelope[i])) {
      out.lift_bin_angle_deg.push_back((static_cast<double>(i) + 0.5) / bins_per_degree);
      out.lift_error_mm.push_back(envelope[i]);
      out.max_lift_error_mm = std::max(out.max_lift_error_mm, std::abs(envelope[i]));
      const double next = envelope[(i + bins_per_degree) % envelope.size()];  // periodic
      if (std::isfinite(next))
        out.max_per_degree_lift_error_mm = std::max(out.max_per_degree_lift_error_mm, std::abs(next - envelope[i]));
    }
  out.meets_requirements = out.max_lift_error_mm <= cam_total_lift_error_limit_mm &&
                           out.max_per_degree_lift_error_mm <= cam_per_degree_lift_error_limit_mm;
}

// Concave parts of the fitted profile: a wheel of larger radius gouges there (K2 tracking keeps
// the tangency at the contact but the wheel then cuts the profile next to it).
void find_concave_parts(const ParametricSpline& spline, CamPlan& out) {
  double min_concave_radius = std::numeric_limits<double>::infinity(), concave_at_deg = 0.0;
  for (int i = 0; i < 20000; ++i) {
    std::array<double, 2> p{}, d1{}, d2{};
    spline.evaluate(spline.length() * i / 20000.0, p, d1, d2);
    const double speed = std::hypot(d1[0], d1[1]);
    const double curvature = (d1[0] * d2[1] - d1[1] * d2[0]) / (speed * speed * speed);
    if (curvature < 0 && -1 / curvature < min_concave_radius) {
      min_concave_radius = -1 / curvature;
      concave_at_deg = std::fmod(std::atan2(p[1], p[0]) * 180 / pi + 360.0, 360.0);
    }
  }
  out.min_concave_radius_mm = min_concave_radius;
  out.min_concave_radius_at_deg = concave_at_deg;
}

// Controller output (docs/planner.md, "Controller output"), read back: the program's pulses and
// durations, and the step table's states replayed through the forward kinematics.
void export_controller(const ParametricSpline& spline, const Kinematics& kinematics, const Json& plan_settings,
                       const std::vector<double>& contact_l, CamPlan& out) {
  out.tick_hz = controller_tick_hz(plan_settings, out.plan.motors);
  const ControllerExport controller = export_plan(
      out.plan, {"chatterlab cam_plan: one revolution of the cam, C in degrees (unwrapped), X slide in mm",
                 "G93 inverse time: F = 60 / segment duration"}, out.tick_hz);
  double step_replay_error = 0.0;
  std::size_t step_states = 0;
  double ls = contact_l[0];
  for_each_step_state(out.plan, controller.events, out.tick_hz,
                      [&](std::size_t k, double u, const std::vector<double>& position) {
                        if (u == 0.0) ls = contact_l[k];
                        step_replay_error = std::max(
                            step_replay_error,
                            std::abs(cam_deviation(spline, kinematics.forward(position, {}), ls).normal_mm));
                        ++step_states;
                      });
  out.gcode = controller.gcode;
  out.step_table = controller.step_table;
  out.controller_exact = controller.exact();
  out.shortest_step_interval_s = controller.check.shortest_step_interval_s;
  out.controller_round_trip = {{"exact", controller.exact()},
                               {"gcode_pulses_identical", controller.check.gcode_pulses_identical},
                               {"gcode_max_duration_error_s", controller.check.gcode_max_duration_error_s},
                               {"step_events", controller.check.step_events},
                               {"step_positions_identical", controller.check.step_positions_identical},
                               {"step_max_time_error_s", controller.check.step_max_time_error_s},
                               {"step_replay_states", step_states},
                               {"step_replay_max_profile_error_mm", step_replay_error}};
}

void certify(CamPlan& out) {
  out.certified = out.rules_ok && out.meets_requirements && out.controller_exact;
  if (!out.rules_ok) out.certification_failures.push_back("machine rules: " + out.rule_violations.front());
  if (!out.meets_requirements)
    out.certification_failures.push_back(
        fmt::format("lift error {:.4g} mm (limit 0.015), per degree {:.4g} mm (limit 0.004)",
                    out.max_lift_error_mm, out.max_per_degree_lift_error_mm));
  if (!out.controller_exact)
    out.certification_failures.push_back(
        "controller export: program.ngc or steps.csv read back differs from the plan");
}

}  // namespace

std::vector<ParamSpec> cam_machine_rule_specs() {
  ParamSpec speed = positive_spec("cam_speed_rpm", "rpm", "largest cam (C axis) speed");
  speed.default_value = 60.0;
  ParamSpec delta = relative_rate_change_spec();
  delta.default_value = 0.1;  // P2's machine
  return {speed, delta};
}

std::vector<ParamSpec> cam_plan_settings_specs() {
  ParamSpec step = positive_spec("segment_angle_deg", "deg", "polar angle of the contact per segment");
  step.default_value = 0.5;
  step.max = 10.0;
  return {step, start_stop_rate_spec(), controller_tick_spec()};
}

CamPlan plan_cam(const ParametricSpline& spline, const Kinematics& kinematics, const Json& machine,
                 const Json& plan_settings) {
  CamPlan out;
  std::vector<double> contact_l;
  track_tangent_points(spline, kinematics, plan_settings.at("segment_angle_deg").get<double>(), out, contact_l);
  schedule_pulses(kinematics, machine, plan_settings, out);
  replay_lift_error(spline, kinematics, contact_l, out);
  find_concave_parts(spline, out);
  export_controller(spline, kinematics, plan_settings, contact_l, out);
  certify(out);
  return out;
}

}  // namespace chatterlab::planner
