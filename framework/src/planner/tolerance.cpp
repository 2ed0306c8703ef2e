#include "planner/tolerance.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace chatterlab::planner {

double chord_error_mm(const Generatrix& generatrix, const Kinematics& kinematics,
                      const std::function<ToolContact(double)>& tool_contact, const ExactTarget& from,
                      const ExactTarget& to) {
  const std::size_t motors = from.positions_mm.size();
  std::vector<double> q(motors);
  double worst = 0.0;
  for (const double u : {0.25, 0.5, 0.75}) {
    for (std::size_t m = 0; m < motors; ++m)
      q[m] = from.positions_mm[m] + u * (to.positions_mm[m] - from.positions_mm[m]);
    const double zeta = from.contact_on_tool_mm + u * (to.contact_on_tool_mm - from.contact_on_tool_mm);
    const ToolContact contact = tool_contact ? tool_contact(zeta) : ToolContact{zeta, 0.0, 0.0};
    worst = std::max(worst, std::abs(tool_deviation_mm(kinematics.forward(q, contact), generatrix)));
  }
  return worst;
}

std::vector<double> tolerance_knots(const Generatrix& generatrix, const Kinematics& kinematics,
                                    const std::function<double(double)>& contact_on_tool,
                                    const std::function<ToolContact(double)>& tool_contact,
                                    double budget_mm, double segment_length_mm,
                                    double min_segment_length_mm) {
  const double a = generatrix.x_min_mm(), b = generatrix.x_max_mm();
  const double longest = std::min(segment_length_mm, b - a);
  // c(x) from probe segments of the longest length on a grid of half that spacing.
  const auto cells = static_cast<std::size_t>(std::clamp(std::ceil(2 * (b - a) / longest), 2.0, 2e5));
  const double dx = (b - a) / static_cast<double>(cells);
  std::vector<double> allowed(cells + 1);
  bool binds = false;
  auto target = [&](double x) { return exact_target(generatrix, kinematics, contact_on_tool, tool_contact, x); };
  std::vector<double> c(cells + 1);
  for (std::size_t i = 0; i <= cells; ++i) {
    const double x = a + dx * static_cast<double>(i);
    const double lo = std::max(a, x - 0.5 * longest), hi = std::min(b, lo + longest);
    const double l = hi - lo;
    c[i] = chord_error_mm(generatrix, kinematics, tool_contact, target(lo), target(hi)) / (l * l);
  }
  for (std::size_t i = 0; i <= cells; ++i) {
    // The envelope over the neighbours: a segment spans more than one probe.
    const double ci = std::max({c[i], i > 0 ? c[i - 1] : 0.0, i < cells ? c[i + 1] : 0.0});
    const double l = ci > 0 ? std::sqrt(budget_mm / ci) : longest;
    allowed[i] = std::clamp(l, min_segment_length_mm, longest);
    binds = binds || allowed[i] < longest;
  }
  if (!binds) return uniform_knots(a, b, segment_length_mm);
  // Knots equally spaced in S(x) = integral of 1 / L(x) dx (trapezoid on the grid).
  std::vector<double> s(cells + 1, 0.0);
  for (std::size_t i = 1; i <= cells; ++i) s[i] = s[i - 1] + 0.5 * dx * (1 / allowed[i - 1] + 1 / allowed[i]);
  const auto segments = static_cast<std::size_t>(std::max(1.0, std::ceil(s.back() - 1e-9)));
  std::vector<double> knots{a};
  std::size_t i = 0;
  for (std::size_t k = 1; k < segments; ++k) {
    const double want = s.back() * static_cast<double>(k) / static_cast<double>(segments);
    while (s[i + 1] < want) ++i;
    const double t = (want - s[i]) / (s[i + 1] - s[i]);
    knots.push_back(a + dx * (static_cast<double>(i) + t));
  }
  knots.push_back(b);
  return knots;
}

