#include "dynamics/surface_memory.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace chatterlab::dynamics_detail {

namespace {
constexpr std::size_t kMargin = 16;  // samples kept beyond one revolution (stencil + arc slack)
}

SurfaceMemory::SurfaceMemory(std::size_t samples_per_rev, std::vector<double> initial_profile,
                             bool with_integral)
    : n_(samples_per_rev),
      // A power of two: the ring index is a mask, not an integer division (four per read).
      capacity_(std::bit_ceil(samples_per_rev + kMargin)),
      spacing_(2.0 * std::numbers::pi / static_cast<double>(samples_per_rev)),
      samples_per_rad_(static_cast<double>(samples_per_rev) / (2.0 * std::numbers::pi)),
      flat_(initial_profile.empty()),
      with_integral_(with_integral),
      initial_(std::move(initial_profile)),
      ring_(capacity_, 0.0) {
  if (n_ < 16) throw std::logic_error("SurfaceMemory: fewer than 16 samples per revolution");
  if (with_integral_) ring_integral_.assign(capacity_, 0.0);
  // A flat initial surface (the usual start) needs no arrays for k < 0: value and integral are 0.
  if (flat_) return;
  if (initial_.size() != n_) throw std::logic_error("SurfaceMemory: initial profile size");
  const auto n = static_cast<std::int64_t>(n_);
  initial_unrolled_.resize(2 * n_);
  for (std::int64_t k = -2 * n; k < 0; ++k)
    initial_unrolled_[static_cast<std::size_t>(k + 2 * n)] = initial_[static_cast<std::size_t>(((k % n) + n) % n)];
  if (!with_integral_) return;
  initial_integral_.assign(2 * n_, 0.0);  // k = -2n .. -1
  for (std::int64_t k = -2 * n + 1; k < 0; ++k) {
    const auto i = static_cast<std::size_t>(k + 2 * n);
    initial_integral_[i] = initial_integral_[i - 1] + 0.5 * spacing_ * (value(k - 1) + value(k));
  }
}

double SurfaceMemory::initial_value(std::int64_t k) const {
  if (flat_) return 0.0;
  const auto n = static_cast<std::int64_t>(n_);
  if (k >= -2 * n) return initial_unrolled_[static_cast<std::size_t>(k + 2 * n)];
  return initial_[static_cast<std::size_t>(((k % n) + n) % n)];
}

double SurfaceMemory::integral(std::int64_t k) const {
  if (!with_integral_) throw std::logic_error("SurfaceMemory: no running integral kept");
  const auto n = static_cast<std::int64_t>(n_);
  if (k < 0 && flat_) return 0.0;
  if (k < 0) return initial_integral_[static_cast<std::size_t>(std::max<std::int64_t>(k + 2 * n, 0))];
  return ring_integral_[slot(k)];
}

void SurfaceMemory::push_integral(double v) {
  ring_integral_[slot(next_)] = integral(next_ - 1) + 0.5 * spacing_ * (value(next_ - 1) + v);
}

double SurfaceMemory::interpolate(double theta, bool of_integral) const {
  const double x = theta * samples_per_rad_;
  const double fl = std::floor(x);
  const double u = x - fl;
  auto i = static_cast<std::int64_t>(fl);
  const std::int64_t last = next_ - 1;  // newest written index (initial profile if none)
  auto weights = cubic_weights;
  double w[4];
  // Fast paths (every right-hand side reads here): the stencil inside the written ring, or
  // inside the unrolled initial profile, without per-sample branches.
  if (i >= 1 && i + 2 <= last) {
    weights(u, w);
    const std::vector<double>& ring = of_integral ? ring_integral_ : ring_;
    const std::size_t mask = capacity_ - 1;
    const auto k = static_cast<std::size_t>(i);
    return w[0] * ring[(k - 1) & mask] + w[1] * ring[k & mask] + w[2] * ring[(k + 1) & mask] +
           w[3] * ring[(k + 2) & mask];
  }
  const auto n = static_cast<std::int64_t>(n_);
  if (!of_integral && i + 2 < 0 && i - 1 >= -2 * n) {
    if (flat_) return 0.0;
    weights(u, w);
    const double* p = initial_unrolled_.data() + (i - 1 + 2 * n);
    return w[0] * p[0] + w[1] * p[1] + w[2] * p[2] + w[3] * p[3];
  }
  // Never read past the newest sample: the stencil is shifted back (an extrapolation of at most
  // a sample or two, which only a step longer than a revolution could ask for).
  const std::int64_t shift = std::max<std::int64_t>(0, i + 2 - std::max<std::int64_t>(last, -1));
  auto sample = [&](std::int64_t k) { return of_integral ? integral(k) : value(k); };
  const std::int64_t j = i - shift;
  weights(u + static_cast<double>(shift), w);
  return w[0] * sample(j - 1) + w[1] * sample(j) + w[2] * sample(j + 1) + w[3] * sample(j + 2);
}

