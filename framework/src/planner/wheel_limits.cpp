#include "planner/wheel_limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "planner/replay.hpp"

namespace chatterlab::planner {

namespace {

struct Frame {
  double x, y, tx, ty, nx, ny;  // point, unit tangent (+x), unit outward normal
};

Frame frame_at(const Generatrix& g, double x) {
  const GeneratrixValue v = g.evaluate(x);
  const double len = std::sqrt(1.0 + v.d1 * v.d1);
  return {x, v.f, 1.0 / len, v.d1 / len, -v.d1 / len, 1.0 / len};
}

}  // namespace

EdgeRadiusLimit largest_edge_radius(const Generatrix& generatrix, std::size_t samples) {
  const double a = generatrix.x_min_mm(), b = generatrix.x_max_mm();
  std::vector<Frame> frames(samples);
  for (std::size_t i = 0; i < samples; ++i)
    frames[i] = frame_at(generatrix, a + (b - a) * static_cast<double>(i) / static_cast<double>(samples - 1));
  EdgeRadiusLimit best{std::numeric_limits<double>::infinity(), 0.0, false};
  for (std::size_t i = 0; i < samples; ++i) {
    const Frame& p = frames[i];
    const GeneratrixValue v = generatrix.evaluate(p.x);
    if (v.d2 > 0) {
      const double rho = std::pow(1.0 + v.d1 * v.d1, 1.5) / v.d2;
      if (rho < best.radius_mm) best = {rho, p.x, true};
    }
    for (std::size_t j = 0; j < samples; ++j) {
      if (j + 1 >= i && j <= i + 1) continue;  // neighbours: the local term above is exact
      const double dx = frames[j].x - p.x, dy = frames[j].y - p.y;
      const double along_normal = dx * p.nx + dy * p.ny;
      if (along_normal <= 0) continue;
      const double r = (dx * dx + dy * dy) / (2 * along_normal);
      if (r < best.radius_mm) best = {r, p.x, false};
    }
  }
  return best;
}

double wheel_geometry_edge_radius_mm(const WheelSection& wheel) {
  const double half = 0.5 * wheel.edge_angle_deg * std::numbers::pi / 180.0;
  return wheel.thickness_mm / (2.0 * std::sin(half));
}

namespace {

// The generatrix as a cubic Hermite table of f and f' (fast, smooth depth queries).
class TabulatedProfile {
 public:
  TabulatedProfile(const Generatrix& g, std::size_t intervals)
      : a_(g.x_min_mm()), b_(g.x_max_mm()), h_((b_ - a_) / static_cast<double>(intervals)),
        f_(intervals + 1), d1_(intervals + 1) {
    for (std::size_t i = 0; i <= intervals; ++i) {
      const GeneratrixValue v = g.evaluate(std::min(b_, a_ + h_ * static_cast<double>(i)));
      f_[i] = v.f;
      d1_[i] = v.d1;
    }
  }
  // Depth of Q below the profile along its normal (first order); -inf beyond the part's ends.
  double depth(double qx, double qy) const {
    if (qx < a_ || qx > b_) return -std::numeric_limits<double>::infinity();
    const double pos = (qx - a_) / h_;
    const auto i = std::min(static_cast<std::size_t>(pos), f_.size() - 2);
    const double t = pos - static_cast<double>(i), t2 = t * t, t3 = t2 * t;
    const double f = (2 * t3 - 3 * t2 + 1) * f_[i] + (t3 - 2 * t2 + t) * h_ * d1_[i] +
                     (-2 * t3 + 3 * t2) * f_[i + 1] + (t3 - t2) * h_ * d1_[i + 1];
    const double d1 = (1 - t) * d1_[i] + t * d1_[i + 1];
    return (f - qy) / std::sqrt(1.0 + d1 * d1);
  }

