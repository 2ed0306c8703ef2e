#pragma once
// A dynamics model plugin (MODELS.md G1..G7). The model supplies physics only; the framework owns
// root finding, integration, grids and output.
//
// Capabilities beyond the physics are typed interfaces a model class may also derive from; study
// kinds reach them through the accessors below (the model returns `this`), never by the model's
// name or by casting to a plugin's class (stability routes: characteristic() for the roots,
// return_difference() for the Nyquist count on the imaginary axis):
//   ClosedFormIndicators (closed_form.hpp)    closed-form criteria reported beside the roots
//   ProcessConditionsModel (process_conditions.hpp)  parameters that follow the process conditions
//   StiffnessChain (below)                    the G1 stiffness chain, for the closed forms
//   LinearisedModel (linearised_model.hpp)    the linearisation derived from the physics written
//                                             once (derived_model.hpp): roots, Floquet
//   MeasuredMachine (modal_fit.hpp)           the measured FRF (and modal fit) the model is built on
//   StructuralCompliance (below)              the machine's compliance H(s) between wheel and work
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/nyquist.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

class ClosedFormIndicators;
class LinearisedModel;
class MeasuredMachine;
class ProcessConditionsModel;

// A structural mode as the closed forms of MODELS.md G1/G3/S1 see it.
struct ModeView {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  double stiffness_n_per_m = 0.0;
};

// The G1 (Snoeys) stiffness chain of a model: the process line of the compliance chart (eq 2-21)
// and the closed forms (G3 wheel growth rate, S1 chatter frequency under variable feed) need it.
// A regeneration that is switched off has an infinite stiffness (its term vanishes from 2-16).
struct StiffnessChain {
  double contact_stiffness_n_per_m = 0.0;  // kc
  double wheel_wear_stiffness_n_per_m = std::numeric_limits<double>::infinity();    // kg
  double work_removal_stiffness_n_per_m = std::numeric_limits<double>::infinity();  // kw
  std::vector<ModeView> modes;
  // G4's penetration-rate coefficient kd [N s/m] acting beside kw in the work chain (0: none).
  // With kd > 0 the work term of eq 2-16 is 1/(kw (1 - e^{-Tw s}) + kd s), whose real part on
  // s = jw is no longer 1/(2 kw): a closed form built on eq 2-21 (the compliance chart's process
  // line) does not hold and must refuse such a chain.
  double penetration_damping_n_s_per_m = 0.0;
};

// Capability of a model: the machine's structural compliance H(s) [m/N] between wheel and work
// in the direction of the normal force (G1: the summed modal compliances), at any complex s [1/s];
// the compliance chart draws H(jw) against the process line.
class StructuralCompliance {
 public:
  virtual ~StructuralCompliance() = default;
  virtual Complex compliance_m_per_n(Complex s) const = 0;
};

class Model {
 public:
  virtual ~Model() = default;

  // Linear stability: the characteristic function at this model's parameters, or null when the
  // model has none (e.g. a purely nonlinear model).
  virtual std::unique_ptr<CharacteristicFunction> characteristic() const { return nullptr; }

  // Linear stability on the imaginary axis alone (chatterlab/nyquist.hpp): the return difference
  // F(j w) whose Nyquist count is the number of unstable roots, or null. A model known only at
  // s = j w (a measured FRF) has this and no characteristic function; a model with both offers
  // two independent routes to the same boundary.
  virtual std::unique_ptr<ReturnDifference> return_difference() const { return nullptr; }

  // Wheel revolution period Tg [s] if the model has a wheel; gives growth per wheel revolution
  // rho = Tg Re(s) / 2 pi (MODELS.md G3).
  virtual std::optional<double> wheel_period_s() const { return std::nullopt; }

  // Time-domain form (states, contact law, regenerated surfaces) for the dynamics engine
  // (chatterlab/dynamics.hpp, study kind `simulate`), or null when the model has none.
  virtual std::unique_ptr<TimeDomainModel> time_domain() const { return nullptr; }

  // ---- capabilities (null / nullopt: the model does not have it)
  virtual const ClosedFormIndicators* closed_forms() const { return nullptr; }
  virtual const ProcessConditionsModel* process_conditions() const { return nullptr; }
  virtual const MeasuredMachine* measured_machine() const { return nullptr; }
  // The G1 stiffness chain, for models of the Snoeys family (plunge_regenerative, thompson, ...).
  virtual std::optional<StiffnessChain> stiffness_chain() const { return std::nullopt; }
  // The linearisation of a model written once (DerivedModel provides it).
  virtual const LinearisedModel* linearised() const { return nullptr; }
  virtual const StructuralCompliance* structural_compliance() const { return nullptr; }
};

}  // namespace chatterlab
