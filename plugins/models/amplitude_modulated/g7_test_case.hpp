#pragma once
// The G7 base case of this plugin's tests (floquet_growth_test.cpp, g7_written_once_test.cpp):
// one 251.6 Hz mode (20 kg, 5e7 N/m, 10 % damping), kc b = 1e8 N/m, kg b = 1e7 N/m, full overlap,
// no modulation, 1450 rpm: wheel-regenerative chatter. Tests vary kg b, mu and Q from here.
#include <cmath>

#include "models/amplitude_modulated/floquet_growth.hpp"

namespace chatterlab::testing {

inline AmplitudeModulatedParameters g7_base_case() {
  AmplitudeModulatedParameters p;
  p.mass_kg = 20.0;
  p.stiffness_n_per_m = 5e7;
  p.damping_n_s_per_m = 0.1 * std::sqrt(5e7 * 20.0);
  p.grinding_stiffness_n_per_m = 1e7;
  p.contact_stiffness_n_per_m = 1e8;
  p.overlap_factor = 1.0;
  p.modulation_depth = 0.0;
  p.wheel_speed_rpm = 1450.0;
  return p;
}

}  // namespace chatterlab::testing
