#pragma once
// The `simulate` kind's closed-form columns (issue 19): a model's closed forms that predict a
// simulated quantity (ClosedFormIndicatorSpec::predicts, chatterlab/closed_form.hpp; G6's forced
// amplitude) are written beside that quantity, or null with the reason where the run is not the
// closed form's case (speeds not constant at the nominal ones, contact opened). Models without
// such a closed form get no extra columns.
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::simulate_closed_forms {

// steady_amplitude_m, one column per predicting closed form, closed_form_note; empty when the
// model has no closed form that predicts a simulated quantity.
std::vector<std::string> columns(const Model& model);

// The values of columns(model) for a finished run of the model's time-domain form.
std::vector<Json> values(const Model& model, const TimeDomainModel& time_domain, const SimulationResult& run);

// The simulated steady amplitude: half peak-to-peak of the displacement over the last whole (even)
// number of cycles in the last fifth of the run (between upward crossings of that fifth's mean),
// and whether it is steady (the two halves of those
// cycles agree within 1 %; fewer than 4 cycles: the whole fifth, not judged steady). Null when the
// fifth holds fewer than 32 samples.
struct SteadyAmplitude {
  Json amplitude_m;
  bool steady = false;
  double change = 0.0;  // relative change between the halves
};
SteadyAmplitude steady_amplitude(const SimulationResult& run);

}  // namespace chatterlab::simulate_closed_forms
