#pragma once
// MODELS.md G5: torsional coupling model, book eqs 2-79..2-87, in the time domain. Transverse
// wheel-head motion, workpiece(+drive) torsion and wheel(+spindle) torsion, coupled only through
// the grinding force, whose size depends on both speeds:
//
//   delta_w = (x - Rw(prev rev) - Rg(prev rev)) / (1 + lambda_w/lambda_g),  delta_g = delta_w lambda_w/lambda_g
//   F = lambda_w b delta_w * (n_w + phi_w' 60/2pi)/n_w * n_g/(n_g + phi_g' 60/2pi)   (speed correction)
//   lambda_g = lambda_w Gr Rg0 n_g / (Rw0 n_w)                                    (grinding ratio Gr)
//   m x'' + c (x' - f) + k (x - x0) = -F cos(alpha),   x0 = f t (infeed)
//   Iw phi_w'' + cw phi_w' + kw phi_w = -F Rw0 sin(alpha),  Ig phi_g'' + cg phi_g' + kg phi_g = -F Rg0 sin(alpha)
//
// The rotation angles are states (th' = 2 pi n/60 + phi'), so the surfaces (radial-line memory of
// the book, here angle-indexed samples) are read one revolution ago of the *actual* rotation.
// Wheel speed approaching zero makes the force law singular (F ~ 1/v_g): below 1 % of the
// nominal wheel speed the force is set to zero and a diagnostic records when (no NaN).
// Docs: docs/models/torsional_coupling.md.
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

struct TorsionalCouplingParameters {
  double mass_kg = 0, damping_n_s_per_m = 0, stiffness_n_per_m = 0;
  double work_inertia_kg_m2 = 0, work_torsional_damping_n_m_s = 0, work_torsional_stiffness_n_m = 0;
  double wheel_inertia_kg_m2 = 0, wheel_torsional_damping_n_m_s = 0, wheel_torsional_stiffness_n_m = 0;
  double work_radius_m = 0, wheel_radius_m = 0;
  double work_speed_rpm = 0, wheel_speed_rpm = 0;
  double grinding_width_m = 0;
  double removal_coefficient_n_per_m2 = 0;  // lambda_w: force per unit width per depth of cut
  double grinding_ratio = 0;                // Gr
  double force_angle_deg = 0;               // alpha
};

class TorsionalCouplingTimeDomain final : public TimeDomainModel {
 public:
  // State: x, x', phi_w, phi_w', phi_g, phi_g', th_w, th_g.
  explicit TorsionalCouplingTimeDomain(const TorsionalCouplingParameters& p);
  std::size_t state_size() const override { return 8; }
  void initial_state(const Disturbance& d, std::span<double> x) const override;
  void state_scales(double displacement_m, std::span<double> scales) const override;
  double highest_frequency_hz() const override;
  bool regenerates(Rotor) const override { return true; }
  double nominal_speed_rpm(Rotor rotor) const override;
  std::optional<std::size_t> angle_state(Rotor rotor) const override { return rotor == Rotor::work ? 6 : 7; }
  double speed_rpm_from_state(Rotor rotor, std::span<const double> state) const override;
  void contact(const ContactInput& in, ContactOutput& out) const override;
  void derivatives(const ContactInput& in, const ContactOutput& contact, std::span<double> dx) const override;
  double displacement_m(std::span<const double> state) const override { return state[0]; }
  std::vector<std::string> diagnostics() const override;

 private:
  TorsionalCouplingParameters p_;
  double lambda_ratio_;  // lambda_w / lambda_g
  double cos_alpha_, sin_alpha_;
  mutable double stalled_since_s_ = -1.0;  // first time the wheel speed fell below 1 % (diagnostic)
  mutable double lowest_wheel_rpm_;
};

class TorsionalCoupling final : public Model {
 public:
  explicit TorsionalCoupling(const ParamValues& values);
  explicit TorsionalCoupling(TorsionalCouplingParameters p) : p_(p) {}
  static PluginInfo info();
  std::optional<double> wheel_period_s() const override { return 60.0 / p_.wheel_speed_rpm; }
  std::unique_ptr<TimeDomainModel> time_domain() const override {
    return std::make_unique<TorsionalCouplingTimeDomain>(p_);
  }

 private:
  TorsionalCouplingParameters p_;
};

}  // namespace chatterlab
