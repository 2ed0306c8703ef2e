#include "models/plunge_regenerative/plunge_regenerative.hpp"

#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "shared/plunge_dynamics/process_scaling.hpp"

namespace chatterlab {

PlungeRegenerative::PlungeRegenerative(const ParamValues& values) : PlungeRegenerative(plunge_dynamics::plunge_parameters_table().read(values)) {}

PlungeRegenerative::PlungeRegenerative(PlungeRegenerativeParameters parameters)
    : parameters_(std::move(parameters)), characteristic_(parameters_) {}

PluginInfo PlungeRegenerative::info() {
  return PluginInfo{
      .name = "plunge_regenerative",
      .description =
          "Plunge grinding, wheel and work regeneration with summed structural modes (G1 eq 2-16)",
      .params = plunge_dynamics::plunge_parameters_table().specs(),
      .thread_safety = ThreadSafety::shareable,  // immutable after construction
      .models_md_ids = "G1, G3",
      .example_params = plunge_dynamics::example_g1_parameters(),
  };
}

std::unique_ptr<CharacteristicFunction> PlungeRegenerative::characteristic() const {
  return std::make_unique<PlungeCharacteristic>(parameters_);
}

std::optional<double> PlungeRegenerative::wheel_period_s() const {
  return 60.0 / parameters_.wheel_speed_rpm;
}

std::unique_ptr<TimeDomainModel> PlungeRegenerative::time_domain() const {
  return std::make_unique<PlungeTimeDomain>(parameters_);
}

std::optional<StiffnessChain> PlungeRegenerative::stiffness_chain() const {
  return plunge_dynamics::stiffness_chain(parameters_);
}

Complex PlungeRegenerative::compliance_m_per_n(Complex s) const {
  return characteristic_.structural_compliance(s);
}

ProcessConditions PlungeRegenerative::nominal_conditions() const {
  return plunge_dynamics::nominal_conditions(parameters_);
}

Json PlungeRegenerative::parameters_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                                       const ProcessScaling& scaling) const {
  return plunge_dynamics::plunge_parameters_table().write(
      plunge_dynamics::parameters_at(parameters_, reference, conditions, scaling));
}

CHATTERLAB_REGISTER_MODEL(PlungeRegenerative);

}  // namespace chatterlab
