#pragma once
// Shared by the study kinds that build a model from a study's [model] table (stability_map,
// simulate): one place that maps `type` to the registered plugin and passes the other keys on.
#include <memory>

#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::kinds_detail {

// The model plugin named by model_table["type"], created from the table's other keys. The
// registry and ParamValues raise the errors (unknown type, bad parameter) the kinds report.
std::unique_ptr<Model> build_model(const Json& model_table);

}  // namespace chatterlab::kinds_detail
