#include "models/plunge_regenerative/plunge_regenerative.hpp"

#include <algorithm>
#include <cmath>

#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "shared/plunge_dynamics/process_scaling.hpp"
#include "shared/plunge_dynamics/wheel_growth_rate.hpp"

namespace chatterlab {

PlungeRegenerative::PlungeRegenerative(const ParamValues& values) : PlungeRegenerative(plunge_dynamics::plunge_parameters_table().read(values)) {}

PlungeRegenerative::PlungeRegenerative(PlungeRegenerativeParameters parameters)
    : parameters_(std::move(parameters)), characteristic_(parameters_), linearisation_(parameters_) {}

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

std::vector<ClosedFormIndicatorSpec> PlungeRegenerative::indicator_specs() const {
  return {
      {"g3_growth_rate_per_s",
       "G3 closed form (corrected 2-68) at the wheel lattice's frequencies of this speed: 2 pi rho/Tg, the "
       "largest (wheel regeneration alone); > 0: chatter",
       true},
      {"g3_growth_rate_per_wheel_rev", "its rho: A_{n+1}/A_n = e^{2 pi rho} per wheel revolution", false},
      {"g3_chatter_frequency_hz", "the frequency of that rho", false},
      {"g3_max_growth_rate_per_wheel_rev",
       "rho_max over every frequency up to 4 x the highest mode: what some wheel speed reaches (5-38)", false},
  };
}

std::vector<Json> PlungeRegenerative::indicator_values() const {
  const PlungeRegenerativeParameters& p = parameters_;
  std::vector<Json> values(4);  // null: G3 is wheel regeneration alone
  if (!p.wheel_regeneration || p.work_regeneration || p.modes.empty()) return values;
  double highest_hz = 0.0;
  for (const StructuralMode& mode : p.modes) highest_hz = std::max(highest_hz, mode.frequency_hz);
  const auto g3 = wheel_growth::wheel_chatter_at_speed(
      p.wheel_wear_stiffness_n_per_m, p.contact_stiffness_n_per_m,
      [this](double w) { return characteristic_.structural_compliance(Complex(0.0, w)); },
      60.0 / p.wheel_speed_rpm, 4.0 * highest_hz);
  auto number = [](double v) { return std::isfinite(v) ? Json(v) : Json(); };
  values[0] = number(g3.growth_rate_per_s);
  values[1] = number(g3.growth_rate_per_rev);
  values[2] = number(g3.chatter_frequency_hz);
  values[3] = number(g3.max_growth_rate_per_rev);
  return values;
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

void PlungeRegenerative::parameter_values_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                                             const ProcessScaling& scaling, std::vector<double>& values) const {
  plunge_dynamics::parameter_values(plunge_dynamics::parameters_at(parameters_, reference, conditions, scaling), values);
}

CHATTERLAB_REGISTER_MODEL(PlungeRegenerative);

}  // namespace chatterlab
