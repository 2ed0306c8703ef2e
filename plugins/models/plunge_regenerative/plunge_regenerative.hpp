#pragma once
// MODELS.md G1: basic plunge-grinding model (Snoeys type), characteristic equation eq 2-16
// (shared/plunge_dynamics/plunge_characteristic.hpp), its time domain (plunge_time_domain.hpp),
// and its capabilities: the stiffness chain and structural compliance (closed forms, the
// compliance chart) and process conditions (feed_risk, suppression_map: the parameters at other
// speeds, widths and depths of cut, shared/plunge_dynamics/process_scaling.hpp).
// Docs: docs/models/plunge_regenerative.md.
#include <memory>
#include <optional>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/closed_form.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/process_conditions.hpp"
#include "chatterlab/registry.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "shared/plunge_dynamics/plunge_characteristic.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab {

class PlungeRegenerative final : public Model,
                                 public StructuralCompliance,
                                 public ProcessConditionsModel,
                                 public ClosedFormIndicators {
 public:
  explicit PlungeRegenerative(const ParamValues& values);
  explicit PlungeRegenerative(PlungeRegenerativeParameters parameters);

  static PluginInfo info();

  std::unique_ptr<CharacteristicFunction> characteristic() const override;
  std::optional<double> wheel_period_s() const override;
  std::unique_ptr<TimeDomainModel> time_domain() const override;  // G1 time domain
  // The linearisation of the same contact law (plunge_time_domain.hpp): the derived
  // characteristic function to check the hand-written one against, and Floquet multipliers of
  // modulated speeds (stability_map with [suppression]). characteristic() stays the fast path.
  const LinearisedModel* linearised() const override { return &linearisation_; }
  const PlungeRegenerativeParameters& parameters() const { return parameters_; }

  std::optional<StiffnessChain> stiffness_chain() const override;
  const StructuralCompliance* structural_compliance() const override { return this; }
  Complex compliance_m_per_n(Complex s) const override;
  const ProcessConditionsModel* process_conditions() const override { return this; }

  // G3's closed form (shared/plunge_dynamics/wheel_growth_rate.hpp) beside the root: it applies to
  // wheel regeneration alone (work_regeneration = false); null otherwise.
  const ClosedFormIndicators* closed_forms() const override { return this; }
  std::vector<ClosedFormIndicatorSpec> indicator_specs() const override;
  std::vector<Json> indicator_values() const override;
  ProcessConditions nominal_conditions() const override;
  Json parameters_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                     const ProcessScaling& scaling) const override;
  void parameter_values_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                           const ProcessScaling& scaling, std::vector<double>& values) const override;

 private:
  PlungeRegenerativeParameters parameters_;
  PlungeCharacteristic characteristic_;  // H(s) of the compliance capability
  PlungeLinearisation linearisation_;
};

}  // namespace chatterlab
