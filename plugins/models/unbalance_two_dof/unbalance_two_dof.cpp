#include "models/unbalance_two_dof/unbalance_two_dof.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/param_table.hpp"

namespace chatterlab {

void UnbalanceTwoDofTimeDomain::initial_state(const Disturbance& d, std::span<double> x) const {
  x[0] = d.displacement_m;
  x[1] = d.velocity_m_per_s;
  x[2] = 0.0;
  x[3] = 0.0;
}

void UnbalanceTwoDofTimeDomain::state_scales(double displacement_m, std::span<double> scales) const {
  const double w = 2.0 * std::numbers::pi * highest_frequency_hz();
  // The forced amplitude U w^2 / k sets the scale when it exceeds the disturbance.
  const double w_g = 2.0 * std::numbers::pi * p_.wheel_speed_rpm / 60.0;
  const double d = std::max(displacement_m, p_.unbalance_kg_m * w_g * w_g /
                                                (unbalance::coupling_stiffness_n_per_m(p_) + p_.wheel_support_stiffness_n_per_m));
  scales[0] = scales[2] = d;
  scales[1] = scales[3] = d * w;
}

double UnbalanceTwoDofTimeDomain::highest_frequency_hz() const {
  const double k = unbalance::coupling_stiffness_n_per_m(p_);
  const double w1 = std::sqrt((k + p_.wheel_support_stiffness_n_per_m) / p_.wheel_mass_kg);
  const double w2 = std::sqrt((k + p_.work_support_stiffness_n_per_m) / p_.work_mass_kg);
  // The coupled frequencies lie below sqrt(w1^2 + w2^2); the forcing is at the wheel speed.
  return 1.5 * std::max(std::hypot(w1, w2) / (2.0 * std::numbers::pi), p_.wheel_speed_rpm / 60.0);
}

double UnbalanceTwoDofTimeDomain::nominal_speed_rpm(Rotor rotor) const {
  return rotor == Rotor::wheel ? p_.wheel_speed_rpm : p_.work_speed_rpm;
}

void UnbalanceTwoDofTimeDomain::contact(const ContactInput& in, ContactOutput& out) const {
  constexpr auto work = static_cast<std::size_t>(Rotor::work);
  const double relative = in.state[0] + in.state[2];
  out.penetration_m = 1.0;  // linear model: always in contact
  out.normal_force_n = unbalance::coupling_stiffness_n_per_m(p_) * relative;  // force through the contact spring
  out.depth_of_cut_m = relative;
  // The work surface keeps a copy of the relative motion: increment over one revolution ago.
  out.removed_m[work] = relative - in.previous_surface_m[work];
}

double UnbalanceTwoDofTimeDomain::linear_forcing(const ContactInput& in) const {
  constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel);
  const double w = 2.0 * std::numbers::pi * in.speed_rpm[wheel] / 60.0;
  return p_.unbalance_kg_m * w * w * std::cos(in.angle_rad[wheel]);
}

std::optional<LinearForm> UnbalanceTwoDofTimeDomain::linear_form(double /*t_s*/) const {
  const double k = unbalance::coupling_stiffness_n_per_m(p_);
  const double m1 = p_.wheel_mass_kg, m2 = p_.work_mass_kg;
  LinearForm form;
  form.contact_matrix = {0.0, 1.0, 0.0, 0.0,
                         -(k + p_.wheel_support_stiffness_n_per_m) / m1, -p_.wheel_damping_n_s_per_m / m1, -k / m1, 0.0,
                         0.0, 0.0, 0.0, 1.0,
                         -k / m2, 0.0, -(k + p_.work_support_stiffness_n_per_m) / m2, -p_.work_damping_n_s_per_m / m2};
  form.contact_input = {0.0, 1.0 / m1, 0.0, 0.0};
  form.free_matrix = form.contact_matrix;  // contact is never lost (penetration 1)
  form.free_input = form.contact_input;
  return form;
}

