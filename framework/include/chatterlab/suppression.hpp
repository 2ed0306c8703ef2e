#pragma once
// Chatter suppression by process modulation (MODELS.md S1-S3; book 5.3): a suppression plugin
// varies one process quantity around its mean (wheel speed, work speed or the infeed rate) and
// the dynamics engine runs the modulated process. The plugin supplies the law only: the
// framework installs it into SimulationSettings (speed law of the rotor, or infeed law) and the
// `suppression_map` study kind compares the modulated run with the constant one. docs/suppression.md.
#include <memory>
#include <string>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

// The modulated quantity.
enum class SuppressionTarget { wheel_speed, work_speed, feed };
const char* to_string(SuppressionTarget target);
SuppressionTarget parse_suppression_target(const std::string& name);  // std::invalid_argument

// The modulated quantity over its mean, q(t)/q_mean, on [0, horizon]: always > 0 (a spindle never
// stops or reverses, the infeed never backs off). level_integral is its exact integral from 0
// (the rotor angle and the infeed follow from it without quadrature error).
class ModulationLaw {
 public:
  virtual ~ModulationLaw() = default;
  virtual double level(double t_s) const = 0;
  virtual double level_integral(double t_s) const = 0;  // [s]
  virtual double min_level() const = 0;
  virtual double max_level() const = 0;
};

class Suppression {
 public:
  virtual ~Suppression() = default;
  virtual SuppressionTarget target() const = 0;
  // The law over [0, horizon_s] (a random law draws its levels up to the horizon).
  virtual std::shared_ptr<const ModulationLaw> law(double horizon_s) const = 0;
  // One modulation period [s] (a random law: its correlation time); 0: no modulation.
  virtual double modulation_period_s() const = 0;
};

// Installs `law` for `target` into the settings: the rotor's speed law (mean = the model's
// nominal speed) or, for feed, an infeed law with mean rate settings.infeed_rate_m_per_s.
// std::invalid_argument when the target rotor's speed is a model state (G5) or feed has no rate.
void apply_modulation(SuppressionTarget target, std::shared_ptr<const ModulationLaw> law,
                      const TimeDomainModel& model, SimulationSettings& settings);

}  // namespace chatterlab
