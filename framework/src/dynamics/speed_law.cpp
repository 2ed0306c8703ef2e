// Speed laws of the dynamics engine (chatterlab/dynamics.hpp). Every law gives its angle as the
// exact integral of its speed, so angle-indexed surfaces see the exact revolution at any speed.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "chatterlab/dynamics.hpp"

namespace chatterlab {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * kPi;
constexpr double rad_per_s_per_rpm = kTwoPi / 60.0;

// Unit periodic waveform w(p) (period 2 pi) and its integral from 0, which is periodic too
// (every waveform has zero mean over a period).
double waveform(SpeedModulation shape, double p) {
  p = p - kTwoPi * std::floor(p / kTwoPi);
  switch (shape) {
    case SpeedModulation::constant: return 0.0;
    case SpeedModulation::sinusoidal: return std::sin(p);
    case SpeedModulation::triangular:
      if (p <= 0.5 * kPi) return 2.0 * p / kPi;
      if (p <= 1.5 * kPi) return 2.0 - 2.0 * p / kPi;
      return 2.0 * p / kPi - 4.0;
    case SpeedModulation::square: return p < kPi ? 1.0 : -1.0;
  }
  return 0.0;
}

double waveform_integral(SpeedModulation shape, double p) {
  p = p - kTwoPi * std::floor(p / kTwoPi);
  switch (shape) {
    case SpeedModulation::constant: return 0.0;
    case SpeedModulation::sinusoidal: return 1.0 - std::cos(p);
    case SpeedModulation::triangular:
      if (p <= 0.5 * kPi) return p * p / kPi;
      if (p <= 1.5 * kPi) return 0.25 * kPi + 2.0 * (p - 0.5 * kPi) - (p * p - 0.25 * kPi * kPi) / kPi;
      return 0.25 * kPi + (p * p - 2.25 * kPi * kPi) / kPi - 4.0 * (p - 1.5 * kPi);
    case SpeedModulation::square: return p < kPi ? p : kTwoPi - p;
  }
  return 0.0;
}

class ModulatedSpeed final : public SpeedLaw {
 public:
  ModulatedSpeed(double mean_rpm, SpeedModulation shape, double amplitude, double frequency_hz)
      : mean_(mean_rpm), shape_(shape), amplitude_(amplitude), frequency_(frequency_hz) {
    if (frequency_ == 0.0 || amplitude_ == 0.0) shape_ = SpeedModulation::constant;
  }
  double rpm(double t) const override {
    return mean_ * (1.0 + amplitude_ * waveform(shape_, kTwoPi * frequency_ * t));
  }
  double angle_rad(double t) const override {
    double angle = rad_per_s_per_rpm * mean_ * t;
    if (shape_ == SpeedModulation::constant) return angle;
    return angle + rad_per_s_per_rpm * mean_ * amplitude_ / (kTwoPi * frequency_) *
                       waveform_integral(shape_, kTwoPi * frequency_ * t);
  }
  double min_rpm(double) const override {
    return shape_ == SpeedModulation::constant ? mean_ : mean_ * (1.0 - amplitude_);
  }
  double max_rpm(double) const override {
    return shape_ == SpeedModulation::constant ? mean_ : mean_ * (1.0 + amplitude_);
  }

