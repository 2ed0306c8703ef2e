#pragma once
// Angle-indexed memory of one regenerated surface (wheel or work): samples at the cumulative
// rotation angles k * 2 pi / n (k = 0, 1, ...), written as the contact point passes them, read
// "one revolution ago" at any angle by cubic Lagrange interpolation. Indices k < 0 are the
// surface before the run (the initial profile, periodic). A ring of >= n + margin samples is
// enough: reads never reach further back than one revolution and a few samples.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace chatterlab::dynamics_detail {

class SurfaceMemory {
 public:
  // samples_per_rev >= 16; initial_profile empty (a flat surface) or of size samples_per_rev.
  // with_integral: keep the running integral that mean() over an arc needs (geometric
  // filtering); without it mean() takes arc 0 only (half the memory and work per sample).
  SurfaceMemory(std::size_t samples_per_rev, std::vector<double> initial_profile, bool with_integral = true);

  std::size_t samples_per_rev() const { return n_; }
  double spacing_rad() const { return spacing_; }
  std::int64_t next_index() const { return next_; }

  // The sample at index k (k < next_index(), and not older than one revolution + margin).
  // Inline ring path: every surface write reads the sample one revolution back and pushes one.
  double value(std::int64_t k) const { return k >= 0 ? ring_[slot(k)] : initial_value(k); }
  // Appends the sample of index next_index().
  void push(double value) {
    if (with_integral_) push_integral(value);
    ring_[slot(next_)] = value;
    ++next_;
  }

  // Surface at cumulative angle theta [rad] (theta <= the last written angle; interpolation
  // needs one sample beyond the interval, clamped to the last written one at the front).
  double at(double theta_rad) const {
    // Inline fast path (every right-hand side reads here twice): the stencil inside the
    // written ring; everything else (initial profile, front of the ring) in interpolate().
    const double x = theta_rad * samples_per_rad_;
    // Truncation, not std::floor: they agree for x >= 1, the only case taken here, and floor
    // has no single instruction in the baseline x86-64 build (it expands to ~8 dependent ones,
    // twice per right-hand side).
    const auto i = static_cast<std::int64_t>(x);
    if (!(x >= 1.0) || i + 3 > next_) {
      // A flat start (the usual one): zero while the whole stencil is before the run, e.g. the
      // work surface during the whole first work revolution.
      if (flat_ && x < -2.0) return 0.0;
      return interpolate(theta_rad, false);
    }
    double w[4];
    cubic_weights(x - static_cast<double>(i), w);
    const std::size_t mask = capacity_ - 1;
    const auto k = static_cast<std::size_t>(i);
    return w[0] * ring_[(k - 1) & mask] + w[1] * ring_[k & mask] + w[2] * ring_[(k + 1) & mask] +
           w[3] * ring_[(k + 2) & mask];
  }
  // Cubic Lagrange weights through i-1..i+2 at offset v from i (products by constants: no
  // division in the innermost read).
  static void cubic_weights(double v, double w[4]) {
    constexpr double sixth = 1.0 / 6.0;
    const double vp = v + 1.0, vm = v - 1.0, vmm = v - 2.0;
    w[0] = -sixth * v * vm * vmm;
    w[1] = 0.5 * vp * vm * vmm;
    w[2] = -0.5 * vp * v * vmm;
    w[3] = sixth * vp * v * vm;
  }
  // True if at(theta) reads written (or initial-profile) samples only: pushes cannot change it.
  bool settled(double theta_rad) const {
    return theta_rad * samples_per_rad_ + 3.0 < static_cast<double>(next_);
  }
  // Mean of the surface over [theta - arc/2, theta + arc/2] (geometric filtering), from the
  // running integral of the samples; arc = 0 gives at(theta).
  double mean(double theta_rad, double arc_rad) const {
    return arc_rad <= 0.0 ? at(theta_rad) : arc_mean(theta_rad, arc_rad);
  }

  // Mean of the interpolated surface (the cubic that at() reads) over the angles [theta_a,
  // theta_b] (theta_a <= theta_b, both well behind the newest sample), integrated exactly: the
  // fixed-step engine's forcing over a step (a point sample would alias a rough surface).
  double average(double theta_a_rad, double theta_b_rad) const;

  // The surface over the last revolution: samples k = next - n .. next - 1 by body angle
  // (k mod n) * spacing, returned in body-angle order 0 .. n - 1.
  std::vector<double> last_revolution() const;

 private:
  double arc_mean(double theta_rad, double arc_rad) const;
  double integral(std::int64_t k) const;  // trapezoid integral of the samples from k = -2n
  double interpolate(double theta_rad, bool of_integral) const;
  double initial_value(std::int64_t k) const;  // k < 0: the surface before the run
  void push_integral(double value);            // the running integral at next_index()
  std::size_t slot(std::int64_t k) const {
    return static_cast<std::size_t>(k) & (capacity_ - 1);  // k >= 0 here
  }

  std::size_t n_, capacity_;
  double spacing_;
  double samples_per_rad_;  // 1 / spacing_ (a multiply per read instead of a division)
  std::int64_t next_ = 0;
  bool flat_;           // initial profile empty: zero before the run
  bool with_integral_;  // ring_integral_ kept
  std::vector<double> initial_;           // n samples, body angle order
  std::vector<double> initial_unrolled_;  // the initial profile at k = -2n .. -1 (no modulo per read)
  std::vector<double> initial_integral_;  // integral at k = -2n .. 0
  std::vector<double> ring_, ring_integral_;
};

}  // namespace chatterlab::dynamics_detail
