#include "planner/wheel_limits.hpp"

#include <algorithm>
#include <array>
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

EdgeRadiusLimit largest_edge_radius(const Generatrix& generatrix, const GeometryAnalysis& geometry,
                                    std::size_t samples) {
  const double a = generatrix.x_min_mm(), b = generatrix.x_max_mm();
  std::vector<Frame> frames(samples);
  for (std::size_t i = 0; i < samples; ++i)
    frames[i] = frame_at(generatrix, a + (b - a) * static_cast<double>(i) / static_cast<double>(samples - 1));
  const double inf = std::numeric_limits<double>::infinity();
  EdgeRadiusLimit best{inf, 0.0, false, inf};
  if (geometry.max_concave_curvature_per_mm > 0)
    best = {1.0 / geometry.max_concave_curvature_per_mm, geometry.max_concave_curvature_at_x_mm, true, inf};
  if (geometry.max_concave_curvature_bound_per_mm > 0)
    best.curvature_bound_radius_mm = 1.0 / geometry.max_concave_curvature_bound_per_mm;
  double distant = inf, distant_x = 0.0;
  for (std::size_t i = 0; i < samples; ++i) {
    const Frame& p = frames[i];
    for (std::size_t j = 0; j < samples; ++j) {
      if (j + 1 >= i && j <= i + 1) continue;  // neighbours: the local term is exact
      const double dx = frames[j].x - p.x, dy = frames[j].y - p.y;
      const double along_normal = dx * p.nx + dy * p.ny;
      if (along_normal <= 0) continue;
      const double r = (dx * dx + dy * dy) / (2 * along_normal);
      if (r < distant) {
        distant = r;
        distant_x = p.x;
      }
    }
  }
  // A chord between nearby samples only approximates the local curvature, which the analysis
  // has exactly: the limit is "distant" only where a point beats the local radius by 0.1 %.
  if (distant < best.radius_mm * (1 - 1e-3)) {
    best.radius_mm = distant;
    best.x_mm = distant_x;
    best.local = false;
  } else {
    best.radius_mm = std::min(best.radius_mm, distant);
  }
  return best;
}

EdgeRadiusLimit largest_edge_radius(const Generatrix& generatrix, std::size_t samples) {
  return largest_edge_radius(generatrix, generatrix.analyse(default_geometry_resolution_mm), samples);
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
      if (i > 0) max_curvature_ = std::max(max_curvature_, std::abs(d1_[i] - d1_[i - 1]) / h_);
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
  // The same, with the profile continued along its end tangents beyond the part's ends: for the
  // contact's own cut when the replayed contact lies a rounding step past an end.
  double depth_continued(double qx, double qy) const {
    if (qx >= a_ && qx <= b_) return depth(qx, qy);
    const bool before = qx < a_;
    const double x0 = before ? a_ : b_, f0 = before ? f_.front() : f_.back(), d0 = before ? d1_.front() : d1_.back();
    return (f0 + d0 * (qx - x0) - qy) / std::sqrt(1.0 + d0 * d0);
  }
  double max_curvature_per_mm() const { return max_curvature_; }  // max |f''| (bounds curvature)

 private:
  double a_, b_, h_;
  std::vector<double> f_, d1_;
  double max_curvature_ = 0.0;
};

// The wheel section in the part frame: tool point (along, across) -> O + along U + across W.
struct ToolFrame {
  double ox, oy, ux, uy, wx, wy;
};

struct Deepest {
  double depth_mm, x_mm;
};

