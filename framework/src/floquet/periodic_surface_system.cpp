// The periodic linearisation of a model written once (chatterlab/floquet.hpp): its Jacobian along
// the process, the delays one revolution of each regenerated rotor by angle.
#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/delay_system.hpp"
#include "chatterlab/derived_model.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/floquet.hpp"
#include "chatterlab/linearised_model.hpp"
#include "derived/surface_system.hpp"

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Jacobian samples per period that decide whether the coefficients vary at all.
constexpr int kConstancySamples = 48;

class SurfacePeriodicSystem final : public PeriodicDelaySystem {
 public:
  SurfacePeriodicSystem(const LinearisedModel& model, const PeriodicProcess& process)
      : model_(model), process_(process), layout_(model.surface_layout()) {
    if (!(process.period_s > 0.0)) throw PointFailure("Floquet: the process period must be > 0");
    for (std::size_t r = 0; r < rotor_count; ++r) {
      const auto& law = process_.speed[r];
      // Periodic laws repeat: a time is moved forward by whole periods until a revolution fits
      // behind it (SpeedLaw angles start at t = 0).
      double lowest = layout_.nominal_speed_rpm[r], highest = lowest;
      if (law) {
        const double horizon = 4.0 * process.period_s + 120.0 / law->min_rpm(4.0 * process.period_s);
        lowest = law->min_rpm(horizon);
        highest = law->max_rpm(horizon);
      }
      if (!(lowest > 0.0)) throw PointFailure("Floquet: a speed law reaches zero");
      shortest_[r] = 60.0 / highest;
      longest_[r] = 60.0 / lowest;
      shift_[r] = process.period_s * std::ceil(longest_[r] / process.period_s + 1.0);
    }
    const JacobianMatrix first = model.jacobian(point(0.0));
    frequency_hz_ = derived_detail::state_block_frequency_hz(first, layout_.states);
    constant_ = true;
    for (int j = 1; j < kConstancySamples && constant_; ++j) {
      const JacobianMatrix other = model.jacobian(point(process.period_s * j / kConstancySamples));
      constant_ = other == first;
      frequency_hz_ = std::max(frequency_hz_, derived_detail::state_block_frequency_hz(other, layout_.states));
    }
    if (constant_) surface_system_matrices(layout_, first, a0_, delayed_);
    // The family of steady states at the nominal point (G1: cumulative removal, multiplier 1).
    family_ = DelayCharacteristic(surface_linear_system(model)).summary().family_roots_at_zero;
  }

