#pragma once
// A grinding model written once (ARCHITECTURE.md "Model"; docs/tutorial_model.md walks through
// one). The author writes the physics a single time, as templates over the scalar type:
//
//   struct MyEquations {
//     std::size_t state_size() const;
//     bool regenerates(Rotor rotor) const;                  // which surfaces are remembered
//     double nominal_speed_rpm(Rotor rotor) const;
//     template <class S> void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const;
//     template <class S> void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& c,
//                                         std::span<S> dx) const;
//     double displacement_m(std::span<const double> state) const;   // what a simulation reports
//   };
//
// and optionally initial_state(disturbance, x), state_scales(displacement_m, scales),
// highest_frequency_hz(), diagnostics(), angle_state(rotor) and speed_rpm_from_state(rotor, x)
// (the TimeDomainModel members, dynamics.hpp; angles as states: G5), and linear_form(t) with
// linear_forcing(ContactInputOf<double>) for the fixed-step engine's exact propagation of a model
// that is linear between contact events (dynamics.hpp, LinearForm; G6). From that
// one definition the framework derives
//   - the time-domain form the dynamics engine integrates (EquationsTimeDomain: S = double),
//   - the Jacobian at rest by forward-mode automatic differentiation (S = Dual, dual.hpp),
//   - the linear delay-differential-algebraic system and its certified characteristic function
//     (derived_characteristic, linearised_model.hpp), and Floquet multipliers when the speeds
//     vary periodically (floquet.hpp).
// This header needs no linear-algebra library (plugins built against the SDK include it as is).
// Equations given as a general delay system f(x(t), x(t - tau_1), ...) instead: delay_equations.hpp.
// A plugin class derives from DerivedModel<MyEquations>; a hand-written characteristic function
// may override characteristic() as a fast path, and derived_characteristic() stays available to
// test it against.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "chatterlab/dual.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/linearised_model.hpp"
#include "chatterlab/model.hpp"

namespace chatterlab {

// TimeDomainModel's ContactInput over a scalar type: the state and the surfaces one revolution ago
// are S (the framework differentiates with respect to them); time, speeds, angles and the infeed
// are given by the process.
template <class S>
struct ContactInputOf {
  double t_s = 0.0;
  std::span<const S> state;
  double infeed_m = 0.0;
  double infeed_rate_m_per_s = 0.0;
  double speed_rpm[rotor_count] = {0.0, 0.0};
  double angle_rad[rotor_count] = {0.0, 0.0};
  S previous_surface_m[rotor_count] = {S(0.0), S(0.0)};
};

// TimeDomainModel's ContactOutput over a scalar type (same meaning, dynamics.hpp).
template <class S>
struct ContactOutputOf {
  S penetration_m = S(0.0);
  S normal_force_n = S(0.0);
  S tangential_force_n = S(0.0);
  S depth_of_cut_m = S(0.0);
  S removed_m[rotor_count] = {S(0.0), S(0.0)};
};

template <class E>
concept GrindingEquations = requires(const E& e, Rotor rotor, std::span<const double> state,
                                     const ContactInputOf<double>& in, ContactOutputOf<double>& out,
                                     std::span<double> dx, const ContactInputOf<Dual>& din,
                                     ContactOutputOf<Dual>& dout, std::span<Dual> ddx) {
  { e.state_size() } -> std::convertible_to<std::size_t>;
  { e.regenerates(rotor) } -> std::convertible_to<bool>;
  { e.nominal_speed_rpm(rotor) } -> std::convertible_to<double>;
  { e.displacement_m(state) } -> std::convertible_to<double>;
  e.contact(in, out);
  e.derivatives(in, std::as_const(out), dx);
  e.contact(din, dout);
  e.derivatives(din, std::as_const(dout), ddx);
};

namespace derived_detail {

inline SurfaceLayout layout_of(std::size_t states, bool wheel, bool work, double wheel_rpm, double work_rpm) {
  SurfaceLayout layout;
  layout.states = states;
  if (wheel) layout.regenerated.push_back(Rotor::wheel);
  if (work) layout.regenerated.push_back(Rotor::work);
  layout.nominal_speed_rpm[static_cast<std::size_t>(Rotor::wheel)] = wheel_rpm;
  layout.nominal_speed_rpm[static_cast<std::size_t>(Rotor::work)] = work_rpm;
  return layout;
}

// The Jacobian of (dx, removed) with respect to (state, previous surfaces) at rest: one forward
// pass of the model's own functions per input, with that input seeded (derivative 1).
template <class E>
JacobianMatrix jacobian(const E& eqs, const SurfaceLayout& layout, const ProcessPoint& point) {
  const std::size_t n = layout.states, r = layout.regenerated.size(), size = n + r;
  JacobianMatrix out(size, size);
  std::vector<Dual> state(n), dx(n);
  for (std::size_t j = 0; j < size; ++j) {
    for (std::size_t i = 0; i < n; ++i) state[i] = Dual(0.0, i == j ? 1.0 : 0.0);
    ContactInputOf<Dual> in;
    in.t_s = point.t_s;
    in.state = std::span<const Dual>(state);
    in.infeed_m = point.infeed_m;
    in.infeed_rate_m_per_s = point.infeed_rate_m_per_s;
    for (std::size_t k = 0; k < rotor_count; ++k) {
      in.speed_rpm[k] = point.speed_rpm[k] > 0.0 ? point.speed_rpm[k] : layout.nominal_speed_rpm[k];
      in.angle_rad[k] = point.angle_rad[k];
    }
    for (std::size_t k = 0; k < r; ++k)
      in.previous_surface_m[static_cast<std::size_t>(layout.regenerated[k])] = Dual(0.0, n + k == j ? 1.0 : 0.0);
    ContactOutputOf<Dual> contact;
    eqs.contact(in, contact);
    std::fill(dx.begin(), dx.end(), Dual(0.0));
    eqs.derivatives(in, std::as_const(contact), std::span<Dual>(dx));
    for (std::size_t i = 0; i < n; ++i) out(i, j) = dx[i].derivative;
    for (std::size_t k = 0; k < r; ++k)
      out(n + k, j) = contact.removed_m[static_cast<std::size_t>(layout.regenerated[k])].derivative;
  }
  return out;
}

// Largest natural frequency of the undelayed state block [Hz] (0 if none).
double state_block_frequency_hz(const JacobianMatrix& jacobian, std::size_t states);

}  // namespace derived_detail

// The dynamics engine's view of equations written once (S = double throughout).
template <GrindingEquations E>
class EquationsTimeDomain final : public TimeDomainModel {
 public:
  explicit EquationsTimeDomain(E equations) : eqs_(std::move(equations)) {}

