#pragma once
// stability_map's Floquet route: a study with a [suppression] table (a speed-modulation plugin,
// MODELS.md S2/S3, e.g. variable_speed) asks for the stability of the periodic linearisation
// instead of the autonomous rightmost root. The model's linearisation (Model::linearised(),
// chatterlab/linearised_model.hpp) along the modulated speeds and revolution delays is discretised
// by semi-discretisation (chatterlab/floquet.hpp); the growth rate is ln|mu| / T of the dominant
// Floquet multiplier mu over one modulation period T. docs/derived_stability.md, "Floquet".
#include <memory>
#include <string>

#include "chatterlab/floquet.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/suppression.hpp"

namespace chatterlab::stability_floquet {

// The shapes a periodic linearisation takes; refused otherwise (InputError naming file, line,
// key, value and the reason): a target other than a rotor speed, a non-periodic law (random), a
// model without a linearisation or whose modulated speed is a state, and a monodromy larger than
// the discretisation's limit at the first level. Validates and fills `document["suppression"]`.
void validate(Json& document, const Model& model, const SourceMap& sources);

struct FloquetPoint {
  FloquetResult floquet;
  double period_s = 0.0;           // T: one modulation period (a revolution of the target rotor at amplitude 0)
  std::string target;              // wheel_speed / work_speed
};

// The Floquet growth rate of `model` under the modulation of `suppression_table` (validated).
// Throws PointFailure when the discretisation fails.
FloquetPoint growth_rate(const Model& model, const Json& suppression_table,
                         const FloquetSettings& settings = {});

}  // namespace chatterlab::stability_floquet
