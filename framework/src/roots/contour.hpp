#pragma once
// Internal to find_rightmost_root: argument-principle zero counts on rectangles.
//
// The phase of E is tracked along straight edges with adaptive steps. A step is accepted only if
//   (a) the phase change is below max_phase_step (well under pi, so the principal value of
//       arg(E1/E0) is the true change),
//   (b) log(E1/E0) agrees with the local model E = c (s - r) e^{lambda s} fitted to E'/E at both
//       ends (exact while one zero dominates; two or more zeros acting within the step break
//       the fit), and
//   (c) the step is no longer than the larger of the two ends' Newton distances |E/E'| (a step
//       cannot jump over a zero that neither end is close to).
// Steps are proposed from the fitted model (the step that turns the phase by phase_step as seen
// from the fitted zero r, limited by the background lambda), so near a zero at distance d they
// shrink to ~d and between zeros they grow: a few evaluations per zero passed whatever d is.
// This is a numerical certificate (double precision, checked steps), not interval arithmetic;
// roots_test.cpp cross-checks it against a far more conservative setting on random rectangles,
// and docs/models/plunge_regenerative.md states the limits.
#include <cmath>
#include <optional>
#include <vector>

#include "roots/evaluator.hpp"

namespace chatterlab::roots_detail {

struct ContourSettings {
  double phase_step = 0.9;        // target phase change per step [rad]
  double max_phase_step = 1.5;    // accepted phase change per step [rad] (< pi/2)
  double consistency = 0.25;      // |log(E1/E0) - trapezoid of E'/E| accepted per step
  double magnitude_weight = 0.3;  // weight of |E'/E| (not only its phase part) in the step length
  double newton_distance_factor = 1.0;  // step <= this * min(|E/E'|) over the step's two ends
};

// A rectangle in the s plane. im_min == 0 marks a box symmetric about the real axis: only its
// upper half is tracked and conjugate symmetry supplies the rest (half the evaluations).
struct Box {
  double re_min = 0.0, re_max = 0.0, im_min = 0.0, im_max = 0.0;
  bool symmetric() const { return im_min == 0.0; }
  bool contains(Complex z) const;  // strictly inside (for symmetric boxes: the mirrored box)
  int multiplicity(Complex z) const;  // zeros of E implied by a root z (Im >= 0) inside the box
};

struct BoxCount {
  bool ok = false;
  int zeros = 0;            // zeros of E inside the (mirrored) box
  // Sum of those zeros and of their squares (trapezoid rule; estimates for Newton: with two
  // unknown zeros inside, the two sums give both, e.g. a conjugate pair in a mirrored box).
  Complex root_sum = 0.0, root_square_sum = 0.0;
  Complex failure_point;    // where the phase could not be resolved (when !ok)
};

class ContourTracker {
 public:
  ContourTracker(Evaluator& evaluate, ContourSettings settings)
      : evaluate_(evaluate), settings_(settings), tan_phase_step_(std::tan(settings.phase_step)) {}

  BoxCount count(const Box& box);

 private:
  struct Node {
    Complex s;
    Complex log_derivative;  // E'/E
    double arg = 0.0;
    double log_abs = 0.0;
  };
  struct PathIntegral {
    double phase = 0.0;
    Complex moment = 0.0, moment2 = 0.0;  // integrals of (s - c) E'/E ds and (s - c)^2 E'/E ds
  };

  struct LocalModel {
    Complex log_change;   // predicted log E(s1) - log E(s0)
    bool has_zero = false;
    Complex zero;         // r
    Complex background;   // lambda
  };

  std::optional<Node> node(Complex s);
  static LocalModel fit(const Node& a, const Node& b);
  void add_moments(const Node& a, const Node& b, const LocalModel& model, PathIntegral& sum) const;
  double model_step(const LocalModel& model, Complex s, Complex direction) const;
  bool segment(const Node& from, const Node& to, PathIntegral& sum, Complex& failure_point);
  bool path(const std::vector<Complex>& vertices, PathIntegral& sum, Complex& failure_point);

  Evaluator& evaluate_;
  ContourSettings settings_;
  double tan_phase_step_;  // tan(settings_.phase_step), for model_step
  Complex centre_ = 0.0;  // moments are taken about this point
};

}  // namespace chatterlab::roots_detail
