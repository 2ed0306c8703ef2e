#pragma once
// The fixed-step route of the dynamics engine (the default): steps of one size tuned to the
// model's highest frequency and aligned with the output samples; exact exponential propagation of
// a model's LinearForm (linear_propagator.hpp), classical fourth-order Runge-Kutta otherwise;
// contact events located inside a step and the step split there. docs/dynamics.md.
#include "chatterlab/dynamics.hpp"

namespace chatterlab::dynamics_detail {

// Steps per wave of the model's highest frequency when SimulationSettings::fixed_steps_per_wave
// is 0 (docs/dynamics.md, "Fixed-step settings and why"): exponential propagation with bilateral
// contact; with one-sided contact (the surfaces then carry kinks where contact was lost, which
// the forcing cells must resolve) and for Runge-Kutta.
inline constexpr double kDefaultExponentialStepsPerWave = 10.0;
inline constexpr double kDefaultOneSidedStepsPerWave = 40.0;
inline constexpr double kDefaultRungeKuttaStepsPerWave = 60.0;

// simulate() for settings.integrator = fixed_step.
SimulationResult simulate_fixed_step(const TimeDomainModel& model, const SimulationSettings& settings);

}  // namespace chatterlab::dynamics_detail
