#pragma once
// MODELS.md G1 with the dynamic grinding force of G4 (book eqs 2-75..2-78): the work removal
// force has a static part kw (= ks, proportional to the depth of cut, regenerating once per work
// revolution) and a dynamic part kd (proportional to the penetration rate, damping-like, not
// regenerating):
//
//   Fn = kw (Ww(t) - Ww(t - Tw)) + kd dWw/dt   ->   Ww = Fn / (kw (1 - e^{-Tw s}) + kd s),
//   D(s) = 1 + kc [ H(s) + 1/(kg (1 - e^{-Tg s})) + 1/(kw (1 - e^{-Tw s}) + kd s) ].
//
// kd = 0 is plunge_regenerative. G1's entire function is affine in B = 1 - e^{-Tw s}, and kd only
// replaces B by B + (kd/kw) s, so E(s) = E_G1(s) + (kd/kw) s E_G1,work off(s): the characteristic
// function is built from two G1 ones (shared/plunge_dynamics). kd = ks sqrt(de u0)/vw
// (shared/plunge_dynamics/grinding_process.hpp): with the process geometry given, the model reports
// G4's closed forms beside its roots, and kd follows the process conditions with that law.
// Docs: docs/models/plunge_with_penetration_damping.md.
#include <memory>
#include <optional>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/closed_form.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/process_conditions.hpp"
#include "chatterlab/registry.hpp"
#include "shared/plunge_dynamics/plunge_characteristic.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab {

class PenetrationDampingCharacteristic final : public CharacteristicFunction {
 public:
  PenetrationDampingCharacteristic(const PlungeRegenerativeParameters& parameters,
                                   double penetration_damping_n_s_per_m);

  CharacteristicValue evaluate(Complex s) const override;
  // G1's Newton form at kd = 0 (the model is then G1, to the bit); E itself otherwise.
  CharacteristicValue newton_form(Complex s) const override;
  std::vector<Complex> neutral_roots(double max_angular_frequency_rad_s) const override;
  void initial_guesses(double max_angular_frequency_rad_s,
                       std::vector<Complex>& guesses) const override;
  double real_part_bound() const override;
  double natural_frequency_scale_hz() const override;

 private:
  PlungeRegenerativeParameters parameters_;
  PlungeCharacteristic full_, work_off_;
  double delay_ratio_;  // kd/kw [s] (0 when the work chain is off)
};

struct PenetrationDampingParameters {
  PlungeRegenerativeParameters plunge;        // G1's, declared by the G1 table
  double penetration_damping_n_s_per_m = 0.0;  // kd
  // Process geometry for the G4 indicators (absent: those indicators are null).
  std::optional<double> work_diameter_mm, wheel_diameter_mm, depth_of_cut_mm;
};

class PlungeWithPenetrationDamping final : public Model,
                                           public ClosedFormIndicators,
                                           public StructuralCompliance,
                                           public ProcessConditionsModel {
 public:
  explicit PlungeWithPenetrationDamping(const ParamValues& values);
  explicit PlungeWithPenetrationDamping(PenetrationDampingParameters parameters);

  static PluginInfo info();

  std::unique_ptr<CharacteristicFunction> characteristic() const override;
  std::optional<double> wheel_period_s() const override;
  const PenetrationDampingParameters& parameters() const { return parameters_; }

  // G4 closed forms at the model's speeds and geometry.
  const ClosedFormIndicators* closed_forms() const override { return this; }
  std::vector<ClosedFormIndicatorSpec> indicator_specs() const override;
  std::vector<Json> indicator_values() const override;

  // The G1 chain with kd beside kw (the compliance chart refuses it: StiffnessChain).
  std::optional<StiffnessChain> stiffness_chain() const override;
  const StructuralCompliance* structural_compliance() const override { return this; }
  Complex compliance_m_per_n(Complex s) const override;

  // G1's rules (shared/plunge_dynamics/process_scaling.hpp) and kd ~ ks sqrt(de u0)/vw.
  const ProcessConditionsModel* process_conditions() const override { return this; }
  ProcessConditions nominal_conditions() const override;
  Json parameters_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                     const ProcessScaling& scaling) const override;

 private:
  PenetrationDampingParameters parameters_;
  PlungeCharacteristic g1_;  // H(s) of the compliance capability
};

}  // namespace chatterlab
