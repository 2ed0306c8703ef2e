#pragma once
// The adaptive SUNDIALS route of the dynamics engine (ARKODE ERKStep or CVODE Adams): the
// reference that the fixed-step engine's equivalence tests compare against.
#include <string>

#include "chatterlab/dynamics.hpp"

namespace chatterlab::dynamics_detail {

// simulate() for settings.integrator = explicit_runge_kutta or adams.
SimulationResult simulate_sundials(const TimeDomainModel& model, const SimulationSettings& settings);

// Test hook: while `routine` is set (on this thread), the SUNDIALS call of that name reports
// failure (a failure flag, or no object from a constructor), so a test can check that every
// refused call is a PointFailure naming it. An empty name switches the hook off.
void fail_sundials_call_for_testing(std::string routine);

}  // namespace chatterlab::dynamics_detail
