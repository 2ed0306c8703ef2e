#include "planner/replay.hpp"

#include "planner/controller_export.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace chatterlab::planner {

namespace {

struct Accumulator {
  double max_abs = 0.0, sum = 0.0, sum_abs = 0.0, sum_sq = 0.0;
  std::size_t n = 0;
  void add(double e) {
    max_abs = std::max(max_abs, std::abs(e));
    sum += e;
    sum_abs += std::abs(e);
    sum_sq += e * e;
    ++n;
  }
  ErrorStats stats() const {
    if (n == 0) return {};
    const auto count = static_cast<double>(n);
    return {max_abs, sum / count, sum_abs / count, std::sqrt(sum_sq / count)};
  }
};

}  // namespace

double tool_deviation_mm(const ToolInPart& tool, const Generatrix& generatrix) {
  GeneratrixValue v = generatrix.evaluate(tool.x_mm);
  // A point tool (the nominal contact itself, P4): first-order foot point, exact for a straight
  // profile; the curvature term is O(d^2 kappa) ~ 1e-12 mm for micrometre deviations d on metre
  // radii of curvature.
  if (tool.radius_mm == 0.0) return (tool.y_mm - v.f) / std::sqrt(1.0 + v.d1 * v.d1);
  // A disc: its centre stands a whole radius R off the profile, where the first-order formula
  // errs by about R^2 kappa / 2 (a 200 mm wheel on a 1300 mm radius of curvature: 15 mm). The
  // foot point of the normal through the centre c solves g(x) = (x - c_x) + (f(x) - c_y) f'(x) = 0;
  // Newton from the first-order foot, Gauss-Newton (g' = 1 + f'^2) where the centre lies near or
  // beyond the centre of curvature and g' is not safely positive.
  double x = tool.x_mm + (tool.y_mm - v.f) * v.d1 / (1.0 + v.d1 * v.d1);
  for (int iteration = 0; iteration < 60; ++iteration) {
    v = generatrix.evaluate(x);
    const double g = (x - tool.x_mm) + (v.f - tool.y_mm) * v.d1;
    const double gauss_newton = 1.0 + v.d1 * v.d1;
    const double newton = gauss_newton + (v.f - tool.y_mm) * v.d2;
    const double step = g / (newton > 0.1 * gauss_newton ? newton : gauss_newton);
    if (!std::isfinite(step)) break;
    x -= step;
    if (std::abs(step) <= 1e-14 * std::max(1.0, std::abs(x))) break;
  }
  v = generatrix.evaluate(x);
  const double dx = tool.x_mm - x, dy = tool.y_mm - v.f;
  // The side: the centre's offset along the profile normal (-f', 1) (positive: away from the axis).
  return std::copysign(std::hypot(dx, dy), dy - v.d1 * dx) - tool.radius_mm;
}

ProfileErrors replay_errors(const Schedule& schedule, const Generatrix& generatrix,
                            const Kinematics& kinematics) {
  const FeedPlan& plan = schedule.plan;
  const std::size_t motors = plan.motors.size();
  ProfileErrors out;
  Accumulator total, linear, quantisation;
  std::vector<double> exact(motors);
  double area = 0.0, last_x = 0.0, last_e = 0.0;
  bool first = true;
  double lo = 1e300, hi = -1e300, lin = 0.0, quant = 0.0;
  auto close_segment = [&](std::size_t k) {
    out.segment_x_mm.push_back(0.5 * (schedule.knots_mm[k] + schedule.knots_mm[k + 1]));
    out.segment_min_mm.push_back(lo);
    out.segment_max_mm.push_back(hi);
    out.segment_linearisation_mm.push_back(lin);
    out.segment_quantisation_mm.push_back(quant);
    lo = 1e300;
    hi = -1e300;
    lin = quant = 0.0;
  };
  for_each_pulse_state(plan, [&](std::size_t k, double u, const std::vector<double>& position) {
    if (u == 0.0 && k > 0) close_segment(k - 1);
    const double zeta = schedule.contact_on_tool_mm[k] +
                        u * (schedule.contact_on_tool_mm[k + 1] - schedule.contact_on_tool_mm[k]);
    const ToolContact contact = schedule.contact_at(zeta);
    const ToolInPart tool = kinematics.forward(position, contact);
    const double e = tool_deviation_mm(tool, generatrix);
    for (std::size_t m = 0; m < motors; ++m)
      exact[m] = schedule.target_mm[k][m] + u * (schedule.target_mm[k + 1][m] - schedule.target_mm[k][m]);
    const double e_linear = tool_deviation_mm(kinematics.forward(exact, contact), generatrix);
    if (std::abs(e) > total.max_abs) out.x_at_max_mm = tool.x_mm;
    total.add(e);
    linear.add(e_linear);
    quantisation.add(e - e_linear);
    lo = std::min(lo, e);
    hi = std::max(hi, e);
    lin = std::max(lin, std::abs(e_linear));
    quant = std::max(quant, std::abs(e - e_linear));
    if (!first) area += 0.5 * (std::abs(e) + std::abs(last_e)) * std::abs(tool.x_mm - last_x);
    first = false;
    last_x = tool.x_mm;
    last_e = e;
  });
  if (!plan.segments.empty()) close_segment(plan.segments.size() - 1);
  // Area under the generatrix (Simpson on the knots' grid refined x4).
  const double a = schedule.knots_mm.front(), b = schedule.knots_mm.back();
  const std::size_t n = 4 * (schedule.knots_mm.size() - 1);
  double under = 0.0;
  for (std::size_t i = 0; i <= n; ++i) {
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    under += w * generatrix.evaluate(a + (b - a) * static_cast<double>(i) / static_cast<double>(n)).f;
  }
  under *= (b - a) / static_cast<double>(n) / 3.0;
  out.area_percent = 100.0 * area / std::abs(under);
  out.total = total.stats();
  out.linearisation = linear.stats();
  out.quantisation = quantisation.stats();
  out.states = total.n;
  return out;
}

StepTableReplay replay_step_events(const Schedule& schedule, const std::vector<StepEvent>& events,
                                   double tick_hz, const Generatrix& generatrix, const Kinematics& kinematics) {
  Accumulator total;
  for_each_step_state(schedule.plan, events, tick_hz, [&](std::size_t k, double u, const std::vector<double>& position) {
    const double zeta = schedule.contact_on_tool_mm[k] +
                        u * (schedule.contact_on_tool_mm[k + 1] - schedule.contact_on_tool_mm[k]);
    total.add(tool_deviation_mm(kinematics.forward(position, schedule.contact_at(zeta)), generatrix));
  });
  return {total.stats(), total.n};
}

}  // namespace chatterlab::planner
