#include "models/plunge_regenerative/plunge_time_domain.hpp"

#include "chatterlab/derived_model.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>

namespace chatterlab {

void apply_growth_rate_settings(SimulationSettings& settings) {
  settings.integrator = TimeIntegrator::explicit_runge_kutta;
  settings.relative_tolerance = 1e-2;
  settings.max_steps_per_wave = 3.0;
  settings.samples_per_wave = 8.0;
}

namespace {

// The speeds of the G8 experiment (M1432: 1450 rpm wheel, 55 rpm work) that every known-answer
// machine here shares, with its stiffness chain kc, kg, kw [N/m]; both chains on, no modes yet.
PlungeRegenerativeParameters at_g8_speeds(double kc_n_per_m, double kg_n_per_m, double kw_n_per_m) {
  return {.wheel_speed_rpm = 1450.0,
          .work_speed_rpm = 55.0,
          .contact_stiffness_n_per_m = kc_n_per_m,
          .wheel_wear_stiffness_n_per_m = kg_n_per_m,
          .work_removal_stiffness_n_per_m = kw_n_per_m,
          .modes = {},
          .wheel_regeneration = true,
          .work_regeneration = true};
}

// MODELS.md G8's seven measured mode frequencies [Hz].
constexpr double kG8ModeFrequenciesHz[] = {67.56, 102.44, 184.08, 221.11, 255.01, 275.05, 305.60};

}  // namespace

PlungeRegenerativeParameters reference_g1_case() {
  PlungeRegenerativeParameters p = at_g8_speeds(1e8, 1e9, 2e8);
  p.modes = {{250.0, 0.05, 5e7}};
  return p;
}

PlungeRegenerativeParameters g8_assumed_modes(double contact_stiffness_n_per_m) {
  PlungeRegenerativeParameters p = at_g8_speeds(contact_stiffness_n_per_m, 5.0e9, 5.0e7);
  for (double f : kG8ModeFrequenciesHz) p.modes.push_back({f, 0.05, 2.0e8});
  return p;
}

PlungeRegenerativeParameters g8_grinder() {
  PlungeRegenerativeParameters p = at_g8_speeds(2e8, 6.3e10, 2e7);
  const double stiffness_n_per_m[] = {5.53e7, 1.27e8, 4.11e8, 5.93e8, 7.88e8, 9.17e8, 1.132e9};
  for (std::size_t i = 0; i < std::size(kG8ModeFrequenciesHz); ++i)
    p.modes.push_back({kG8ModeFrequenciesHz[i], 0.03, stiffness_n_per_m[i]});
  return p;
}

PlungeEquations::PlungeEquations(const PlungeRegenerativeParameters& p) {
  total_compliance_ = 0.0;
  for (const StructuralMode& m : p.modes) {
    modes_.push_back({2.0 * std::numbers::pi * m.frequency_hz, m.damping_ratio, 1.0 / m.stiffness_n_per_m});
    total_compliance_ += 1.0 / m.stiffness_n_per_m;
  }
  wheel_wear_compliance_ = p.wheel_regeneration ? 1.0 / p.wheel_wear_stiffness_n_per_m : 0.0;
  work_removal_compliance_ = p.work_regeneration ? 1.0 / p.work_removal_stiffness_n_per_m : 0.0;
  series_stiffness_ =
      1.0 / (1.0 / p.contact_stiffness_n_per_m + wheel_wear_compliance_ + work_removal_compliance_);
}

namespace {

// PlungeEquations in the shape derived_detail::jacobian differentiates (derived_model.hpp).
struct PlungeEquationsForJacobian {
  const PlungeEquations& eqs;
  template <class S>
  void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const { eqs.contact(in, out); }
  template <class S>
  void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& c, std::span<S> dx) const {
    eqs.derivatives(in, c, dx);
  }
};

}  // namespace

PlungeLinearisation::PlungeLinearisation(const PlungeRegenerativeParameters& p)
    : eqs_(p),
      layout_(derived_detail::layout_of(2 * p.modes.size(), p.wheel_regeneration, p.work_regeneration,
                                        p.wheel_speed_rpm, p.work_speed_rpm)) {}

