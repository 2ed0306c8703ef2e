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
// steady grinding force is not part of it). Docs: docs/models/amplitude_modulated.md.
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

class AmplitudeModulatedTimeDomain final : public TimeDomainModel {
 public:
  explicit AmplitudeModulatedTimeDomain(const AmplitudeModulatedModalParameters& p);
  std::size_t state_size() const override { return 2; }
  void initial_state(const Disturbance& d, std::span<double> x) const override;
  void state_scales(double displacement_m, std::span<double> scales) const override;
  double highest_frequency_hz() const override;
  bool regenerates(Rotor rotor) const override { return rotor == Rotor::wheel; }
  double nominal_speed_rpm(Rotor rotor) const override;
  void contact(const ContactInput& in, ContactOutput& out) const override;
  void derivatives(const ContactInput& in, const ContactOutput& contact, std::span<double> dx) const override;
  double displacement_m(std::span<const double> state) const override { return state[0]; }

 private:
  AmplitudeModulatedModalParameters p_;
  double omega_;
};

class AmplitudeModulated final : public Model {
 public:
  explicit AmplitudeModulated(const ParamValues& values);
  explicit AmplitudeModulated(AmplitudeModulatedModalParameters p) : p_(p) {}
  static PluginInfo info();
  std::optional<double> wheel_period_s() const override { return 60.0 / p_.wheel_speed_rpm; }
  std::unique_ptr<TimeDomainModel> time_domain() const override {
    return std::make_unique<AmplitudeModulatedTimeDomain>(p_);
  }
  const AmplitudeModulatedModalParameters& parameters() const { return p_; }

 private:
  AmplitudeModulatedModalParameters p_;
};

}  // namespace chatterlab
