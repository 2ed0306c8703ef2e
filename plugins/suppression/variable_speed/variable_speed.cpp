#include "suppression/variable_speed/variable_speed.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

constexpr double kPi = std::numbers::pi;

// splitmix64 (Steele, Lea, Flood 2014): a well-mixed 64-bit hash, so level k does not depend on
// how many levels were drawn before it, and the same seed gives the same law on every platform
// (std::uniform_real_distribution is implementation-defined).
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// The periodic shapes are the engine's speed laws at a mean of 1 "rpm": level = rpm, and the
// integral of the level is the angle over 2 pi/60.
class PeriodicLaw final : public ModulationLaw {
 public:
  PeriodicLaw(SpeedModulation shape, double amplitude, double frequency_hz)
      : unit_(make_modulated_speed(1.0, shape, amplitude, frequency_hz)), constant_(amplitude == 0.0) {}
  double level(double t) const override { return unit_->rpm(t); }
  // Zero amplitude: exactly t, so that an unmodulated run is bit-for-bit the constant one.
  double level_integral(double t) const override {
    return constant_ ? t : unit_->angle_rad(t) * 60.0 / (2.0 * kPi);
  }
  double min_level() const override { return unit_->min_rpm(0.0); }
  double max_level() const override { return unit_->max_rpm(0.0); }

 private:
  std::unique_ptr<SpeedLaw> unit_;
  bool constant_;
};

class RandomLaw final : public ModulationLaw {
 public:
  RandomLaw(const VariableSpeedParameters& p, double horizon)
      : wave_(p.seed, p.frequency_hz, horizon), amplitude_(p.amplitude_ratio) {}
  double level(double t) const override { return 1.0 + amplitude_ * wave_.value(t); }
  double level_integral(double t) const override { return t + amplitude_ * wave_.integral(t); }
  // |w| <= 1 (the raised cosine never overshoots its two knots): the bounds of the shape.
  double min_level() const override { return 1.0 - amplitude_; }
  double max_level() const override { return 1.0 + amplitude_; }

 private:
  RandomWaveform wave_;
  double amplitude_;
};

SpeedModulation periodic_shape(ModulationShape shape) {
  switch (shape) {
    case ModulationShape::sinusoidal: return SpeedModulation::sinusoidal;
    case ModulationShape::triangular: return SpeedModulation::triangular;
    case ModulationShape::square: return SpeedModulation::square;
    case ModulationShape::random: break;
  }
  throw std::logic_error("variable_speed: not a periodic shape");
}

ModulationShape parse_shape(const std::string& name) {
  if (name == "sinusoidal") return ModulationShape::sinusoidal;
  if (name == "triangular") return ModulationShape::triangular;
  if (name == "square") return ModulationShape::square;
  if (name == "random") return ModulationShape::random;
  throw std::invalid_argument("unknown modulation shape '" + name +
                              "' (valid: random, sinusoidal, square, triangular)");
}

}  // namespace

// ------------------------------------------------------------------ random waveform

RandomWaveform::RandomWaveform(std::uint64_t seed, double frequency_hz, double horizon_s)
    : seed_(seed), frequency_hz_(frequency_hz) {
  if (!(frequency_hz > 0.0)) throw std::invalid_argument("a random modulation needs frequency_hz > 0");
  const auto knots = static_cast<std::size_t>(std::ceil(std::max(horizon_s, 0.0) * frequency_hz)) + 2;
  levels_.resize(knots);
  prefix_.assign(knots, 0.0);
  for (std::size_t k = 0; k < knots; ++k) levels_[k] = draw(k);
  for (std::size_t k = 1; k < knots; ++k)
    prefix_[k] = prefix_[k - 1] + 0.5 * (levels_[k - 1] + levels_[k]) / frequency_hz_;
}

double RandomWaveform::knot_level(std::size_t k) const {
  return k < levels_.size() ? levels_[k] : draw(k);
}

double RandomWaveform::draw(std::size_t k) const {
  if (k == 0) return 0.0;  // start at the mean, like the sine
  const std::uint64_t bits = splitmix64(seed_ ^ splitmix64(static_cast<std::uint64_t>(k)));
  const double unit = static_cast<double>(bits >> 11) * 0x1.0p-53;  // [0, 1)
  return 2.0 * unit - 1.0;
}

double RandomWaveform::prefix_integral(std::size_t k) const {
  if (k < prefix_.size()) return prefix_[k];
  double sum = prefix_.back();  // beyond the horizon: continue the same sum
  for (std::size_t j = prefix_.size(); j <= k; ++j)
    sum += 0.5 * (knot_level(j - 1) + knot_level(j)) / frequency_hz_;
  return sum;
}

