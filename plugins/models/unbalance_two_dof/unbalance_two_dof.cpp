#include "models/unbalance_two_dof/unbalance_two_dof.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/param_table.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

void UnbalanceTwoDofEquations::initial_state(const Disturbance& d, std::span<double> x) const {
  x[0] = d.displacement_m;
  x[1] = d.velocity_m_per_s;
  x[2] = 0.0;
  x[3] = 0.0;
}

void UnbalanceTwoDofEquations::state_scales(double displacement_m, std::span<double> scales) const {
  const double w = 2.0 * std::numbers::pi * highest_frequency_hz();
  // The forced amplitude U w^2 / k sets the scale when it exceeds the disturbance.
  const double w_g = 2.0 * std::numbers::pi * p.wheel_speed_rpm / 60.0;
  const double d = std::max(displacement_m, p.unbalance_kg_m * w_g * w_g /
                                                (unbalance::coupling_stiffness_n_per_m(p) + p.wheel_support_stiffness_n_per_m));
  scales[0] = scales[2] = d;
  scales[1] = scales[3] = d * w;
}

double UnbalanceTwoDofEquations::highest_frequency_hz() const {
  const double k = unbalance::coupling_stiffness_n_per_m(p);
  const double w1 = std::sqrt((k + p.wheel_support_stiffness_n_per_m) / p.wheel_mass_kg);
  const double w2 = std::sqrt((k + p.work_support_stiffness_n_per_m) / p.work_mass_kg);
  // The coupled frequencies lie below sqrt(w1^2 + w2^2); the forcing is at the wheel speed.
  return 1.5 * std::max(std::hypot(w1, w2) / (2.0 * std::numbers::pi), p.wheel_speed_rpm / 60.0);
}

std::optional<LinearForm> UnbalanceTwoDofEquations::linear_form(double /*t_s*/) const {
  const SurfaceLayout layout = derived_detail::layout_of(state_size(), false, true, p.wheel_speed_rpm, p.work_speed_rpm);
  const JacobianMatrix jacobian = derived_detail::jacobian(*this, layout, {});
  const std::size_t n = state_size();
  LinearForm form;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) form.contact_matrix.push_back(jacobian(i, j));
  form.contact_input = {0.0, 1.0 / p.wheel_mass_kg, 0.0, 0.0};  // F acts on the wheel side (checked by the engine)
  form.free_matrix = form.contact_matrix;  // contact is never lost (penetration 1)
  form.free_input = form.contact_input;
  return form;
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

UnbalanceTwoDof::UnbalanceTwoDof(const ParamValues& values)
    : DerivedModel(UnbalanceTwoDofEquations(parameters_table().read(values))) {}

std::vector<ClosedFormIndicatorSpec> UnbalanceTwoDof::indicator_specs() const {
  using P = ClosedFormIndicatorSpec::Predicts;
  return {{"forced_amplitude_m",
           "G6 closed form, damped 2 x 2 solve: steady amplitude |X1 + X2| of the relative motion at the wheel speed",
           false, P::steady_amplitude},
          {"undamped_relative_amplitude_m",
           "G6 eq 3-3 (corrected): undamped amplitude of the surface motion (x1 + x2)/(1 + kg/kc), signed", false,
           P::nothing},
          {"natural_frequency_1_hz", "G6 eq 3-4 (corrected): lower undamped natural frequency", false, P::nothing},
          {"natural_frequency_2_hz", "G6 eq 3-4 (corrected): upper undamped natural frequency", false, P::nothing},
          {"lobes_per_work_revolution", "G6 eq 3-6: Z = n_g/n_w", false, P::nothing}};
}

std::vector<Json> UnbalanceTwoDof::indicator_values() const {
  const UnbalanceTwoDofParameters& p = parameters();
  const unbalance::SteadyState steady = unbalance::unbalance_response(p);
  const unbalance::NaturalFrequencies n = unbalance::natural_frequencies(p);
  // Infinite at an undamped resonance: "does not apply" (null), never inf in a table.
  const auto finite = [](double v) { return std::isfinite(v) ? Json(v) : Json(); };
  return {finite(std::abs(steady.wheel_m + steady.work_m)),
          finite(unbalance::undamped_relative_amplitude_m(p, unbalance::forcing_frequency_rad_s(p))),
          n.lower_rad_s / (2.0 * std::numbers::pi), n.upper_rad_s / (2.0 * std::numbers::pi),
          unbalance::lobes_per_revolution(p)};
}

PluginInfo UnbalanceTwoDof::info() {
  return plugin_info("unbalance_two_dof", "G6",
                     parameters_table().specs(),
                     Json::parse(R"({
                         "mass_1_kg": 60.0, "damping_1_n_s_per_m": 6000.0, "stiffness_1_n_per_m": 5.0e7,
                         "mass_2_kg": 20.0, "damping_2_n_s_per_m": 3000.0, "stiffness_2_n_per_m": 3.0e7,
                         "contact_stiffness_n_per_m": 1.0e8, "wheel_wear_stiffness_n_per_m": 1.0e9,
                         "unbalance_kg_m": 1.0e-4, "wheel_speed_rpm": 1450.0, "work_speed_rpm": 55.0 })"),
                     "two-DOF wheel/work system forced by wheel unbalance U w^2 cos wt (G6, eqs "
                     "3-1..3-6): forced response, Z = n_g/n_w lobes on the work",
                     ThreadSafety::shareable);
}

CHATTERLAB_REGISTER_MODEL(UnbalanceTwoDof);

}  // namespace chatterlab
