#include "roots/contour.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace chatterlab::roots_detail {

namespace {

double wrap_phase(double phase) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  phase = std::fmod(phase, two_pi);
  if (phase > std::numbers::pi) phase -= two_pi;
  if (phase <= -std::numbers::pi) phase += two_pi;
  return phase;
}

}  // namespace

// The local model E(s) = c (s - r) e^{lambda s} (one zero r near the step, smooth background
// lambda), fitted exactly to L0 = E'/E(s0) and L1 = E'/E(s1). Unlike the trapezoid rule the model
// is exact while a single zero dominates, so a step may approach or leave a nearby zero in one go;
// when two or more zeros act within the step the fit fails the consistency test and the step is
// refined.
ContourTracker::LocalModel ContourTracker::fit(const Node& a, const Node& b) {
  const Complex ds = b.s - a.s;
  const Complex dl = a.log_derivative - b.log_derivative;
  LocalModel model;
  model.log_change = 0.5 * (a.log_derivative + b.log_derivative) * ds;  // trapezoid
  model.background = 0.5 * (a.log_derivative + b.log_derivative);
  if (magnitude(dl) * magnitude(ds) < 1e-3) return model;  // L nearly constant: no zero nearby
  // 1/(s0 - r) - 1/(s1 - r) = L0 - L1  <=>  u (u + ds) = ds / dl with u = s0 - r.
  const Complex root_disc = square_root(ds * ds + 4.0 * divide(ds, dl));
  double best_background = std::numeric_limits<double>::infinity();
  Complex best_u = 0.0, best_lambda = 0.0;
  for (Complex u : {0.5 * (-ds + root_disc), 0.5 * (-ds - root_disc)}) {
    if (u == Complex(0.0) || u + ds == Complex(0.0)) continue;
    const Complex lambda = a.log_derivative - divide(1.0, u);
    // Of the two exact fits (r and its reflection through the midpoint) the physical one has the
    // smoother background.
    if (magnitude(lambda) < best_background) {
      best_background = magnitude(lambda);
      best_u = u;
      best_lambda = lambda;
    }
  }
  if (best_u != Complex(0.0)) {
    model.log_change = logarithm(divide(best_u + ds, best_u)) + best_lambda * ds;
    model.has_zero = true;
    model.zero = a.s - best_u;
    model.background = best_lambda;
  }
  return model;
}

// Step that changes the phase by about phase_step according to the model: the zero r subtends
// the angle arg(s - r) measured along the path; the background adds Im(lambda ds).
double ContourTracker::model_step(const LocalModel& model, Complex s, Complex direction) const {
  const double theta = settings_.phase_step;
  double step = theta / std::max(std::abs((model.background * direction).imag()), 1e-300);
  if (!model.has_zero) return step;
  const Complex w = (s - model.zero) * std::conj(direction);  // the zero at the origin, path along +real
  const double x = w.real(), y = std::abs(w.imag());
  if (y == 0.0) return 0.0;
  // The angle a = atan2(y, x) subtended by the zero decreases towards 0 along the path; the step
  // to a - theta (when a > theta) is y cot(a - theta) - x = tan(theta) |w|^2 / (y - x tan(theta)),
  // and a > theta exactly when y - x tan(theta) > 0 (a in (0, pi), theta < pi/2): no atan2, no
  // tan per step.
  const double denominator = y - x * tan_phase_step_;
  if (denominator > 0.0) step = std::min(step, tan_phase_step_ * (x * x + y * y) / denominator);
  return step;
}

bool Box::contains(Complex z) const {
  bool re_inside = z.real() > re_min && z.real() < re_max;
  if (symmetric()) return re_inside && std::abs(z.imag()) < im_max;
  return re_inside && z.imag() > im_min && z.imag() < im_max;
}

int Box::multiplicity(Complex z) const {
  if (!contains(z)) return 0;
  if (!symmetric()) return 1;
  return z.imag() == 0.0 ? 1 : 2;  // the mirrored box also holds the conjugate
}

