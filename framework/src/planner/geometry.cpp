#include "planner/geometry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace chatterlab::planner {

namespace {

double turn_rate(const Jet& j) { return std::abs(j.d2) / (1.0 + j.d1 * j.d1); }
double curvature(const Jet& j) { return j.d2 / std::pow(1.0 + j.d1 * j.d1, 1.5); }

// The running maxima every analysis reports.
struct Maxima {
  double concave = 0.0, concave_x = 0.0, turn = 0.0, turn_x = 0.0;
  void visit(double x, const Jet& j) {
    if (!std::isfinite(j.d1) || !std::isfinite(j.d2)) return;
    const double k = curvature(j), t = turn_rate(j);
    if (k > concave) {
      concave = k;
      concave_x = x;
    }
    if (t > turn) {
      turn = t;
      turn_x = x;
    }
  }
  void store(GeometryAnalysis& out) const {
    out.max_concave_curvature_per_mm = concave;
    out.max_concave_curvature_at_x_mm = concave_x;
    out.max_turn_rate_rad_per_mm = turn;
    out.max_turn_rate_at_x_mm = turn_x;
  }
};

// Sites closer than `gap` describe one place: keep the largest of each kind.
std::vector<Singularity> merge_sites(std::vector<Singularity> sites, double gap) {
  std::sort(sites.begin(), sites.end(), [](const Singularity& p, const Singularity& q) { return p.x_mm < q.x_mm; });
  std::vector<Singularity> out;
  for (const Singularity& s : sites) {
    auto same = std::find_if(out.rbegin(), out.rend(), [&](const Singularity& o) {
      return o.kind == s.kind && std::abs(o.x_mm - s.x_mm) <= gap;
    });
    if (same == out.rend()) out.push_back(s);
    else if (s.size > same->size) *same = s;
  }
  std::sort(out.begin(), out.end(), [](const Singularity& p, const Singularity& q) { return p.x_mm < q.x_mm; });
  return out;
}

}  // namespace

GeometryAnalysis analyse_expression(const Expression& e, double a, double b, double resolution_mm) {
  GeometryAnalysis out;
  out.resolution_mm = resolution_mm;
  out.method =
      "interval enclosures of f, f', f'' over the whole range (branch and bound); switches of "
      "abs, sign, rint, min, max, comparisons and ?: located to 1e-10 of the range and "
      "classified from exact one-sided derivatives";
  const double span = b - a;
  const double locate = std::max(1e-10 * span, 64 * std::numeric_limits<double>::epsilon() *
                                                   std::max({1.0, std::abs(a), std::abs(b)}));
  const double feature_width = resolution_mm / 64;
  const double turn_limit = 1.0 / resolution_mm;
  constexpr std::size_t budget = 4'000'000;

  Maxima maxima;
  auto point = [&](double x) {
    const Jet j = e.jet(x);
    maxima.visit(x, j);
    return j;
  };
  // Seed the maximum with a grid (the branch and bound then only refines near it).
  for (int k = 0; k <= 4096; ++k) point(a + span * k / 4096.0);

  std::vector<Singularity> sites;
  auto site = [&](Singularity::Kind kind, double x, double size, bool concave = false) {
    sites.push_back({kind, x, size, concave});
  };
  // A tiny interval that may switch or leave the domain: exact one-sided jets just outside it
  // (clamped to the range) tell a jump, a kink or a smooth junction apart.
  auto classify = [&](const Interval& x, bool switching) {
    const double w = x.width();
    const double left = std::max(a, x.lo - w), right = std::min(b, x.hi + w);
    const Jet jl = e.jet(left), jm = e.jet(x.mid()), jr = e.jet(right);
    for (const auto& [at, j] : {std::pair{left, jl}, std::pair{x.mid(), jm}, std::pair{right, jr}}) {
      if (!std::isfinite(j.v)) return site(Singularity::Kind::not_finite, at, 0.0);
      if (!std::isfinite(j.d1)) return site(Singularity::Kind::vertical_tangent, at, 0.0);
      if (!std::isfinite(j.d2))
        return site(Singularity::Kind::narrow_feature, at, std::numeric_limits<double>::infinity());
    }
    if (!switching) return;
    const double width = right - left;
    const double jump = jr.v - jl.v - 0.5 * (jl.d1 + jr.d1) * width;
    const double kink = jr.d1 - jl.d1 - 0.5 * (jl.d2 + jr.d2) * width;
    if (std::abs(jump) > 1e-9 * std::max(1.0, std::abs(jl.v)))
      site(Singularity::Kind::jump, x.mid(), std::abs(jump));
    else if (std::abs(kink) > 1e-8 * std::max(1.0, std::abs(jl.d1)))
      site(Singularity::Kind::kink, x.mid(), std::abs(kink), kink > 0);
  };

  std::vector<Interval> stack;
  for (int k = 63; k >= 0; --k) stack.push_back({a + span * k / 64.0, k == 63 ? b : a + span * (k + 1) / 64.0});
  double bound = 0.0;
  std::size_t evaluations = 0;
  while (!stack.empty()) {
    const Interval x = stack.back();
    stack.pop_back();
    if (++evaluations > budget)
      throw std::invalid_argument(fmt::format(
          "the expression could not be analysed within {} interval evaluations (stuck near x = "
          "{:.6g}); simplify it", budget, x.mid()));
    const IntervalJet j = e.enclose(x);
    const double w = x.width();
    auto split = [&] {
      const double m = x.mid();
      stack.push_back({m, x.hi});
      stack.push_back({x.lo, m});
    };
    if (j.may_be_undefined || !j.v.finite() || !j.d1.finite() || !j.d2.finite()) {
      // A whole sub-range outside the domain is reported at its middle, not bisected away.
      if (!std::isfinite(e.jet(x.mid()).v)) {
        site(Singularity::Kind::not_finite, x.mid(), 0.0);
        continue;
      }
      if (w > locate) split();
      else classify(x, j.may_switch);
      continue;
    }
    if (j.may_switch) {
      if (w > locate) split();
      else classify(x, true);
      continue;
    }
    const Interval s = Interval::point(1.0) + sqr(j.d1);
    const Interval turn = j.d2 / s;
    const Interval concave = turn / sqrt(s);
    const Jet mid = point(x.mid());
    if (turn.magnitude() > turn_limit) {
      if (w > feature_width) {
        split();
        continue;
      }
      if (turn_rate(mid) > turn_limit) {
        site(Singularity::Kind::narrow_feature, x.mid(), turn_rate(mid));
        bound = std::max(bound, concave.hi);
        continue;  // refused anyway: no need to resolve the curvature there
      }
    }
    // Concave curvatures below 1e-7 /mm (radii beyond 10 km) limit no wheel.
    if (concave.hi > maxima.concave * (1 + 1e-7) + 1e-7 && w > locate) {
      split();
      continue;
    }
    bound = std::max(bound, concave.hi);
  }
  out.evaluations = evaluations + 4097;
  maxima.store(out);
  out.max_concave_curvature_bound_per_mm = std::max(bound, maxima.concave);
  out.singularities = merge_sites(std::move(sites), std::max(1e3 * locate, 1e-3 * resolution_mm));
  // Narrow features: one report per resolution-wide place.
  std::vector<Singularity> merged, narrow;
  for (const Singularity& s : out.singularities)
    (s.kind == Singularity::Kind::narrow_feature ? narrow : merged).push_back(s);
  for (const Singularity& s : merge_sites(std::move(narrow), resolution_mm)) merged.push_back(s);
  std::sort(merged.begin(), merged.end(), [](const Singularity& p, const Singularity& q) { return p.x_mm < q.x_mm; });
  out.singularities = std::move(merged);
  // A concave kink is a corner of infinite curvature: no edge radius fits there.
  for (const Singularity& s : out.singularities)
    if (s.kind == Singularity::Kind::kink && s.concave) {
      out.max_concave_curvature_per_mm = out.max_concave_curvature_bound_per_mm =
          std::numeric_limits<double>::infinity();
      out.max_concave_curvature_at_x_mm = s.x_mm;
      break;
    }
  return out;
}

