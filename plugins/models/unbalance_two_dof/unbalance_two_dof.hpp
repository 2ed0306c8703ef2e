#pragma once
// MODELS.md G6: forced vibration from wheel unbalance, eqs 3-1..3-6, in the time domain:
//
//   m1 x1'' + c1 x1' + (k + k1) x1 + k x2 = F,   F = U w^2 cos th_g(t)
//   m2 x2'' + c2 x2' + (k + k2) x2 + k x1 = 0,   k = kc kg / (kc + kg)
//
// (signs as printed: x2 is measured against x1, so x1 + x2 is the relative wheel-work motion;
// w = the current wheel speed, th_g the wheel angle, w t at constant speed). The relative motion is
// imprinted on the workpiece surface once per work revolution, which shows Z = n_g/n_w lobes per
// revolution. The work surface stored by the engine is that copy of x1 + x2 (no regeneration:
// the forced response alone). Linear: contact is never lost.
//
// Written once (derived_model.hpp): the same templated equations give the simulation (with the
// fixed-step engine's exact linear form) and the stability route. The unbalance force is an
// additive forcing that does not depend on the state, so the linearisation (and the stability of
// any response) is that of the autonomous two-DOF structure: stability_map reports its certified
// rightmost root through the derived route. The closed forms (unbalance_closed_form.hpp) are
// reported beside the roots and beside the simulated steady amplitude (ClosedFormIndicators).
// Docs: docs/models/unbalance_two_dof.md.
#include <cmath>
#include <numbers>
#include <optional>
#include <span>

#include "chatterlab/closed_form.hpp"
#include "chatterlab/derived_model.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "models/unbalance_two_dof/unbalance_closed_form.hpp"

namespace chatterlab {

// The parameters are MODELS.md G6's, shared with the closed form (one definition).
// State: x1, x1', x2, x2'.
struct UnbalanceTwoDofEquations {
  UnbalanceTwoDofEquations(const UnbalanceTwoDofParameters& parameters) : p(parameters) {}  // NOLINT: implicit
  UnbalanceTwoDofParameters p;

  std::size_t state_size() const { return 4; }
  void initial_state(const Disturbance& d, std::span<double> x) const;
  void state_scales(double displacement_m, std::span<double> scales) const;
  double highest_frequency_hz() const;
  bool regenerates(Rotor rotor) const { return rotor == Rotor::work; }
  double nominal_speed_rpm(Rotor rotor) const { return rotor == Rotor::wheel ? p.wheel_speed_rpm : p.work_speed_rpm; }
  // The relative wheel-work motion x1 + x2.
  double displacement_m(std::span<const double> s) const { return s[0] + s[2]; }

  template <class S>
  void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const {
    constexpr auto work = static_cast<std::size_t>(Rotor::work);
    const S relative = in.state[0] + in.state[2];
    out.penetration_m = S(1.0);  // linear model: always in contact
    out.normal_force_n = unbalance::coupling_stiffness_n_per_m(p) * relative;  // force through the contact spring
    out.depth_of_cut_m = relative;
    // The work surface keeps a copy of the relative motion: increment over one revolution ago.
    out.removed_m[work] = relative - in.previous_surface_m[work];
  }
  template <class S>
  void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& /*contact*/, std::span<S> dx) const {
    const double force = unbalance_force_n(in);
    const double k = unbalance::coupling_stiffness_n_per_m(p);
    const S x1 = in.state[0], v1 = in.state[1], x2 = in.state[2], v2 = in.state[3];
    dx[0] = v1;
    dx[1] = (force - p.wheel_damping_n_s_per_m * v1 - (k + p.wheel_support_stiffness_n_per_m) * x1 - k * x2) /
            p.wheel_mass_kg;
    dx[2] = v2;
    dx[3] = (-p.work_damping_n_s_per_m * v2 - (k + p.work_support_stiffness_n_per_m) * x2 - k * x1) / p.work_mass_kg;
  }
  // F = U w^2 cos th_g at the current wheel speed and angle: independent of the state.
  template <class S>
  double unbalance_force_n(const ContactInputOf<S>& in) const {
    constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel);
    const double w = 2.0 * std::numbers::pi * in.speed_rpm[wheel] / 60.0;
    return p.unbalance_kg_m * w * w * std::cos(in.angle_rad[wheel]);
  }
  // The fixed-step engine's exact propagation (dynamics.hpp, LinearForm): the state matrix is the
  // derived Jacobian's state block, the forcing the unbalance force entering the wheel equation.
  std::optional<LinearForm> linear_form(double t_s) const;
  double linear_forcing(const ContactInputOf<double>& in) const { return unbalance_force_n(in); }
};

class UnbalanceTwoDof final : public DerivedModel<UnbalanceTwoDofEquations>, public ClosedFormIndicators {
 public:
  explicit UnbalanceTwoDof(const ParamValues& values);
  explicit UnbalanceTwoDof(UnbalanceTwoDofParameters p) : DerivedModel(UnbalanceTwoDofEquations(p)) {}
  static PluginInfo info();
  const UnbalanceTwoDofParameters& parameters() const { return equations().p; }

  // G6 closed forms (unbalance_closed_form.hpp) beside the roots and the simulated amplitude.
  const ClosedFormIndicators* closed_forms() const override { return this; }
  std::vector<ClosedFormIndicatorSpec> indicator_specs() const override;
  std::vector<Json> indicator_values() const override;
};

// The engine's view of the equations (tests simulate it directly).
using UnbalanceTwoDofTimeDomain = EquationsTimeDomain<UnbalanceTwoDofEquations>;

}  // namespace chatterlab