// The wheel section sampled once in its own frame, probed at each state: the deepest sample,
// refined by golden section between its neighbours only where it could matter. The depth along
// the section has a second derivative of at most k = (section curvature) + max |f''| per mm of
// arc, so no point between samples Delta apart lies more than k Delta^2 / 8 deeper than the
// deeper of them (`sampling_bound_mm`).
class SectionProbe {
 public:
  // Samples: enough that the sampling bound is at most half the tolerance (at least 64, at most
  // 4096), so that the golden-section refinement is needed only where a sample itself comes
  // within half the tolerance of interfering (the contact's own point lies on the section and
  // sits exactly at its own cut: with a coarser sampling every state would be refined).
  SectionProbe(const WheelSection& wheel, double part_curvature, double tolerance_mm) : wheel_(wheel) {
    half_angle_ = 0.5 * wheel.edge_angle_deg * std::numbers::pi / 180.0;
    const double width = wheel.profiled ? wheel.edge_radius_mm * 2 * half_angle_ : wheel.thickness_mm;
    const double k = (wheel.profiled ? 1.0 / wheel.edge_radius_mm : 0.0) + part_curvature;
    const double wanted = k > 0 ? width / std::sqrt(8.0 * 0.5 * tolerance_mm / k) : 0.0;
    samples_ = static_cast<int>(std::clamp(std::ceil(wanted), 64.0, 4096.0));
    for (int i = 0; i <= samples_; ++i) points_.push_back(tool_point(-1.0 + 2.0 * i / samples_));
    const double spacing = width / samples_;
    sampling_bound_mm_ = k * spacing * spacing / 8.0;
  }
  double sampling_bound_mm() const { return sampling_bound_mm_; }

  // Deepest point; refined where the coarse depth exceeds refine_above_mm.
  Deepest deepest(const TabulatedProfile& profile, const ToolFrame& f, double refine_above_mm) const {
    auto at = [&](const std::array<double, 2>& p) {
      const double qx = f.ox + p[0] * f.ux + p[1] * f.wx, qy = f.oy + p[0] * f.uy + p[1] * f.wy;
      return Deepest{profile.depth(qx, qy), qx};
    };
    Deepest best{-std::numeric_limits<double>::infinity(), 0.0};
    int best_i = 0;
    for (int i = 0; i <= samples_; ++i) {
      const Deepest d = at(points_[static_cast<std::size_t>(i)]);
      if (d.depth_mm > best.depth_mm) {
        best = d;
        best_i = i;
      }
    }
    if (!std::isfinite(best.depth_mm) || best.depth_mm <= refine_above_mm) return best;
    double lo = -1.0 + 2.0 * std::max(0, best_i - 1) / samples_;
    double hi = -1.0 + 2.0 * std::min(samples_, best_i + 1) / samples_;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 24; ++it) {
      const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
      if (at(tool_point(m1)).depth_mm > at(tool_point(m2)).depth_mm) hi = m2; else lo = m1;
    }
    const Deepest refined = at(tool_point(0.5 * (lo + hi)));
    return refined.depth_mm > best.depth_mm ? refined : best;
  }

 private:
  int samples_ = 64;
  std::array<double, 2> tool_point(double t) const {  // t in [-1, 1] along the section
    if (!wheel_.profiled) return {0.5 * wheel_.thickness_mm * t, 0.0};
    const double phi = half_angle_ * t, r = wheel_.edge_radius_mm;
    return {r * std::sin(phi), r * (1 - std::cos(phi))};
  }
  WheelSection wheel_;
  double half_angle_ = 0.0, sampling_bound_mm_ = 0.0;
  std::vector<std::array<double, 2>> points_;
};

constexpr std::size_t table_intervals = 20000;

}  // namespace

Interference check_interference(const Generatrix& generatrix, const WheelSection& wheel,
                                const std::vector<double>& contacts_mm, double tolerance_mm) {
  const TabulatedProfile profile(generatrix, table_intervals);
  const SectionProbe probe(wheel, profile.max_curvature_per_mm(), tolerance_mm);
  Interference out;
  out.tolerance_mm = tolerance_mm;
  for (double x : contacts_mm) {
    const Frame p = frame_at(generatrix, x);
    const Deepest d = probe.deepest(profile, {p.x, p.y, p.tx, p.ty, p.nx, p.ny},
                                    tolerance_mm - probe.sampling_bound_mm());
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
  const SectionProbe probe(wheel, profile.max_curvature_per_mm(), tolerance_mm);
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
    // A contact a rounding step beyond the part's end still has its own cut (the profile
    // continued along its end tangent).
    const double own_cut = std::max(0.0, profile.depth_continued(contact.x_mm, contact.y_mm));
    const Deepest d = probe.deepest(profile, frame, own_cut + tolerance_mm - probe.sampling_bound_mm());
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
