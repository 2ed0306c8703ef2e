#include "planner/replay.hpp"

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
  // First-order foot point: exact for a straight profile; the curvature term is
  // O(d^2 kappa) ~ 1e-12 mm for micrometre deviations on metre radii.
  const GeneratrixValue v = generatrix.evaluate(tool.x_mm);
  return (tool.y_mm - v.f) / std::sqrt(1.0 + v.d1 * v.d1) - tool.radius_mm;
}

ProfileErrors replay_errors(const Schedule& schedule, const Generatrix& generatrix,
                            const Kinematics& kinematics) {
  const FeedPlan& plan = schedule.plan;
  const std::size_t motors = plan.motors.size();
  ProfileErrors out;
  Accumulator total, linear, quantisation;
  std::vector<double> position(plan.initial_position_mm), exact(motors);
  std::vector<std::pair<double, std::size_t>> events;
  double area = 0.0, last_x = 0.0, last_e = 0.0;
  bool first = true;
  auto visit = [&](std::size_t k, double u, double& lo, double& hi) {
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
    if (!first) area += 0.5 * (std::abs(e) + std::abs(last_e)) * std::abs(tool.x_mm - last_x);
    first = false;
    last_x = tool.x_mm;
    last_e = e;
  };
  for (std::size_t k = 0; k < plan.segments.size(); ++k) {
    const PlanSegment& seg = plan.segments[k];
    events.clear();
    for (std::size_t m = 0; m < motors; ++m) {
      const std::int64_t n = std::llabs(seg.pulses[m]);
      for (std::int64_t j = 1; j <= n; ++j)
        events.emplace_back((static_cast<double>(j) - 0.5) / static_cast<double>(n), m);
    }
    std::sort(events.begin(), events.end());
    double lo = 1e300, hi = -1e300;
    visit(k, 0.0, lo, hi);
    for (std::size_t i = 0; i < events.size(); ++i) {
      const std::size_t m = events[i].second;
      position[m] += (seg.pulses[m] > 0 ? 1.0 : -1.0) * plan.motors[m].mm_per_pulse;
      if (i + 1 < events.size() && events[i + 1].first == events[i].first) continue;
      visit(k, events[i].first, lo, hi);
    }
    out.segment_x_mm.push_back(0.5 * (schedule.knots_mm[k] + schedule.knots_mm[k + 1]));
    out.segment_min_mm.push_back(lo);
    out.segment_max_mm.push_back(hi);
  }
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

}  // namespace chatterlab::planner
