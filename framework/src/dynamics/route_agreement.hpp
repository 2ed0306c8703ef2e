#pragma once
// How closely two simulations of one model agree (the fixed-step engine against the adaptive
// reference route): what the equivalence tests assert and the benchmark reports
// (docs/dynamics.md, "Equivalence with the reference route").
#include <cstddef>

#include "chatterlab/dynamics.hpp"

namespace chatterlab::dynamics_detail {

struct RouteAgreement {
  double reference_growth_per_s = 0.0, growth_per_s = 0.0;
  double reference_frequency_hz = 0.0, frequency_hz = 0.0;
  double growth_error = 0.0;     // |growth / reference - 1|
  double frequency_error = 0.0;  // |frequency / reference - 1|
  double surface_error = 0.0;    // largest over the regenerated rotors (0 when none)
};

// Growth rates fitted over [from_s, to_s] (fit_envelope, peaks below floor_hz ignored); the
// chatter frequency: the reference's dominant spectral line in that window, and the line of the
// other run nearest to it among its four strongest (both Hann spectra, peaks interpolated);
// surfaces: rms of the difference of the snapshots `snapshot` of each regenerated rotor over the
// rms of the reference snapshot about its mean.
RouteAgreement route_agreement(const SimulationResult& reference, const SimulationResult& other, double from_s,
                               double to_s, double floor_hz = 10.0, std::size_t snapshot = 0);

}  // namespace chatterlab::dynamics_detail
