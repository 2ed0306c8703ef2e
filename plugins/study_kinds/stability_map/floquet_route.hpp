#pragma once
// stability_map's Floquet route: a study with a [suppression] table (a speed-modulation plugin,
// MODELS.md S2/S3, e.g. variable_speed) asks for the stability of the periodic linearisation
// instead of the autonomous rightmost root. The model's linearisation (Model::linearised(),
// chatterlab/linearised_model.hpp) along the modulated speeds and revolution delays is discretised
// by semi-discretisation (chatterlab/floquet.hpp); the growth rate is ln|mu| / T of the dominant
// Floquet multiplier mu over one modulation period T. docs/derived_stability.md, "Floquet".
#include <memory>
#include <optional>
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

// ---- models whose linearisation has periodic coefficients at constant speeds (G7)

// The model's coefficient period (LinearisedModel::coefficient_period_s), or nullopt: a study of
// such a model takes the Floquet route without a [suppression] table.
std::optional<double> coefficient_period_s(const Model& model);

// Refuses (InputError naming file, line, key, value and the reason) a [suppression] table on such
// a model (the modulation period and the coefficients' period are in general incommensurate, so
// the process has no common period) and a monodromy beyond the discretisation's limit.
void validate_periodic_model(const Json& document, const Model& model, const SourceMap& sources);

// The Floquet growth rate over one coefficient period at the model's nominal constant speeds.
// Throws PointFailure when the discretisation fails.
FloquetPoint periodic_model_growth_rate(const Model& model, const FloquetSettings& settings = {});

}  // namespace chatterlab::stability_floquet