 private:
  double a_, b_, h_;
  std::vector<double> f_, d1_;
};

// The wheel section in the part frame: tool point (along, across) -> O + along U + across W.
struct ToolFrame {
  double ox, oy, ux, uy, wx, wy;
};

struct Deepest {
  double depth_mm, x_mm;
};

// Deepest point of the section below the profile: samples, then golden section around the best.
Deepest deepest_point(const TabulatedProfile& profile, const WheelSection& wheel, const ToolFrame& f) {
  const double half = 0.5 * wheel.edge_angle_deg * std::numbers::pi / 180.0;
  auto point = [&](double t) {  // t in [-1, 1] along the section
    double along = 0.0, across = 0.0;
    if (!wheel.profiled) {
      along = 0.5 * wheel.thickness_mm * t;
    } else {
      const double phi = half * t, r = wheel.edge_radius_mm;
      along = r * std::sin(phi);
      across = r * (1 - std::cos(phi));
    }
    const double qx = f.ox + along * f.ux + across * f.wx, qy = f.oy + along * f.uy + across * f.wy;
    return Deepest{profile.depth(qx, qy), qx};
  };
  constexpr int samples = 64;
  Deepest best{-std::numeric_limits<double>::infinity(), 0.0};
  int best_i = 0;
  for (int i = 0; i <= samples; ++i) {
    const Deepest d = point(-1.0 + 2.0 * i / samples);
    if (d.depth_mm > best.depth_mm) {
      best = d;
      best_i = i;
    }
  }
  if (!std::isfinite(best.depth_mm)) return best;
  // The depth is smooth along the section: refine between the best sample's neighbours.
  double lo = -1.0 + 2.0 * std::max(0, best_i - 1) / samples, hi = -1.0 + 2.0 * std::min(samples, best_i + 1) / samples;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 30; ++it) {
    const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
    if (point(m1).depth_mm > point(m2).depth_mm) hi = m2; else lo = m1;
  }
  const Deepest refined = point(0.5 * (lo + hi));
  return refined.depth_mm > best.depth_mm ? refined : best;
}

constexpr std::size_t table_intervals = 20000;

}  // namespace

Interference check_interference(const Generatrix& generatrix, const WheelSection& wheel,
                                const std::vector<double>& contacts_mm, double tolerance_mm) {
  const TabulatedProfile profile(generatrix, table_intervals);
  Interference out;
  out.tolerance_mm = tolerance_mm;
  for (double x : contacts_mm) {
    const Frame p = frame_at(generatrix, x);
    const Deepest d = deepest_point(profile, wheel, {p.x, p.y, p.tx, p.ty, p.nx, p.ny});
    ++out.states_checked;
    if (d.depth_mm > tolerance_mm) {
      ++out.contacts_with_interference;
      if (d.depth_mm > out.depth_mm) {
        out.depth_mm = d.depth_mm;
        out.x_mm = d.x_mm;
        out.contact_x_mm = x;
      }
    }
  }
  return out;
}

Interference check_interference_along_plan(const Schedule& schedule, const Generatrix& generatrix,
                                           const Kinematics& kinematics, const WheelSection& wheel,
                                           double tolerance_mm) {
  const TabulatedProfile profile(generatrix, table_intervals);
  const FeedPlan& plan = schedule.plan;
  Interference out;
  out.tolerance_mm = tolerance_mm;
  std::size_t last_segment = plan.segments.size();
  for_each_pulse_state(plan, [&](std::size_t k, double u, const std::vector<double>& position) {
    const ToolInPart o = kinematics.forward(position, {0.0, 0.0, 0.0});
    const ToolInPart along = kinematics.forward(position, {1.0, 0.0, 0.0});
    const ToolInPart across = kinematics.forward(position, {0.0, 1.0, 0.0});
    const ToolFrame frame{o.x_mm, o.y_mm, along.x_mm - o.x_mm, along.y_mm - o.y_mm,
                          across.x_mm - o.x_mm, across.y_mm - o.y_mm};
    const double zeta = schedule.contact_on_tool_mm[k] +
                        u * (schedule.contact_on_tool_mm[k + 1] - schedule.contact_on_tool_mm[k]);
    const ToolInPart contact = kinematics.forward(position, schedule.contact_at(zeta));
    const double own_cut = std::max(0.0, -tool_deviation_mm(contact, generatrix));
    const Deepest d = deepest_point(profile, wheel, frame);
    ++out.states_checked;
    const double excess = d.depth_mm - own_cut;
    if (!(excess > tolerance_mm)) return;
    ++out.contacts_with_interference;
    if (k != last_segment) ++out.segments_with_interference;
    last_segment = k;
    if (excess > out.depth_mm) {
      out.depth_mm = excess;
      out.x_mm = d.x_mm;
      out.contact_x_mm = contact.x_mm;
      out.time_s = plan.segments[k].start_s + u * plan.segments[k].duration_s;
    }
  });
  return out;
}

}  // namespace chatterlab::planner
