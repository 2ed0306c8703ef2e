#pragma once
// Shared by the study kinds that build a model from a study's [model] table (stability_map,
// simulate): one place that maps `type` to the registered plugin and passes the other keys on.
#include <memory>

#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/roots.hpp"

namespace chatterlab::kinds_detail {

// The model plugin named by model_table["type"], created from the table's other keys. The
// registry and ParamValues raise the errors (unknown type, bad parameter) the kinds report.
std::unique_ptr<Model> build_model(const Json& model_table);

// Root search options from a validated [stability] table (StabilityMap::info().params): the band
// defaults to StabilityMap::default_band_multiple x the function's natural frequency scale.
RootSearchOptions root_search_options(const Json& stability_table, const CharacteristicFunction& fn);

// The certified rightmost root of `model` with the [stability] settings: what stability_map
// computes at a grid point (feed_risk calls it per condition group). Throws PointFailure when
// the model has no characteristic function or no root was found.
RightmostRoot rightmost_root(const Model& model, const Json& stability_table);

}  // namespace chatterlab::kinds_detail
