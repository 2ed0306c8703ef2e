#pragma once
// Closed-form stability indicators a model may report next to its characteristic roots (e.g. the
// Thompson criteria of MODELS.md G2, G6's forced amplitude). A model opts in by also deriving from
// ClosedFormIndicators and returning `this` from Model::closed_forms(); the stability_map study
// kind then appends one results.csv column per indicator, so the closed forms and the rightmost
// root can be compared point by point, and `simulate` appends the indicators that predict a
// simulated quantity (ClosedFormIndicatorSpec::predicts) beside it.
#include <string>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

struct ClosedFormIndicatorSpec {
  std::string name;         // results.csv column; unit in the name (e.g. "..._n_s_per_m")
  std::string description;  // one line
  // A chatter margin: > 0 predicts chatter, < 0 stability, 0 the boundary. stability_map draws
  // such an indicator as a map with its zero contour and counts the points where its sign
  // disagrees with the rightmost root's.
  bool chatter_margin = false;
  // What a simulation of the model measures that this closed form predicts. steady_amplitude: the
  // amplitude (half peak-to-peak) of TimeDomainModel::displacement_m once the transient has
  // decayed, at the model's constant nominal speeds with the contact kept (G6's forced response).
  // `simulate` writes such an indicator beside the simulated quantity, or null with the reason
  // where the run is not the closed form's case.
  enum class Predicts { nothing, steady_amplitude };
  Predicts predicts = Predicts::nothing;
};

class ClosedFormIndicators {
 public:
  virtual ~ClosedFormIndicators() = default;
  // The indicators of this model type, in column order. Must not depend on parameter values (the
  // columns are fixed for the whole study).
  virtual std::vector<ClosedFormIndicatorSpec> indicator_specs() const = 0;
  // One value per spec, at this model's parameters: a finite number, a boolean, or null where the
  // indicator does not apply (e.g. no conditional band above the unconditional damping).
  virtual std::vector<Json> indicator_values() const = 0;
};

}  // namespace chatterlab