void UnbalanceTwoDofTimeDomain::derivatives(const ContactInput& in, const ContactOutput&,
                                            std::span<double> dx) const {
  const double force = linear_forcing(in);
  const double k = unbalance::coupling_stiffness_n_per_m(p_);
  const double x1 = in.state[0], v1 = in.state[1], x2 = in.state[2], v2 = in.state[3];
  dx[0] = v1;
  dx[1] = (force - p_.wheel_damping_n_s_per_m * v1 - (k + p_.wheel_support_stiffness_n_per_m) * x1 - k * x2) / p_.wheel_mass_kg;
  dx[2] = v2;
  dx[3] = (-p_.work_damping_n_s_per_m * v2 - (k + p_.work_support_stiffness_n_per_m) * x2 - k * x1) / p_.work_mass_kg;
}

namespace {

const ParamTable<UnbalanceTwoDofParameters>& parameters_table() {
  using P = UnbalanceTwoDofParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::wheel_mass_kg, "mass_1_kg", "kg", "wheel-side mass m1").positive().required();
    t.add(&P::wheel_damping_n_s_per_m, "damping_1_n_s_per_m", "N s/m", "wheel-side damping c1")
        .non_negative()
        .required();
    t.add(&P::wheel_support_stiffness_n_per_m, "stiffness_1_n_per_m", "N/m", "wheel-side support stiffness k1")
        .positive()
        .required();
    t.add(&P::work_mass_kg, "mass_2_kg", "kg", "work-side mass m2").positive().required();
    t.add(&P::work_damping_n_s_per_m, "damping_2_n_s_per_m", "N s/m", "work-side damping c2")
        .non_negative()
        .required();
    t.add(&P::work_support_stiffness_n_per_m, "stiffness_2_n_per_m", "N/m", "work-side support stiffness k2")
        .positive()
        .required();
    t.add(&P::contact_stiffness_n_per_m, "contact_stiffness_n_per_m", "N/m", "contact stiffness kc")
        .positive()
        .required();
    t.add(&P::grinding_stiffness_n_per_m, "wheel_wear_stiffness_n_per_m", "N/m",
          "wheel stiffness kg; k = kc kg/(kc + kg)")
        .positive()
        .required();
    t.add(&P::unbalance_kg_m, "unbalance_kg_m", "kg m", "wheel unbalance U (mass times eccentricity)")
        .non_negative()
        .required();
    t.add(&P::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed n_g (forcing frequency w = 2 pi n_g/60)")
        .positive()
        .required();
    t.add(&P::work_speed_rpm, "work_speed_rpm", "rpm", "work speed n_w (lobes Z = n_g/n_w)").positive().required();
    return t;
  }();
  return table;
}

}  // namespace

UnbalanceTwoDof::UnbalanceTwoDof(const ParamValues& values) : p_(parameters_table().read(values)) {}

PluginInfo UnbalanceTwoDof::info() {
  PluginInfo info;
  info.name = "unbalance_two_dof";
  info.description = "two-DOF wheel/work system forced by wheel unbalance U w^2 cos wt (G6, eqs "
                     "3-1..3-6): forced response, Z = n_g/n_w lobes on the work";
  info.params = parameters_table().specs();
  info.thread_safety = ThreadSafety::shareable;
  info.models_md_ids = "G6";
  info.example_params = Json::parse(R"({
      "mass_1_kg": 60.0, "damping_1_n_s_per_m": 6000.0, "stiffness_1_n_per_m": 5.0e7,
      "mass_2_kg": 20.0, "damping_2_n_s_per_m": 3000.0, "stiffness_2_n_per_m": 3.0e7,
      "contact_stiffness_n_per_m": 1.0e8, "wheel_wear_stiffness_n_per_m": 1.0e9,
      "unbalance_kg_m": 1.0e-4, "wheel_speed_rpm": 1450.0, "work_speed_rpm": 55.0 })");
  return info;
}

CHATTERLAB_REGISTER_MODEL(UnbalanceTwoDof);

}  // namespace chatterlab
