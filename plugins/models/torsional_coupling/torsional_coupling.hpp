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
// Written once: stability_map takes the certified rightmost root of the derived linearisation.
// Docs: docs/models/torsional_coupling.md.
#include <cmath>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/dual.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/process_conditions.hpp"
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

// G5 written once (derived_model.hpp): the time-domain physics, templated over the scalar type,
// is the single source of the simulation and of the stability route (the derived linearisation,
// docs/derived_stability.md). State: x, x', phi_w, phi_w', phi_g, phi_g', th_w, th_g. The speeds
// in the force law are read from the state (n + phi' 60/2pi), so automatic differentiation sees
// the speed correction; the engine's speeds (speed_rpm_from_state) are the same numbers.
struct TorsionalCouplingEquations {
  TorsionalCouplingEquations(const TorsionalCouplingParameters& p);  // NOLINT: implicit on purpose
  std::size_t state_size() const { return 8; }
  void initial_state(const Disturbance& d, std::span<double> x) const;
  void state_scales(double displacement_m, std::span<double> scales) const;
  double highest_frequency_hz() const;
  bool regenerates(Rotor) const { return true; }
  double nominal_speed_rpm(Rotor rotor) const;
  std::optional<std::size_t> angle_state(Rotor rotor) const { return rotor == Rotor::work ? 6 : 7; }
  double speed_rpm_from_state(Rotor rotor, std::span<const double> state) const;
  double displacement_m(std::span<const double> state) const { return state[0]; }
  std::vector<std::string> diagnostics() const;

  template <class S>
  void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const {
    constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel), work = static_cast<std::size_t>(Rotor::work);
    using std::max;
    const S interference = in.state[0] - in.previous_surface_m[work] - in.previous_surface_m[wheel];
    const S delta_w = interference / (1.0 + lambda_ratio_);
    const S delta_g = delta_w * lambda_ratio_;
    const S work_rpm = speed_rpm(Rotor::work, in.state), wheel_rpm = speed_rpm(Rotor::wheel, in.state);
    S force = p_.removal_coefficient_n_per_m2 * p_.grinding_width_m * delta_w;
    if constexpr (std::is_same_v<S, double>) note_wheel_speed(in.t_s, wheel_rpm);
    if (value_of(wheel_rpm) <= stall_fraction * p_.wheel_speed_rpm) {
      force = S(0.0);  // F ~ v_w / v_g: singular as the wheel stops. No grinding without wheel speed.
    } else {
      force *= max(work_rpm, S(0.0)) / p_.work_speed_rpm * p_.wheel_speed_rpm / wheel_rpm;
    }
    out.penetration_m = interference;
    out.normal_force_n = force;
    out.tangential_force_n = force * sin_alpha_;
    out.depth_of_cut_m = delta_w;
    out.removed_m[work] = delta_w;
    out.removed_m[wheel] = delta_g;
  }

  template <class S>
  void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& c, std::span<S> dx) const {
    using std::max;
    const auto& s = in.state;
    const S f = c.normal_force_n;
    dx[0] = s[1];
    dx[1] = (-f * cos_alpha_ - p_.damping_n_s_per_m * (s[1] - in.infeed_rate_m_per_s) -
             p_.stiffness_n_per_m * (s[0] - in.infeed_m)) / p_.mass_kg;
    dx[2] = s[3];
    dx[3] = (-f * p_.work_radius_m * sin_alpha_ - p_.work_torsional_damping_n_m_s * s[3] -
             p_.work_torsional_stiffness_n_m * s[2]) / p_.work_inertia_kg_m2;
    dx[4] = s[5];
    dx[5] = (-f * p_.wheel_radius_m * sin_alpha_ - p_.wheel_torsional_damping_n_m_s * s[5] -
             p_.wheel_torsional_stiffness_n_m * s[4]) / p_.wheel_inertia_kg_m2;
    // Rotation angles: nominal speed plus torsional velocity; never backwards (a reversing body
    // would regrind its surface the wrong way: documented limit).
    dx[6] = max(S(two_pi * p_.work_speed_rpm / 60.0) + s[3], S(0.0));
    dx[7] = max(S(two_pi * p_.wheel_speed_rpm / 60.0) + s[5], S(0.0));
  }

  static constexpr double stall_fraction = 0.01;  // below 1 % of the nominal wheel speed: force law off
  static constexpr double two_pi = 2.0 * std::numbers::pi;
  static constexpr double rpm_per_rad_s = 60.0 / two_pi;

 private:
  template <class S>
  S speed_rpm(Rotor rotor, std::span<const S> s) const {
    return rotor == Rotor::wheel ? p_.wheel_speed_rpm + s[5] * rpm_per_rad_s : p_.work_speed_rpm + s[3] * rpm_per_rad_s;
  }
  void note_wheel_speed(double t_s, double wheel_rpm) const;

  TorsionalCouplingParameters p_;
  double lambda_ratio_;  // lambda_w / lambda_g
  double cos_alpha_, sin_alpha_;
  // Diagnostics of one simulation (each time_domain() copies the equations).
  mutable double stalled_since_s_ = -1.0;  // first time the wheel speed fell below 1 % (diagnostic)
  mutable double lowest_wheel_rpm_;
};

// The dynamics engine's view of G5 (S = double).
using TorsionalCouplingTimeDomain = EquationsTimeDomain<TorsionalCouplingEquations>;

class TorsionalCoupling final : public DerivedModel<TorsionalCouplingEquations>,
                                public ProcessConditionsModel {
 public:
  explicit TorsionalCoupling(const ParamValues& values);
  explicit TorsionalCoupling(const TorsionalCouplingParameters& p)
      : DerivedModel(TorsionalCouplingEquations(p)), parameters_(p) {}

  static PluginInfo info();

  // Process conditions (feed_risk, suppression_map): the speeds, the width b and the radii are
  // G5's own parameters and take the conditions' values (scaled by conditions/reference where the
  // reference gives them); lambda_w follows G4's removal law Kv/(1+Kv) like G1's kw
  // (shared/plunge_dynamics/process_scaling.hpp), and lambda_g = lambda_w Gr Rg0 n_g/(Rw0 n_w)
  // follows through the speeds and radii. G5 has no separate contact or wear stiffness, so S1's
  // depth-of-cut law (thickness exponent) has nothing to rescale.
  const ProcessConditionsModel* process_conditions() const override { return this; }
  ProcessConditions nominal_conditions() const override;
  Json parameters_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                     const ProcessScaling& scaling) const override;

 private:
  TorsionalCouplingParameters parameters_;
};

}  // namespace chatterlab