double RandomWaveform::value(double t) const {
  if (t <= 0.0) return 0.0;
  const double x = t * frequency_hz_;
  const auto k = static_cast<std::size_t>(x);
  const double u = x - static_cast<double>(k);
  const double s = 0.5 * (1.0 - std::cos(kPi * u));
  return knot_level(k) + (knot_level(k + 1) - knot_level(k)) * s;
}

double RandomWaveform::integral(double t) const {
  if (t <= 0.0) return 0.0;
  const double x = t * frequency_hz_;
  const auto k = static_cast<std::size_t>(x);
  const double u = x - static_cast<double>(k);
  const double lk = knot_level(k), dl = knot_level(k + 1) - lk;
  // integral over [0, u] of L_k + dL (1 - cos(pi v))/2 dv, times the knot interval 1/f
  const double inside = lk * u + dl * (0.5 * u - std::sin(kPi * u) / (2.0 * kPi));
  return prefix_integral(k) + inside / frequency_hz_;
}

// ------------------------------------------------------------------ plugin

std::shared_ptr<const ModulationLaw> make_modulation_law(const VariableSpeedParameters& p, double horizon_s) {
  if (!(p.amplitude_ratio >= 0.0 && p.amplitude_ratio < 1.0))
    throw std::invalid_argument(
        "amplitude_ratio must be in [0, 1): at 1 or more the modulated quantity would stop or reverse");
  if (p.shape == ModulationShape::random) return std::make_shared<RandomLaw>(p, horizon_s);
  return std::make_shared<PeriodicLaw>(periodic_shape(p.shape), p.amplitude_ratio, p.frequency_hz);
}

namespace {
VariableSpeedParameters read_parameters(const ParamValues& v) {
  VariableSpeedParameters p;
  p.target = parse_suppression_target(v.string("target"));
  p.shape = parse_shape(v.string("shape"));
  p.amplitude_ratio = v.real("amplitude_ratio");
  p.frequency_hz = v.real("frequency_hz");
  p.seed = static_cast<std::uint64_t>(v.integer("seed"));
  return p;
}
}  // namespace

VariableSpeed::VariableSpeed(const ParamValues& values) : VariableSpeed(read_parameters(values)) {}

VariableSpeed::VariableSpeed(VariableSpeedParameters parameters) : p_(parameters) {
  make_modulation_law(p_, 0.0);  // refuses bad parameters at construction (std::invalid_argument)
}

std::shared_ptr<const ModulationLaw> VariableSpeed::law(double horizon_s) const {
  return make_modulation_law(p_, horizon_s);
}

double VariableSpeed::modulation_period_s() const {
  return p_.amplitude_ratio > 0.0 ? 1.0 / p_.frequency_hz : 0.0;
}

PluginInfo VariableSpeed::info() {
  ParamSpec target = param_spec("target", ValueKind::string, "",
                                "modulated quantity: wheel_speed (S2), work_speed (S3) or feed "
                                "(the infeed rate, S1)");
  target.default_value = "wheel_speed";
  target.choices = {"wheel_speed", "work_speed", "feed"};
  ParamSpec shape = param_spec("shape", ValueKind::string, "",
                               "waveform w: sinusoidal, triangular, square, or random (seeded "
                               "smooth levels every 1/f)");
  shape.default_value = "sinusoidal";
  shape.choices = {"sinusoidal", "triangular", "square", "random"};
  ParamSpec amplitude = param_spec("amplitude_ratio", ValueKind::real, "1",
                                   "modulation amplitude over the mean, q = q_mean (1 + a w); < 1 so "
                                   "a spindle never stops or reverses");
  amplitude.default_value = 0.0;
  amplitude.min = 0.0;
  amplitude.max = 1.0;
  amplitude.max_exclusive = true;
  ParamSpec frequency = param_spec("frequency_hz", ValueKind::real, "Hz",
                                   "modulation frequency f (random: a new level every 1/f)");
  frequency.default_value = 1.0;
  frequency.min = 0.0;
  frequency.min_exclusive = true;
  ParamSpec seed = param_spec("seed", ValueKind::integer, "1", "seed of the random shape's levels");
  seed.default_value = 1;
  seed.min = 0;
  return plugin_info("variable_speed", "S1, S2, S3",
                     {target, shape, amplitude, frequency, seed},
                     Json::parse(
                         R"({"target": "wheel_speed", "shape": "sinusoidal", "amplitude_ratio": 0.1, "frequency_hz": 0.5})"),
                     "variable wheel speed, work speed or feed: sinusoidal, triangular, square or "
                     "random modulation (S1-S3)",
                     ThreadSafety::shareable);  // immutable after construction
}

CHATTERLAB_REGISTER_SUPPRESSION(VariableSpeed);

}  // namespace chatterlab