  std::size_t size() const override { return layout_.size(); }
  std::vector<bool> differential() const override {
    std::vector<bool> out(layout_.size(), false);
    std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(layout_.states), true);
    return out;
  }
  std::size_t delay_count() const override { return layout_.regenerated.size(); }
  double period_s() const override { return process_.period_s; }
  double delay_s(std::size_t k, double t) const override {
    const std::size_t r = static_cast<std::size_t>(layout_.regenerated[k]);
    return revolution_time(r, t, first_guess(r, t));
  }
  // Each solve starts from the previous two extrapolated (error O(dt^2 tau''), so one Newton step
  // and its check instead of four or five from the instantaneous revolution).
  void delays_s(std::size_t k, const std::vector<double>& times, std::vector<double>& out) const override {
    const std::size_t r = static_cast<std::size_t>(layout_.regenerated[k]);
    out.resize(times.size());
    for (std::size_t i = 0; i < times.size(); ++i) {
      double guess = first_guess(r, times[i]);
      if (i >= 2) guess = out[i - 1] + (out[i - 1] - out[i - 2]) * (times[i] - times[i - 1]) / (times[i - 1] - times[i - 2]);
      out[i] = revolution_time(r, times[i], guess);
    }
  }
  double max_delay_s() const override {
    double m = 0.0;
    for (Rotor r : layout_.regenerated) m = std::max(m, longest_[static_cast<std::size_t>(r)]);
    return m;
  }
  double min_delay_s() const override {
    double m = std::numeric_limits<double>::infinity();
    for (Rotor r : layout_.regenerated) m = std::min(m, shortest_[static_cast<std::size_t>(r)]);
    return m;
  }
  void coefficients(double t, Eigen::MatrixXd& a0, std::vector<Eigen::MatrixXd>& delayed) const override {
    if (constant_) {
      a0 = a0_;
      delayed = delayed_;
      return;
    }
    surface_system_matrices(layout_, model_.jacobian(point(t)), a0, delayed);
  }
  double frequency_scale_hz() const override { return frequency_hz_; }
  int family_multipliers() const override { return family_; }

 private:
  ProcessPoint point(double t) const {
    ProcessPoint p;
    p.t_s = t;
    for (std::size_t r = 0; r < rotor_count; ++r) {
      if (const auto& law = process_.speed[r]) {
        const double shifted = t + shift_[r];
        p.speed_rpm[r] = law->rpm(shifted);
        // The angle at t itself (not shifted): the law's phase at the process time.
        p.angle_rad[r] = law->angle_rad(std::max(t, 0.0));
      } else {
        p.speed_rpm[r] = layout_.nominal_speed_rpm[r];
        p.angle_rad[r] = kTwoPi * layout_.nominal_speed_rpm[r] / 60.0 * t;
      }
    }
    return p;
  }

  // The instantaneous revolution at t: where a solve without a better guess starts.
  double first_guess(std::size_t r, double t) const {
    const auto& law = process_.speed[r];
    return law ? 60.0 / law->rpm(t + shift_[r]) : 60.0 / layout_.nominal_speed_rpm[r];
  }

  // The time of the revolution that ends at t: angle(t) - angle(t - tau) = 2 pi, by Newton's
  // method from `guess`, safeguarded by bisection on [shortest, longest]. Newton converges
  // quadratically (relative error ~ tau |omega'/omega| e^2), so a correction below 1e-11 tau
  // leaves an error far below 1e-15 tau and ends the solve without another evaluation.
  double revolution_time(std::size_t r, double t, double guess) const {
    const auto& law = process_.speed[r];
    if (!law) return 60.0 / layout_.nominal_speed_rpm[r];
    const double end = t + shift_[r];
    const double target = law->angle_rad(end) - kTwoPi;
    double lo = shortest_[r], hi = longest_[r];
    double tau = guess > lo && guess < hi ? guess : 60.0 / law->rpm(end);
    for (int it = 0; it < 60; ++it) {
      const double f = law->angle_rad(end - tau) - target;  // decreasing in tau; zero at the root
      if (f > 0.0) lo = tau;
      else hi = tau;
      const double speed = kTwoPi * law->rpm(end - tau) / 60.0;
      const double step = f / speed;
      // (Checked before the bracket: f carries the rounding of angles of many revolutions, ~1e-14
      // tau, so the bracket can close around the root's rounding noise.)
      if (std::abs(step) <= 1e-11 * tau) return tau + step;
      double next = tau + step;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (std::abs(next - tau) <= 1e-15 * tau) return next;
      tau = next;
    }
    return tau;
  }

  const LinearisedModel& model_;
  PeriodicProcess process_;
  SurfaceLayout layout_;
  double shortest_[rotor_count] = {0.0, 0.0}, longest_[rotor_count] = {0.0, 0.0}, shift_[rotor_count] = {0.0, 0.0};
  double frequency_hz_ = 0.0;
  bool constant_ = false;
  Eigen::MatrixXd a0_;
  std::vector<Eigen::MatrixXd> delayed_;
  int family_ = 0;
};

}  // namespace

std::unique_ptr<PeriodicDelaySystem> periodic_surface_system(const LinearisedModel& model, const PeriodicProcess& process) {
  return std::make_unique<SurfacePeriodicSystem>(model, process);
}

}  // namespace chatterlab