GeometryAnalysis analyse_spline(const CubicSpline& spline, double resolution_mm) {
  GeometryAnalysis out;
  out.resolution_mm = resolution_mm;
  out.method =
      "natural cubic spline (C2: no jumps or kinks); curvature and turn rate maximised piece by "
      "piece (32 samples, knots included, golden-section refinement); the bound from f'' "
      "(linear) and the smallest |f'| (quadratic) of each piece";
  Maxima maxima;
  std::vector<Singularity> sites;
  double bound = 0.0;
  std::size_t evaluations = 0;
  const std::size_t pieces = spline.x.size() - 1;
  constexpr int samples = 32;
  for (std::size_t i = 0; i < pieces; ++i) {
    const double x0 = spline.x[i], x1 = spline.x[i + 1], h = x1 - x0;
    double best = -std::numeric_limits<double>::infinity();
    int best_k = 0;
    for (int k = 0; k <= samples; ++k) {
      const double x = k == samples ? x1 : x0 + h * k / samples;
      const Jet j = spline.evaluate(x);
      ++evaluations;
      maxima.visit(x, j);
      if (turn_rate(j) > 1.0 / resolution_mm) sites.push_back({Singularity::Kind::narrow_feature, x, turn_rate(j)});
      if (curvature(j) > best) {
        best = curvature(j);
        best_k = k;
      }
    }
    // Golden section on the concave curvature around the best sample.
    double lo = x0 + h * std::max(0, best_k - 1) / samples, hi = x0 + h * std::min(samples, best_k + 1) / samples;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 50; ++it) {
      const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
      evaluations += 2;
      if (curvature(spline.evaluate(m1)) > curvature(spline.evaluate(m2))) hi = m2; else lo = m1;
    }
    maxima.visit(0.5 * (lo + hi), spline.evaluate(0.5 * (lo + hi)));
    // Bound: f'' is linear on the piece (largest at an end); |f'| is at least its smallest value
    // over the piece (ends and the vertex of the quadratic f').
    const double d2max = std::max(spline.m[i], spline.m[i + 1]);
    if (d2max > 0) {
      std::vector<double> slopes{spline.evaluate(x0).d1, spline.evaluate(x1).d1};
      if (spline.m[i + 1] != spline.m[i]) {  // f'' = 0 inside: the vertex of f'
        const double t = spline.m[i] / (spline.m[i] - spline.m[i + 1]);
        if (t > 0 && t < 1) slopes.push_back(spline.evaluate(x0 + t * h).d1);
      }
      double min_slope = std::numeric_limits<double>::infinity();
      for (double v : slopes) min_slope = std::min(min_slope, std::abs(v));
      const auto [lo_s, hi_s] = std::minmax_element(slopes.begin(), slopes.end());
      if (*lo_s <= 0 && *hi_s >= 0) min_slope = 0.0;  // f' passes through zero
      bound = std::max(bound, d2max / std::pow(1.0 + min_slope * min_slope, 1.5));
    }
  }
  out.evaluations = evaluations;
  maxima.store(out);
  out.max_concave_curvature_bound_per_mm = std::max(bound, maxima.concave);
  out.singularities = merge_sites(std::move(sites), resolution_mm);
  return out;
}

}  // namespace chatterlab::planner
