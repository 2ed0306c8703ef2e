// The Nyquist count on the imaginary axis (chatterlab/nyquist.hpp).
//
// The axis is cut at the model's fast frequencies (delay lattices). Inside each piece the phase of
// F is followed with steps that double while the phase moves less than pi/6 per step and halve
// otherwise; towards either end of a piece the steps also shrink geometrically (at most half the
// remaining distance), down to 1e-12 of the piece. So a turn of F packed into a tiny neighbourhood
// of a lattice point (the wheel chain's, whose width scales with kc/kg) is followed, not jumped.
#include "chatterlab/nyquist.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace chatterlab {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMaxPhaseStep = kPi / 6.0;
constexpr double kEndFraction = 1e-12;  // closest approach to a piece's ends, relative to its length

struct Tracker {
  const ReturnDifference& f;
  NyquistCount& count;
  double phase = 0.0;        // unwrapped arg F
  double start_phase = 0.0;  // arg F just above w = 0
  bool started = false;
  Complex last = 0.0;

  Complex value(double w) {
    const Complex v = f.at(w).value;
    ++count.evaluations;
    if (std::abs(v) < count.min_modulus) {
      count.min_modulus = std::abs(v);
      count.min_modulus_frequency_hz = w / (2.0 * kPi);
    }
    return v;
  }

  // The phase change between two values (principal value).
  static double turn(Complex from, Complex to) { return std::arg(to / from); }

  // Follows the phase over the open piece (a, b). Returns false when a step had to shrink below
  // the resolution (F too close to 0: a root on the axis).
  bool follow(double a, double b) {
    const double length = b - a;
    const double closest = kEndFraction * length;
    double t = a + closest;
    Complex v = value(t);
    if (started) {
      phase += turn(last, v);
    } else {
      phase = start_phase = std::arg(v);
      started = true;
    }
    last = v;
    double h = closest;
    while (b - t > closest) {
      // Geometric approach to b: never more than half the remaining distance.
      h = std::min(h, 0.5 * (b - t));
      const double next = t + h;
      const Complex w = value(next);
      const double d = turn(last, w);
      if (std::abs(d) > kMaxPhaseStep || !std::isfinite(d)) {
        h *= 0.5;
        if (h < 1e-15 * std::max(b, 1.0)) return false;
        continue;
      }
      phase += d;
      last = w;
      t = next;
      h *= 2.0;
    }
    return true;
  }
};

}  // namespace

NyquistCount count_unstable_roots(const ReturnDifference& f) {
  NyquistCount count;
  count.min_modulus = std::numeric_limits<double>::infinity();
  const double limit = f.winding_limit_rad_s();
  if (!(limit > 0.0)) {
    count.min_modulus = 0.0;
    count.note = "|F - 1| < 1 on the whole axis: nothing can be unstable";
    return count;
  }
  std::vector<double> cuts;
  f.fast_frequencies(limit, cuts);
  cuts.push_back(0.0);
  cuts.push_back(limit);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::remove_if(cuts.begin(), cuts.end(), [&](double w) { return w < 0.0 || w > limit; }), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end(),
                         [&](double a, double b) { return b - a <= 1e-13 * std::max(limit, 1.0); }),
             cuts.end());
  Tracker tracker{f, count, 0.0, 0.0, false, 0.0};
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    if (!tracker.follow(cuts[i], cuts[i + 1])) {
      count.reliable = false;
      count.note = fmt::format("F(j w) passes too close to 0 near {:.6g} Hz: a root on the imaginary axis",
                               count.min_modulus_frequency_hz);
      return count;
    }
  }
  // F(0) is real: the phase starts at a multiple of pi. Beyond the limit F stays in Re F > 0 and
  // tends to 1: the phase ends at the multiple of 2 pi nearest to where it was left.
  const double begin = kPi * std::round(tracker.start_phase / kPi);
  const double end = 2.0 * kPi * std::round(tracker.phase / (2.0 * kPi));
  const long n = std::lround(-(end - begin) / kPi);
  count.unstable_roots = static_cast<int>(n);
  if (n < 0) {
    count.reliable = false;
    count.note = fmt::format("negative count {}: F has poles in the right half plane", n);
  }
  return count;
}

}  // namespace chatterlab