  std::size_t state_size() const override { return eqs_.state_size(); }
  void initial_state(const Disturbance& d, std::span<double> x) const override {
    if constexpr (requires { eqs_.initial_state(d, x); }) {
      eqs_.initial_state(d, x);
    } else {
      std::fill(x.begin(), x.end(), 0.0);
      x[0] = d.displacement_m;
      if (x.size() > 1) x[1] = d.velocity_m_per_s;
    }
  }
  void state_scales(double displacement_m, std::span<double> scales) const override {
    if constexpr (requires { eqs_.state_scales(displacement_m, scales); }) {
      eqs_.state_scales(displacement_m, scales);
    } else {
      // Displacement and velocity pairs (x, x') per mode: x ~ d, x' ~ d w.
      const double w = 2.0 * std::numbers::pi * highest_frequency_hz();
      for (std::size_t i = 0; i < scales.size(); ++i) scales[i] = i % 2 == 0 ? displacement_m : displacement_m * w;
    }
  }
  double highest_frequency_hz() const override {
    if constexpr (requires { eqs_.highest_frequency_hz(); }) {
      return eqs_.highest_frequency_hz();
    } else {
      // 1.5 x the largest natural frequency of the linearised structure in contact.
      const SurfaceLayout layout = layout_of_equations();
      const double f = derived_detail::state_block_frequency_hz(derived_detail::jacobian(eqs_, layout, {}), layout.states);
      return 1.5 * std::max(f, std::max(layout.nominal_speed_rpm[0], layout.nominal_speed_rpm[1]) / 60.0);
    }
  }
  bool regenerates(Rotor rotor) const override { return eqs_.regenerates(rotor); }
  double nominal_speed_rpm(Rotor rotor) const override { return eqs_.nominal_speed_rpm(rotor); }
  // G5: rotation angles that are states (optional members of the equations, dynamics.hpp).
  std::optional<std::size_t> angle_state(Rotor rotor) const override {
    if constexpr (requires { eqs_.angle_state(rotor); }) return eqs_.angle_state(rotor);
    else return std::nullopt;
  }
  double speed_rpm_from_state(Rotor rotor, std::span<const double> state) const override {
    if constexpr (requires { eqs_.speed_rpm_from_state(rotor, state); }) return eqs_.speed_rpm_from_state(rotor, state);
    else return 0.0;
  }
  void contact(const ContactInput& in, ContactOutput& out) const override {
    ContactOutputOf<double> c;
    eqs_.contact(convert(in), c);
    out.penetration_m = c.penetration_m;
    out.normal_force_n = c.normal_force_n;
    out.tangential_force_n = c.tangential_force_n;
    out.depth_of_cut_m = c.depth_of_cut_m;
    for (std::size_t k = 0; k < rotor_count; ++k) out.removed_m[k] = c.removed_m[k];
  }
  void derivatives(const ContactInput& in, const ContactOutput& contact, std::span<double> dx) const override {
    ContactOutputOf<double> c;
    c.penetration_m = contact.penetration_m;
    c.normal_force_n = contact.normal_force_n;
    c.tangential_force_n = contact.tangential_force_n;
    c.depth_of_cut_m = contact.depth_of_cut_m;
    for (std::size_t k = 0; k < rotor_count; ++k) c.removed_m[k] = contact.removed_m[k];
    eqs_.derivatives(convert(in), std::as_const(c), dx);
  }
  double displacement_m(std::span<const double> state) const override { return eqs_.displacement_m(state); }
  std::vector<std::string> diagnostics() const override {
    if constexpr (requires { eqs_.diagnostics(); }) return eqs_.diagnostics();
    else return {};
  }
  std::optional<LinearForm> linear_form(double t_s) const override {
    if constexpr (requires { eqs_.linear_form(t_s); }) return eqs_.linear_form(t_s);
    else return std::nullopt;
  }
  double linear_forcing(const ContactInput& in) const override {
    if constexpr (requires { eqs_.linear_forcing(convert(in)); }) return eqs_.linear_forcing(convert(in));
    else return 0.0;
  }

