#pragma once
// Capability of a model: its linearisation, derived from its time-domain physics (a model written
// once, derived_model.hpp). Study kinds reach it through Model::linearised(); it gives the Jacobian
// of the model's physics at the rest point of any process point (constant or varying speeds,
// angles, time). From it the framework assembles
//   - the linear delay-differential-algebraic system at constant speeds: the state x and one
//     algebraic variable per regenerated surface, S_r(t) = S_r(t - T_r) + removed_r(t) with T_r
//     one revolution (MODELS.md G1's surfaces), and its certified characteristic function
//     (derived_characteristic below; the matrices: framework/src/derived/surface_system.hpp);
//   - the periodic system of a varying process, for Floquet analysis (floquet.hpp).
// This header needs no linear-algebra library: a plugin written against the SDK includes it as is.
// docs/derived_stability.md.
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/dynamics.hpp"

namespace chatterlab {

// The variables of a model written once: its states, then one surface per regenerated rotor.
struct SurfaceLayout {
  std::size_t states = 0;
  std::vector<Rotor> regenerated;  // in variable order
  double nominal_speed_rpm[rotor_count] = {0.0, 0.0};
  std::size_t size() const { return states + regenerated.size(); }
};

// Where the process is when a linearisation is taken (the state and surfaces are at the model's
// rest point; the engine's one-sided contact is taken as closed).
struct ProcessPoint {
  double t_s = 0.0;
  double speed_rpm[rotor_count] = {0.0, 0.0};  // 0: the nominal speed
  double angle_rad[rotor_count] = {0.0, 0.0};
  double infeed_m = 0.0;
  double infeed_rate_m_per_s = 0.0;
};

// A dense matrix, row-major (the Jacobian crosses the public interface without Eigen).
struct JacobianMatrix {
  std::size_t rows = 0, cols = 0;
  std::vector<double> values;  // rows * cols, row-major
  JacobianMatrix() = default;
  JacobianMatrix(std::size_t r, std::size_t c) : rows(r), cols(c), values(r * c, 0.0) {}
  double& operator()(std::size_t i, std::size_t j) { return values[i * cols + j]; }
  double operator()(std::size_t i, std::size_t j) const { return values[i * cols + j]; }
  bool operator==(const JacobianMatrix&) const = default;
};

class LinearisedModel {
 public:
  virtual ~LinearisedModel() = default;

  virtual SurfaceLayout surface_layout() const = 0;

  // Jacobian of (state derivative, removal per regenerated surface) with respect to (state,
  // surface one revolution ago per regenerated rotor) at `point`: (n + r) x (n + r), by automatic
  // differentiation of the model's own contact law and derivatives.
  virtual JacobianMatrix jacobian(const ProcessPoint& point) const = 0;

  // The period [s] of the linearisation's coefficients at the nominal constant speeds when they
  // depend on the rotor angles (G7: an unbalance modulates the grinding stiffness once per wheel
  // revolution); nullopt when they are constant. A model with periodic coefficients has no
  // characteristic function: its stability is the Floquet growth rate over this period
  // (floquet.hpp; stability_map takes that route).
  virtual std::optional<double> coefficient_period_s() const { return std::nullopt; }
};

// The certified characteristic function (DelayCharacteristic, delay_system.hpp) of the linear
// system at `point` with the delays of constant speeds (one revolution each):
//   x' = J_xx x + sum_r J_xr S_r(t - T_r),
//   0  = -S_r + S_r(t - T_r) + J_rx x + sum_r' J_rr' S_r'(t - T_r').
std::unique_ptr<CharacteristicFunction> derived_characteristic(const LinearisedModel& model,
                                                               const ProcessPoint& point = {});

}  // namespace chatterlab