std::optional<ContourTracker::Node> ContourTracker::node(Complex s) {
  CharacteristicValue e = evaluate_(s);
  if (!is_finite(e.value) || !is_finite(e.derivative) || e.value == Complex(0.0))
    return std::nullopt;
  // |E| itself may be huge (e^{tau |Re s|}): logarithm() guards the squares.
  const Complex log_value = logarithm(e.value);
  if (!is_finite(log_value)) return std::nullopt;
  Node n;
  n.s = s;
  n.log_derivative = divide(e.derivative, e.value);
  n.arg = log_value.imag();
  n.log_abs = log_value.real();
  if (!is_finite(n.log_derivative)) return std::nullopt;
  return n;
}

bool ContourTracker::segment(const Node& from, const Node& to, PathIntegral& sum,
                             Complex& failure_point) {
  const Complex delta = to.s - from.s;
  const double length = std::abs(delta);
  if (length == 0.0) return true;
  const Complex direction = delta / length;
  // Below this a step cannot move s by more than a few ulps: a zero sits on the edge.
  const double min_step =
      64.0 * std::numeric_limits<double>::epsilon() *
      std::max({magnitude(from.s), magnitude(to.s), length * 1e-3, 1e-300});
  // Step from the derivative alone (no model yet): mostly the phase part of E'/E along the path,
  // with some weight on |E'/E| (~ 1/distance to the nearest zero) so a zero ahead is not rushed.
  auto rate_step = [&](const Node& n) {
    double along_phase = std::abs((n.log_derivative * direction).imag());
    return settings_.phase_step /
           std::max({along_phase, settings_.magnitude_weight * magnitude(n.log_derivative), 1e-300});
  };

  Node current = from;
  double position = 0.0, previous_step = length;
  std::optional<LocalModel> model;  // fitted on the last accepted step
  while (position < length) {
    double proposal = model ? model_step(*model, current.s, direction) : rate_step(current);
    if (!(proposal > 0.0)) proposal = rate_step(current);
    double step = std::min({proposal, 4.0 * previous_step, length - position});
    for (;;) {
      bool last = position + step >= length * (1.0 - 1e-15);
      std::optional<Node> next =
          last ? std::optional<Node>(to) : node(from.s + direction * (position + step));
      if (next) {
        const double phase_change = wrap_phase(next->arg - current.arg);
        const double l0 = magnitude(current.log_derivative), l1 = magnitude(next->log_derivative);
        // The step may not be longer than the larger of its ends' Newton distances |E/E'| (~ the
        // distance to the nearest zero): this refuses a long step that passes zeros in its
        // middle while the one-zero model still fits its ends (two zeros on one side make the
        // principal phase off by exactly 2 pi; found by the cross-check test in roots_test.cpp).
        // The cheap tests first: the local model is fitted only for a step that passes them (the
        // same tests and results; ~14 % of the fits were for steps these two refuse).
        if (std::abs(phase_change) <= settings_.max_phase_step &&
            step * std::min(l0, l1) <= settings_.newton_distance_factor) {
          const Complex log_change(next->log_abs - current.log_abs, phase_change);
          const LocalModel fitted = fit(current, *next);
          if (magnitude(log_change - fitted.log_change) <= settings_.consistency) {
            sum.phase += phase_change;
            add_moments(current, *next, fitted, sum);
            current = *next;
            position = last ? length : position + step;
            previous_step = step;
            model = fitted;
            break;
          }
        }
      }
      model.reset();
      step *= 0.4;
      if (step < min_step) {
        failure_point = current.s + direction * step;
        return false;
      }
    }
  }
  return true;
}

