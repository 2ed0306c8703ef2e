#pragma once
// Shared ParamSpec builder of the model plugins (on top of chatterlab::param_spec).
#include <string>
#include <utility>

#include "chatterlab/params.hpp"

namespace chatterlab::model_params {

// A real number > 0 (stiffness, speed, frequency, delay).
inline ParamSpec positive(std::string key, std::string unit, std::string description) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::real, std::move(unit), std::move(description));
  spec.min = 0.0;
  spec.min_exclusive = true;
  return spec;
}

}  // namespace chatterlab::model_params
