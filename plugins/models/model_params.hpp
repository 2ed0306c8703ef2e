#pragma once
// Shared ParamSpec builders of the model plugins (on top of chatterlab::param_spec).
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

// A real number >= 0 (damping, a coefficient that may vanish).
inline ParamSpec non_negative(std::string key, std::string unit, std::string description) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::real, std::move(unit), std::move(description));
  spec.min = 0.0;
  return spec;
}

// A dimensionless fraction in [0, 1], or [0, 1) when 1 is excluded (a damping ratio of 1 is no
// longer a vibration mode; a modulation depth of 1 would switch the process off).
inline ParamSpec fraction(std::string key, std::string description, bool one_excluded) {
  ParamSpec spec = non_negative(std::move(key), "1", std::move(description));
  spec.max = 1.0;
  spec.max_exclusive = one_excluded;
  return spec;
}

}  // namespace chatterlab::model_params