 private:
  static ContactInputOf<double> convert(const ContactInput& in) {
    ContactInputOf<double> c;
    c.t_s = in.t_s;
    c.state = in.state;
    c.infeed_m = in.infeed_m;
    c.infeed_rate_m_per_s = in.infeed_rate_m_per_s;
    for (std::size_t k = 0; k < rotor_count; ++k) {
      c.speed_rpm[k] = in.speed_rpm[k];
      c.angle_rad[k] = in.angle_rad[k];
      c.previous_surface_m[k] = in.previous_surface_m[k];
    }
    return c;
  }
  SurfaceLayout layout_of_equations() const {
    return derived_detail::layout_of(eqs_.state_size(), eqs_.regenerates(Rotor::wheel), eqs_.regenerates(Rotor::work),
                                     eqs_.nominal_speed_rpm(Rotor::wheel), eqs_.nominal_speed_rpm(Rotor::work));
  }
  E eqs_;
};

// A model plugin whose characteristic function, time-domain form and linearisation all come from
// one set of equations. Derive the plugin class from it (it stays abstract only in info(), the
// registration convention).
template <GrindingEquations E>
class DerivedModel : public Model, public LinearisedModel {
 public:
  explicit DerivedModel(E equations) : eqs_(std::move(equations)) {}

  const E& equations() const { return eqs_; }

  // The derived route: the certified characteristic function of linear_system().
  std::unique_ptr<CharacteristicFunction> derived_characteristic() const {
    return chatterlab::derived_characteristic(*this);
  }
  std::unique_ptr<CharacteristicFunction> characteristic() const override { return derived_characteristic(); }
  std::unique_ptr<TimeDomainModel> time_domain() const override {
    return std::make_unique<EquationsTimeDomain<E>>(eqs_);
  }
  std::optional<double> wheel_period_s() const override { return 60.0 / eqs_.nominal_speed_rpm(Rotor::wheel); }
  const LinearisedModel* linearised() const override { return this; }

  SurfaceLayout surface_layout() const override {
    return derived_detail::layout_of(eqs_.state_size(), eqs_.regenerates(Rotor::wheel), eqs_.regenerates(Rotor::work),
                                     eqs_.nominal_speed_rpm(Rotor::wheel), eqs_.nominal_speed_rpm(Rotor::work));
  }
  JacobianMatrix jacobian(const ProcessPoint& point) const override {
    return derived_detail::jacobian(eqs_, surface_layout(), point);
  }

 private:
  E eqs_;
};

}  // namespace chatterlab