double SurfaceMemory::arc_mean(double theta, double arc) const {
  if (!with_integral_) throw std::logic_error("SurfaceMemory: mean over an arc without the running integral");
  return (interpolate(theta + 0.5 * arc, true) - interpolate(theta - 0.5 * arc, true)) / arc;
}

double SurfaceMemory::average(double theta_a, double theta_b) const {
  const double xa = theta_a * samples_per_rad_, xb = theta_b * samples_per_rad_;
  if (!(xb > xa)) return at(0.5 * (theta_a + theta_b));
  if (flat_ && xb < -2.0) return 0.0;
  const auto first = static_cast<std::int64_t>(std::floor(xa)), last = static_cast<std::int64_t>(std::floor(xb));
  if (last + 2 >= next_) return at(0.5 * (theta_a + theta_b));  // the stencil would reach unwritten samples
  // Antiderivatives (from 0) of the cubic Lagrange weights through i-1..i+2 on the interval
  // [i, i + 1], local u in [0, 1] (cubic_weights): their sum of values times samples integrates
  // the interpolant exactly.
  auto antiderivatives = [](double u, double w[4]) {
    const double u2 = u * u, u3 = u2 * u, u4 = u3 * u;
    w[0] = -(0.25 * u4 - u3 + u2) / 6.0;
    w[1] = 0.5 * (0.25 * u4 - 2.0 * u3 / 3.0 - 0.5 * u2 + 2.0 * u);
    w[2] = -0.5 * (0.25 * u4 - u3 / 3.0 - u2);
    w[3] = (0.25 * u4 - 0.5 * u2) / 6.0;
  };
  // Samples i-1 .. i+2 of each interval: from the ring directly when all are written (the usual
  // case: reads one revolution back), else through value() (initial profile).
  const bool in_ring = first >= 1;
  const std::size_t mask = capacity_ - 1;
  double integral = 0.0;
  for (std::int64_t i = first; i <= last; ++i) {
    const double u0 = std::max(xa - static_cast<double>(i), 0.0), u1 = std::min(xb - static_cast<double>(i), 1.0);
    if (!(u1 > u0)) continue;
    double w0[4], w1[4];
    antiderivatives(u0, w0);
    antiderivatives(u1, w1);
    if (in_ring) {
      const auto k = static_cast<std::size_t>(i);
      integral += (w1[0] - w0[0]) * ring_[(k - 1) & mask] + (w1[1] - w0[1]) * ring_[k & mask] +
                  (w1[2] - w0[2]) * ring_[(k + 1) & mask] + (w1[3] - w0[3]) * ring_[(k + 2) & mask];
    } else {
      for (int j = 0; j < 4; ++j) integral += (w1[j] - w0[j]) * value(i - 1 + j);
    }
  }
  return integral / (xb - xa);
}

std::vector<double> SurfaceMemory::last_revolution() const {
  std::vector<double> out(n_);
  const auto n = static_cast<std::int64_t>(n_);
  for (std::int64_t k = next_ - n; k < next_; ++k) out[static_cast<std::size_t>(((k % n) + n) % n)] = value(k);
  return out;
}

}  // namespace chatterlab::dynamics_detail
