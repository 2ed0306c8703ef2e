#pragma once
// MODELS.md G1: the parameters of the Snoeys-type plunge-grinding model (speeds, the contact,
// wear and removal stiffnesses, the machine's structural modes, the two regeneration switches),
// declared once (chatterlab/param_table.hpp) for every model of the family: plunge_regenerative,
// plunge_with_penetration_damping (G1 + G4's kd), and thompson's equivalent G1 system.
#include <vector>

#include "chatterlab/model.hpp"
#include "chatterlab/param_table.hpp"

namespace chatterlab {

struct StructuralMode {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  double stiffness_n_per_m = 0.0;
};

struct PlungeRegenerativeParameters {
  double wheel_speed_rpm = 0.0;
  double work_speed_rpm = 0.0;
  double contact_stiffness_n_per_m = 0.0;       // kc
  double wheel_wear_stiffness_n_per_m = 0.0;    // kg
  double work_removal_stiffness_n_per_m = 0.0;  // kw
  std::vector<StructuralMode> modes;
  bool wheel_regeneration = true;
  bool work_regeneration = true;
};

namespace plunge_dynamics {

// The G1 parameter table: `chatterlab describe plunge_regenerative` prints it.
const ParamTable<PlungeRegenerativeParameters>& plunge_parameters_table();

// The numbers of plunge_parameters_table().write(p) in the table's order (switches as 0/1):
// ProcessConditionsModel::parameter_values_at without building the table.
void parameter_values(const PlungeRegenerativeParameters& p, std::vector<double>& values);

// The family's example (`chatterlab describe plunge_regenerative`): the G8 experiment's speeds and
// its 184 Hz and 306 Hz modes; the stiffnesses are assumptions of the right order for an external
// cylindrical grinder (docs/models/plunge_regenerative.md).
Json example_g1_parameters();

// The stiffness chain of these parameters (Model::stiffness_chain()): a chain that is switched
// off has an infinite stiffness (its term vanishes from eq 2-16).
StiffnessChain stiffness_chain(const PlungeRegenerativeParameters& parameters);

}  // namespace plunge_dynamics
}  // namespace chatterlab