 private:
  double mean_;
  SpeedModulation shape_;
  double amplitude_, frequency_;
};

class ScheduledSpeed final : public SpeedLaw {
 public:
  ScheduledSpeed(std::vector<double> times, std::vector<double> rpm)
      : times_(std::move(times)), rpm_(std::move(rpm)) {
    angle_.assign(times_.size(), 0.0);
    for (std::size_t i = 1; i < times_.size(); ++i)
      angle_[i] = angle_[i - 1] +
                  0.5 * rad_per_s_per_rpm * (rpm_[i] + rpm_[i - 1]) * (times_[i] - times_[i - 1]);
  }
  double rpm(double t) const override {
    std::size_t i = segment(t);
    if (i + 1 >= times_.size()) return rpm_.back();
    double u = (t - times_[i]) / (times_[i + 1] - times_[i]);
    return rpm_[i] + u * (rpm_[i + 1] - rpm_[i]);
  }
  double angle_rad(double t) const override {
    std::size_t i = segment(t);
    double dt = t - times_[i];
    if (i + 1 >= times_.size()) return angle_[i] + rad_per_s_per_rpm * rpm_[i] * dt;
    double slope = (rpm_[i + 1] - rpm_[i]) / (times_[i + 1] - times_[i]);
    return angle_[i] + rad_per_s_per_rpm * (rpm_[i] * dt + 0.5 * slope * dt * dt);
  }
  double min_rpm(double t_end) const override { return bound(t_end, false); }
  double max_rpm(double t_end) const override { return bound(t_end, true); }

 private:
  // Index of the schedule point at or before t (0 for t before the first point).
  std::size_t segment(double t) const {
    auto it = std::upper_bound(times_.begin(), times_.end(), t);
    return it == times_.begin() ? 0 : static_cast<std::size_t>(it - times_.begin()) - 1;
  }
  double bound(double t_end, bool highest) const {
    double b = rpm(t_end);  // the speed is linear between points: extremes at points or the end
    for (std::size_t i = 0; i < times_.size() && times_[i] <= t_end; ++i)
      b = highest ? std::max(b, rpm_[i]) : std::min(b, rpm_[i]);
    return b;
  }
  std::vector<double> times_, rpm_, angle_;
};

}  // namespace

std::unique_ptr<SpeedLaw> make_modulated_speed(double mean_rpm, SpeedModulation shape,
                                               double amplitude_ratio, double frequency_hz) {
  if (!(std::isfinite(mean_rpm) && mean_rpm > 0.0))
    throw std::invalid_argument("mean speed must be > 0 rpm");
  if (!(std::isfinite(amplitude_ratio) && amplitude_ratio >= 0.0 && amplitude_ratio < 1.0))
    throw std::invalid_argument(
        "amplitude_ratio must be in [0, 1): at 1 or more the spindle would stop or reverse");
  if (!(std::isfinite(frequency_hz) && frequency_hz >= 0.0))
    throw std::invalid_argument("modulation frequency_hz must be >= 0");
  if (shape != SpeedModulation::constant && amplitude_ratio > 0.0 && frequency_hz == 0.0)
    throw std::invalid_argument("a modulation with amplitude_ratio > 0 needs frequency_hz > 0");
  return std::make_unique<ModulatedSpeed>(mean_rpm, shape, amplitude_ratio, frequency_hz);
}

std::unique_ptr<SpeedLaw> make_scheduled_speed(std::vector<double> times_s, std::vector<double> rpm) {
  if (times_s.empty() || times_s.size() != rpm.size())
    throw std::invalid_argument("a speed schedule needs as many times as speeds, at least one");
  if (times_s.front() != 0.0) throw std::invalid_argument("a speed schedule must start at t = 0 s");
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    if (!(std::isfinite(rpm[i]) && rpm[i] > 0.0))
      throw std::invalid_argument("every scheduled speed must be > 0 rpm");
    if (i > 0 && !(times_s[i] > times_s[i - 1]))
      throw std::invalid_argument("schedule times must be strictly increasing");
  }
  return std::make_unique<ScheduledSpeed>(std::move(times_s), std::move(rpm));
}

SpeedModulation parse_speed_modulation(const std::string& name) {
  if (name == "constant") return SpeedModulation::constant;
  if (name == "sinusoidal") return SpeedModulation::sinusoidal;
  if (name == "triangular") return SpeedModulation::triangular;
  if (name == "square") return SpeedModulation::square;
  throw std::invalid_argument("unknown speed modulation '" + name +
                              "' (valid: constant, sinusoidal, triangular, square)");
}

const char* to_string(Rotor rotor) { return rotor == Rotor::wheel ? "wheel" : "work"; }

}  // namespace chatterlab