// The moments integral (s - c)^k E'/E ds, k = 1, 2, over an accepted step: exactly for the
// step's local model E'/E = 1/(s - r) + lambda (a nearby zero r, background lambda), trapezoid
// where no zero was fitted. The trapezoid alone, on steps that turn the phase by ~1 rad, left the
// moments 10-20 % off; the repair starts Newton from them.
void ContourTracker::add_moments(const Node& a, const Node& b, const LocalModel& model, PathIntegral& sum) const {
  const Complex ua = a.s - centre_, ub = b.s - centre_, ds = b.s - a.s;
  if (!model.has_zero) {
    const Complex ga = ua * a.log_derivative, gb = ub * b.log_derivative;
    sum.moment += 0.5 * (ga + gb) * ds;
    sum.moment2 += 0.5 * (ua * ga + ub * gb) * ds;
    return;
  }
  // log((s1 - r)/(s0 - r)) is the model's log change without its background part.
  const Complex log_ratio = model.log_change - model.background * ds, d = model.zero - centre_;
  const Complex ua2 = ua * ua, ub2 = ub * ub;
  sum.moment += ds + d * log_ratio + model.background * 0.5 * (ub2 - ua2);
  sum.moment2 += 0.5 * (ub2 - ua2) + d * ds + d * d * log_ratio + model.background * (ub2 * ub - ua2 * ua) / 3.0;
}

bool ContourTracker::path(const std::vector<Complex>& vertices, PathIntegral& sum,
                          Complex& failure_point) {
  std::optional<Node> previous = node(vertices.front());
  if (!previous) {
    failure_point = vertices.front();
    return false;
  }
  const std::optional<Node> first = previous;
  for (std::size_t i = 1; i < vertices.size(); ++i) {
    // A closed path ends where it started: reuse that node (same phase reference).
    bool closing = vertices[i] == vertices.front();
    std::optional<Node> next = closing ? first : node(vertices[i]);
    if (!next) {
      failure_point = vertices[i];
      return false;
    }
    if (!segment(*previous, *next, sum, failure_point)) return false;
    previous = next;
  }
  return true;
}

BoxCount ContourTracker::count(const Box& box) {
  BoxCount result;
  // Moments about the box centre (real for a mirrored box): smaller integrands, better estimates.
  centre_ = Complex(0.5 * (box.re_min + box.re_max), box.symmetric() ? 0.0 : 0.5 * (box.im_min + box.im_max));
  PathIntegral sum;
  double winding = 0.0;
  if (box.symmetric()) {
    // Upper half of the mirrored box, from the right end on the real axis round to the left end.
    // E(conj s) = conj E(s), so the lower half contributes the same phase change: total winding
    // = phase / pi. The lower half's moment is -conj of the upper half's.
    std::vector<Complex> vertices = {Complex(box.re_max, 0.0), Complex(box.re_max, box.im_max),
                                     Complex(box.re_min, box.im_max), Complex(box.re_min, 0.0)};
    if (!path(vertices, sum, result.failure_point)) return result;
    winding = sum.phase / std::numbers::pi;
    result.root_sum = Complex(sum.moment.imag() / std::numbers::pi, 0.0);
    result.root_square_sum = Complex(sum.moment2.imag() / std::numbers::pi, 0.0);
  } else {
    std::vector<Complex> vertices = {Complex(box.re_max, box.im_min), Complex(box.re_max, box.im_max),
                                     Complex(box.re_min, box.im_max), Complex(box.re_min, box.im_min),
                                     Complex(box.re_max, box.im_min)};
    if (!path(vertices, sum, result.failure_point)) return result;
    winding = sum.phase / (2.0 * std::numbers::pi);
    result.root_sum = sum.moment / Complex(0.0, 2.0 * std::numbers::pi);
    result.root_square_sum = sum.moment2 / Complex(0.0, 2.0 * std::numbers::pi);
  }
  double rounded = std::round(winding);
  // Every accepted step is resolved to well under pi, so a total far from an integer means the
  // tracking is not trustworthy (e.g. loss of precision in E); report it as a failure.
  if (std::abs(winding - rounded) > 0.05 || rounded < 0.0) {
    result.failure_point = Complex(box.re_min, box.im_max);
    return result;
  }
  result.ok = true;
  result.zeros = static_cast<int>(rounded);
  // Moments were taken about the centre c: sum r = S1 + n c, sum r^2 = S2 + 2 c S1 + n c^2.
  result.root_square_sum += 2.0 * centre_ * result.root_sum + centre_ * centre_ * rounded;
  result.root_sum += centre_ * rounded;
  return result;
}

}  // namespace chatterlab::roots_detail