JacobianMatrix PlungeLinearisation::jacobian(const ProcessPoint& point) const {
  return derived_detail::jacobian(PlungeEquationsForJacobian{eqs_}, layout_, point);
}

PlungeTimeDomain::PlungeTimeDomain(const PlungeRegenerativeParameters& p) : p_(p), eqs_(p) {}

SimulationSettings converged_reference_settings(SimulationSettings settings) {
  settings.integrator = TimeIntegrator::explicit_runge_kutta;
  settings.relative_tolerance = 1e-8;
  settings.samples_per_wave *= 4.0;
  settings.max_steps_per_wave *= 4.0;
  return settings;
}

void PlungeTimeDomain::initial_state(const Disturbance& d, std::span<double> x) const {
  // The disturbance in the static deflection shape: each mode takes its share of compliance.
  for (std::size_t i = 0; i < eqs_.modes().size(); ++i) {
    const double share = eqs_.modes()[i].compliance_m_per_n / eqs_.total_compliance_m_per_n();
    x[2 * i] = d.displacement_m * share;
    x[2 * i + 1] = d.velocity_m_per_s * share;
  }
}

void PlungeTimeDomain::state_scales(double displacement_m, std::span<double> scales) const {
  for (std::size_t i = 0; i < eqs_.modes().size(); ++i) {
    scales[2 * i] = displacement_m;
    scales[2 * i + 1] = displacement_m * eqs_.modes()[i].omega;
  }
}

double PlungeTimeDomain::highest_frequency_hz() const {
  // The contact stiffens each mode at most to sqrt(1 + kc/k_i) w_i; 1.5x leaves room for the
  // regenerative shift and the lattice roots around it.
  double highest = 0.0;
  for (const Mode& m : eqs_.modes())
    highest = std::max(highest, m.omega / (2.0 * std::numbers::pi) *
                                    std::sqrt(1.0 + p_.contact_stiffness_n_per_m * m.compliance_m_per_n));
  return 1.5 * highest;
}

bool PlungeTimeDomain::regenerates(Rotor rotor) const {
  return rotor == Rotor::wheel ? p_.wheel_regeneration : p_.work_regeneration;
}

double PlungeTimeDomain::nominal_speed_rpm(Rotor rotor) const {
  return rotor == Rotor::wheel ? p_.wheel_speed_rpm : p_.work_speed_rpm;
}

std::optional<LinearForm> PlungeTimeDomain::linear_form(double /*t_s*/) const {
  // State (q_i, q_i'): q_i' = v_i, v_i' = w_i^2 (F / k_i - q_i) - 2 zeta_i w_i v_i, with
  // F = k (f - sum_j q_j) in contact and 0 out of contact.
  const std::size_t n = state_size();
  LinearForm form;
  form.free_matrix.assign(n * n, 0.0);
  form.free_input.assign(n, 0.0);
  for (std::size_t i = 0; i < eqs_.modes().size(); ++i) {
    const Mode& m = eqs_.modes()[i];
    form.free_matrix[(2 * i) * n + 2 * i + 1] = 1.0;
    form.free_matrix[(2 * i + 1) * n + 2 * i] = -m.omega * m.omega;
    form.free_matrix[(2 * i + 1) * n + 2 * i + 1] = -2.0 * m.zeta * m.omega;
  }
  form.contact_matrix = form.free_matrix;
  form.contact_input.assign(n, 0.0);
  for (std::size_t i = 0; i < eqs_.modes().size(); ++i) {
    const Mode& m = eqs_.modes()[i];
    const double gain = m.omega * m.omega * m.compliance_m_per_n * eqs_.series_stiffness_n_per_m();
    for (std::size_t j = 0; j < eqs_.modes().size(); ++j) form.contact_matrix[(2 * i + 1) * n + 2 * j] -= gain;
    form.contact_input[2 * i + 1] = gain;
  }
  return form;
}

double PlungeTimeDomain::linear_forcing(const ContactInput& in) const {
  constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel);
  constexpr auto work = static_cast<std::size_t>(Rotor::work);
  return in.infeed_m - in.previous_surface_m[wheel] - in.previous_surface_m[work];
}

}  // namespace chatterlab
