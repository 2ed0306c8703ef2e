#include "planner/wheel_limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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

Interference check_interference(const Generatrix& generatrix, const WheelSection& wheel,
                                const std::vector<double>& contacts_mm,
                                const std::vector<double>& contact_on_tool_mm,
                                double tolerance_mm) {
  const double a = generatrix.x_min_mm(), b = generatrix.x_max_mm();
  constexpr int samples = 64;
  Interference out;
  for (std::size_t k = 0; k < contacts_mm.size(); ++k) {
    const Frame p = frame_at(generatrix, contacts_mm[k]);
    const double zeta = contact_on_tool_mm.empty() ? 0.0 : contact_on_tool_mm[k];
    double deepest = 0.0;
    for (int i = 0; i <= samples; ++i) {
      double qx = 0.0, qy = 0.0;
      if (!wheel.profiled) {
        // Face from -a/2 to a/2 about the wheel's middle; the contact sits at zeta on it.
        const double t = -0.5 * wheel.thickness_mm + wheel.thickness_mm * i / samples - zeta;
        qx = p.x + t * p.tx;
        qy = p.y + t * p.ty;
      } else {
        // The arc spans +-alpha/2 about its middle; the contact sits at arc angle zeta / r.
        const double half = 0.5 * wheel.edge_angle_deg * std::numbers::pi / 180.0;
        const double phi = -half + 2 * half * i / samples - zeta / wheel.edge_radius_mm;
        const double r = wheel.edge_radius_mm;
        // Arc centre at P + r n; arc point at angle phi from the contact direction -n.
        const double cx = p.x + r * p.nx, cy = p.y + r * p.ny;
        qx = cx - r * (std::cos(phi) * p.nx - std::sin(phi) * p.tx);
        qy = cy - r * (std::cos(phi) * p.ny - std::sin(phi) * p.ty);
      }
      if (qx < a || qx > b) continue;  // beyond the part's ends: no material
      const double depth = (generatrix.evaluate(qx).f - qy) * p.ny;  // along the normal, approx.
      deepest = std::max(deepest, depth);
    }
    if (deepest > tolerance_mm) {
      ++out.contacts_with_interference;
      if (deepest > out.depth_mm) {
        out.depth_mm = deepest;
        out.x_mm = p.x;
      }
    }
  }
  return out;
}

}  // namespace chatterlab::planner
