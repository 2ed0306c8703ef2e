#pragma once
// MODELS.md G7: regenerative-forced hybrid chatter (amplitude modulation), eqs 3-9..3-20.
// Wheel-regenerative chatter whose grinding stiffness is modulated once per wheel revolution
// (unbalance):
//
//   F_p(t) = -kg b (1 + Q sin th_g(t)) (x(t) - mu x(t - Tg)),   x = x1 + x2,  x2 = F_p / (kc b),
//   m x1'' + c x1' + k x1 = F_p,
//
// th_g the wheel angle (w0 t at constant speed), x(t - Tg) the wheel surface one revolution ago
// by angle. Solving the algebraic loop: F_p = -g (x1 - mu x(t - Tg)) / (1 + g/(kc b)),
// g = kg b (1 + Q sin th_g). A periodic-coefficient DDE: its Floquet solution has a carrier at
// the chatter frequency and sidebands spaced by the wheel rotation frequency; the time signal
// beats with the wheel period. Linear perturbation model: contact is never lost (the
// steady grinding force is not part of it). Written once: stability_map reports the Floquet growth
// rate of its periodic linearisation (route "floquet"). Docs: docs/models/amplitude_modulated.md.
#include <cmath>
#include <memory>
#include <optional>
#include <span>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "models/amplitude_modulated/floquet_growth.hpp"

namespace chatterlab {

// The plugin's parameters in modal form (natural frequency and damping ratio). A different type
// from floquet_growth.hpp's AmplitudeModulatedParameters (mass, damping, stiffness), which
// floquet_parameters converts to: one equation, two parameterisations.
struct AmplitudeModulatedModalParameters {
  double frequency_hz = 0.0;                  // structural natural frequency sqrt(k/m)/2 pi
  double damping_ratio = 0.0;                 // c / (2 sqrt(k m))
  double stiffness_n_per_m = 0.0;             // k
  double grinding_stiffness_n_per_m = 0.0;    // kg b
  double contact_stiffness_n_per_m = 0.0;     // kc b
  double overlap_factor = 1.0;                // mu
  double modulation_depth = 0.0;              // Q
  double wheel_speed_rpm = 0.0;               // n_g, w0 = 2 pi n_g / 60
  double work_speed_rpm = 55.0;               // n_w (reported; the model regenerates the wheel)
};

// The same model for floquet_growth(): m = k/w^2, c = 2 zeta sqrt(k m).
AmplitudeModulatedParameters floquet_parameters(const AmplitudeModulatedModalParameters& p);

// G7 written once (derived_model.hpp): the templated equations give the simulation and, by
// automatic differentiation, the periodic linearisation whose Floquet growth rate stability_map
// reports (floquet.hpp). State: x1, x1'; the wheel surface stores x = x1 + x2.
struct AmplitudeModulatedEquations {
  AmplitudeModulatedEquations(const AmplitudeModulatedModalParameters& parameters);  // NOLINT: implicit
  AmplitudeModulatedModalParameters p;
  double omega_rad_s = 0.0;  // 2 pi frequency_hz

  std::size_t state_size() const { return 2; }
  void initial_state(const Disturbance& d, std::span<double> x) const;
  void state_scales(double displacement_m, std::span<double> scales) const;
  double highest_frequency_hz() const;
  bool regenerates(Rotor rotor) const { return rotor == Rotor::wheel; }
  double nominal_speed_rpm(Rotor rotor) const { return rotor == Rotor::wheel ? p.wheel_speed_rpm : p.work_speed_rpm; }
  double displacement_m(std::span<const double> state) const { return state[0]; }

  template <class S>
  void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const {
    constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel);
    const double g = p.grinding_stiffness_n_per_m * (1.0 + p.modulation_depth * std::sin(in.angle_rad[wheel]));
    const S x1 = in.state[0];
    const S delayed = in.previous_surface_m[wheel];  // x(t - Tg)
    const S force = -g * (x1 - p.overlap_factor * delayed) / (1.0 + g / p.contact_stiffness_n_per_m);
    const S x = x1 + force / p.contact_stiffness_n_per_m;
    out.penetration_m = S(1.0);  // linear perturbation model: always in contact
    out.normal_force_n = force;
    out.depth_of_cut_m = x - p.overlap_factor * delayed;
    // The stored wheel surface is x(t): the increment over one revolution ago.
    out.removed_m[wheel] = x - delayed;
  }
  template <class S>
  void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& contact, std::span<S> dx) const {
    dx[0] = in.state[1];
    dx[1] = omega_rad_s * omega_rad_s * (contact.normal_force_n / p.stiffness_n_per_m - in.state[0]) -
            2.0 * p.damping_ratio * omega_rad_s * in.state[1];
  }
};

class AmplitudeModulated final : public DerivedModel<AmplitudeModulatedEquations> {
 public:
  explicit AmplitudeModulated(const ParamValues& values);
  explicit AmplitudeModulated(const AmplitudeModulatedModalParameters& p) : DerivedModel(AmplitudeModulatedEquations(p)) {}
  static PluginInfo info();
  const AmplitudeModulatedModalParameters& parameters() const { return equations().p; }
  // The grinding stiffness follows the wheel angle: the linearisation's coefficients repeat once
  // per wheel revolution, so there is no characteristic function (an autonomous root at one
  // wheel angle would be wrong); the stability is the Floquet growth rate over that period.
  std::unique_ptr<CharacteristicFunction> characteristic() const override { return nullptr; }
  std::optional<double> coefficient_period_s() const override { return 60.0 / parameters().wheel_speed_rpm; }
};

// The engine's view of the equations (tests simulate it directly).
using AmplitudeModulatedTimeDomain = EquationsTimeDomain<AmplitudeModulatedEquations>;

}  // namespace chatterlab