TolerancePlan plan_to_tolerance(const Generatrix& generatrix, const Kinematics& kinematics,
                                const FeedConstraints& constraints, const ToleranceSettings& settings,
                                const std::function<double(double)>& contact_on_tool,
                                const std::function<ToolContact(double)>& tool_contact) {
  const double tol = settings.max_profile_error_mm;
  std::vector<double> knots =
      tolerance_knots(generatrix, kinematics, contact_on_tool, tool_contact,
                      settings.linearisation_share * tol, settings.segment_length_mm,
                      settings.min_segment_length_mm);
  TolerancePlan out;
  bool keep_first = true;  // x_1 nominal (the seed's first segment) unless the tolerance needs it
  for (int round = 1;; ++round) {
    out.schedule = plan_feed_on_knots(generatrix, kinematics, constraints, knots, contact_on_tool,
                                      true, tool_contact, keep_first);
    out.errors = replay_errors(out.schedule, generatrix, kinematics);
    out.nominal_knots_mm = knots;
    out.rounds = round;
    const ProfileErrors& e = out.errors;
    if (e.total.max_abs_mm <= tol) {
      out.met = true;
      break;
    }
    // Split the segments over the tolerance where the linearisation part still matters (a
    // segment half as long has a quarter of it). The motor steps' part does not shrink with the
    // length, but a new knot, placed where the axes round well, can cut it: segments over the
    // tolerance by their motor steps are split once, in the first round (the first segment's
    // remedy is to release its end, below).
    std::vector<double> refined{knots.front()};
    std::size_t splits = 0, worst = 0;
    bool too_short = false;
    for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
      if (e.segment_max_abs_mm(k) > e.segment_max_abs_mm(worst)) worst = k;
      const double length = knots[k + 1] - knots[k];
      const bool quantised = e.segment_linearisation_mm[k] <= 0.1 * tol;
      if (e.segment_max_abs_mm(k) > tol && (!quantised || (round == 1 && k > 0))) {
        if (0.5 * length >= settings.min_segment_length_mm) {
          refined.push_back(0.5 * (knots[k] + knots[k + 1]));
          ++splits;
        } else {
          too_short = true;
        }
      }
      refined.push_back(knots[k + 1]);
    }
    // The first segment's end is kept where the seed has it; its rounding residues then are
    // arbitrary. Where that segment breaks the tolerance by the motor steps, its end is chosen
    // like every other knot.
    if (keep_first && e.segment_max_abs_mm(0) > tol && e.segment_linearisation_mm[0] <= 0.1 * tol &&
        knots.size() > 2) {
      keep_first = false;
      out.first_knot_chosen = true;
      ++splits;  // a change worth another round
    }
    const double x_worst = e.x_at_max_mm;
    if (splits == 0 || round >= settings.max_rounds) {
      if (splits == 0 && !too_short) {
        out.limited_by = "motor_step";
        out.limit_note = fmt::format(
            "the replayed error {:.4g} mm at x = {:.2f} mm is the motor steps' own (quantisation "
            "{:.4g} mm, linearisation {:.4g} mm in that segment): shorter segments cannot bring it "
            "within {} mm; a finer step or a smaller lever arm can",
            e.total.max_abs_mm, x_worst, e.segment_quantisation_mm[worst],
            e.segment_linearisation_mm[worst], tol);
      } else if (splits == 0) {
        out.limited_by = "min_segment_length";
        out.limit_note = fmt::format(
            "the replayed error {:.4g} mm at x = {:.2f} mm would need segments shorter than "
            "min_segment_length_mm = {} mm", e.total.max_abs_mm, x_worst, settings.min_segment_length_mm);
      } else {
        out.limited_by = "rounds";
        out.limit_note = fmt::format("the replayed error is still {:.4g} mm at x = {:.2f} mm after {} rounds "
                                     "of refinement", e.total.max_abs_mm, x_worst, round);
      }
      break;
    }
    out.segments_split += refined.size() - knots.size();
    knots = std::move(refined);
  }
  const std::vector<double>& k = out.schedule.knots_mm;
  out.shortest_segment_mm = out.longest_segment_mm = k[1] - k[0];
  for (std::size_t i = 0; i + 1 < k.size(); ++i) {
    out.shortest_segment_mm = std::min(out.shortest_segment_mm, k[i + 1] - k[i]);
    out.longest_segment_mm = std::max(out.longest_segment_mm, k[i + 1] - k[i]);
    if (out.errors.segment_max_abs_mm(i) >= 0.9 * tol) ++out.binding_segments;
  }
  return out;
}

}  // namespace chatterlab::planner
