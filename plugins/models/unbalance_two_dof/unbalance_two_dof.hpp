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
// the forced response alone). Linear: contact is never lost. Docs: docs/models/unbalance_two_dof.md.
#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "models/unbalance_two_dof/unbalance_closed_form.hpp"

namespace chatterlab {

// The parameters are MODELS.md G6's, shared with the closed form (one definition).

class UnbalanceTwoDofTimeDomain final : public TimeDomainModel {
 public:
  explicit UnbalanceTwoDofTimeDomain(const UnbalanceTwoDofParameters& p) : p_(p) {}
  std::size_t state_size() const override { return 4; }  // x1, x1', x2, x2'
  void initial_state(const Disturbance& d, std::span<double> x) const override;
  void state_scales(double displacement_m, std::span<double> scales) const override;
  double highest_frequency_hz() const override;
  bool regenerates(Rotor rotor) const override { return rotor == Rotor::work; }
  double nominal_speed_rpm(Rotor rotor) const override;
  void contact(const ContactInput& in, ContactOutput& out) const override;
  void derivatives(const ContactInput& in, const ContactOutput& contact, std::span<double> dx) const override;
  // The relative wheel-work motion x1 + x2.
  double displacement_m(std::span<const double> s) const override { return s[0] + s[2]; }
  // Linear with constant coefficients; forcing f = U w^2 cos th_g (the unbalance force).
  std::optional<LinearForm> linear_form(double t_s) const override;
  double linear_forcing(const ContactInput& in) const override;

 private:
  UnbalanceTwoDofParameters p_;
};

class UnbalanceTwoDof final : public Model {
 public:
  explicit UnbalanceTwoDof(const ParamValues& values);
  explicit UnbalanceTwoDof(UnbalanceTwoDofParameters p) : p_(p) {}
  static PluginInfo info();
  std::optional<double> wheel_period_s() const override { return 60.0 / p_.wheel_speed_rpm; }
  std::unique_ptr<TimeDomainModel> time_domain() const override {
    return std::make_unique<UnbalanceTwoDofTimeDomain>(p_);
  }
  const UnbalanceTwoDofParameters& parameters() const { return p_; }

 private:
  UnbalanceTwoDofParameters p_;
};

}  // namespace chatterlab
