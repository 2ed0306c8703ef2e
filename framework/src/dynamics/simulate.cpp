// simulate() (chatterlab/dynamics.hpp): checks the settings and runs the chosen route, the
// fixed-step engine (fixed_step_engine.cpp) or the adaptive SUNDIALS reference
// (sundials_engine.cpp).
#include <stdexcept>
#include <string>

#include "chatterlab/dynamics.hpp"
#include "dynamics/fixed_step_engine.hpp"
#include "dynamics/sundials_engine.hpp"

namespace chatterlab {

const char* to_string(TimeIntegrator integrator) {
  switch (integrator) {
    case TimeIntegrator::fixed_step: return "fixed_step";
    case TimeIntegrator::adams: return "adams";
    case TimeIntegrator::explicit_runge_kutta: return "explicit_runge_kutta";
  }
  return "?";
}

TimeIntegrator parse_time_integrator(const std::string& name) {
  for (TimeIntegrator i : {TimeIntegrator::fixed_step, TimeIntegrator::explicit_runge_kutta, TimeIntegrator::adams})
    if (name == to_string(i)) return i;
  throw std::invalid_argument("unknown integrator '" + name + "' (valid: fixed_step, explicit_runge_kutta, adams)");
}

SimulationResult simulate(const TimeDomainModel& model, const SimulationSettings& settings) {
  if (settings.integrator == TimeIntegrator::fixed_step) return dynamics_detail::simulate_fixed_step(model, settings);
  return dynamics_detail::simulate_sundials(model, settings);
}

}  // namespace chatterlab
