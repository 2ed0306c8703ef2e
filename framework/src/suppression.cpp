// Installing a suppression plugin's modulation law into the dynamics engine (suppression.hpp).
#include "chatterlab/suppression.hpp"

#include <numbers>
#include <stdexcept>
#include <utility>

namespace chatterlab {

namespace {

constexpr double rad_per_s_per_rpm = 2.0 * std::numbers::pi / 60.0;

// A rotor speed mean * level(t); its angle is the exact integral of the speed.
class ModulatedRotorSpeed final : public SpeedLaw {
 public:
  ModulatedRotorSpeed(std::shared_ptr<const ModulationLaw> law, double mean_rpm)
      : law_(std::move(law)), mean_rpm_(mean_rpm) {}
  double rpm(double t) const override { return mean_rpm_ * law_->level(t); }
  double angle_rad(double t) const override {
    return rad_per_s_per_rpm * mean_rpm_ * law_->level_integral(t);
  }
  double min_rpm(double) const override { return mean_rpm_ * law_->min_level(); }
  double max_rpm(double) const override { return mean_rpm_ * law_->max_level(); }

 private:
  std::shared_ptr<const ModulationLaw> law_;
  double mean_rpm_;
};

// An infeed with rate mean * level(t); u(t) is its exact integral.
class ModulatedInfeed final : public InfeedLaw {
 public:
  ModulatedInfeed(std::shared_ptr<const ModulationLaw> law, double mean_rate)
      : law_(std::move(law)), mean_rate_(mean_rate) {}
  double infeed_m(double t) const override { return mean_rate_ * law_->level_integral(t); }
  double rate_m_per_s(double t) const override { return mean_rate_ * law_->level(t); }

 private:
  std::shared_ptr<const ModulationLaw> law_;
  double mean_rate_;
};

}  // namespace

const char* to_string(SuppressionTarget target) {
  switch (target) {
    case SuppressionTarget::wheel_speed: return "wheel_speed";
    case SuppressionTarget::work_speed: return "work_speed";
    case SuppressionTarget::feed: return "feed";
  }
  return "?";
}

SuppressionTarget parse_suppression_target(const std::string& name) {
  for (SuppressionTarget t :
       {SuppressionTarget::wheel_speed, SuppressionTarget::work_speed, SuppressionTarget::feed})
    if (name == to_string(t)) return t;
  throw std::invalid_argument("unknown suppression target '" + name +
                              "' (valid: feed, wheel_speed, work_speed)");
}

void apply_modulation(SuppressionTarget target, std::shared_ptr<const ModulationLaw> law,
                      const TimeDomainModel& model, SimulationSettings& settings) {
  if (!(law->min_level() > 0.0))
    throw std::invalid_argument("a modulation law must keep its level > 0");
  if (target == SuppressionTarget::feed) {
    if (!(settings.infeed_rate_m_per_s > 0.0))
      throw std::invalid_argument("feed modulation needs a mean infeed rate > 0");
    settings.infeed = std::make_shared<ModulatedInfeed>(std::move(law), settings.infeed_rate_m_per_s);
    return;
  }
  const Rotor rotor = target == SuppressionTarget::wheel_speed ? Rotor::wheel : Rotor::work;
  if (model.angle_state(rotor))
    throw std::invalid_argument(std::string("the model integrates the ") + to_string(rotor) +
                                " speed as a state: it cannot be modulated by a speed law");
  settings.speed[static_cast<std::size_t>(rotor)] =
      std::make_shared<ModulatedRotorSpeed>(std::move(law), model.nominal_speed_rpm(rotor));
}

}  // namespace chatterlab
