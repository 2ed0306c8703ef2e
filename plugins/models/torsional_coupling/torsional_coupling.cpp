#include "models/torsional_coupling/torsional_coupling.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/param_table.hpp"
#include "chatterlab/plugin_info.hpp"
#include "shared/plunge_dynamics/process_scaling.hpp"

namespace chatterlab {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}  // namespace

TorsionalCouplingEquations::TorsionalCouplingEquations(const TorsionalCouplingParameters& p)
    : p_(p),
      lambda_ratio_(p.work_radius_m * p.work_speed_rpm /
                    (p.grinding_ratio * p.wheel_radius_m * p.wheel_speed_rpm)),
      cos_alpha_(std::cos(p.force_angle_deg * std::numbers::pi / 180.0)),
      sin_alpha_(std::sin(p.force_angle_deg * std::numbers::pi / 180.0)),
      lowest_wheel_rpm_(p.wheel_speed_rpm) {}

void TorsionalCouplingEquations::initial_state(const Disturbance& d, std::span<double> x) const {
  std::fill(x.begin(), x.end(), 0.0);
  x[0] = d.displacement_m;
  x[1] = d.velocity_m_per_s;
}

void TorsionalCouplingEquations::state_scales(double displacement_m, std::span<double> s) const {
  const double w = kTwoPi * highest_frequency_hz();
  s[0] = displacement_m;
  s[1] = displacement_m * w;
  // Torsion angles ~ displacement over radius; rotation angles ~ 1 rad.
  s[2] = displacement_m / p_.work_radius_m;
  s[3] = s[2] * w;
  s[4] = displacement_m / p_.wheel_radius_m;
  s[5] = s[4] * w;
  s[6] = s[7] = 1.0;
}

double TorsionalCouplingEquations::highest_frequency_hz() const {
  const double contact = p_.removal_coefficient_n_per_m2 * p_.grinding_width_m / (1.0 + lambda_ratio_);
  const double transverse = std::sqrt((p_.stiffness_n_per_m + contact) / p_.mass_kg);
  const double work = std::sqrt((p_.work_torsional_stiffness_n_m + contact * p_.work_radius_m * p_.work_radius_m) /
                                p_.work_inertia_kg_m2);
  const double wheel = std::sqrt((p_.wheel_torsional_stiffness_n_m + contact * p_.wheel_radius_m * p_.wheel_radius_m) /
                                 p_.wheel_inertia_kg_m2);
  return 1.5 * std::max({transverse, work, wheel}) / kTwoPi;
}

double TorsionalCouplingEquations::nominal_speed_rpm(Rotor rotor) const {
  return rotor == Rotor::wheel ? p_.wheel_speed_rpm : p_.work_speed_rpm;
}

double TorsionalCouplingEquations::speed_rpm_from_state(Rotor rotor, std::span<const double> s) const {
  return speed_rpm(rotor, s);
}

void TorsionalCouplingEquations::note_wheel_speed(double t_s, double wheel_rpm) const {
  lowest_wheel_rpm_ = std::min(lowest_wheel_rpm_, wheel_rpm);
  if (wheel_rpm <= stall_fraction * p_.wheel_speed_rpm && stalled_since_s_ < 0.0) stalled_since_s_ = t_s;
}

std::vector<std::string> TorsionalCouplingEquations::diagnostics() const {
  std::vector<std::string> out;
  if (stalled_since_s_ >= 0.0)
    out.push_back(fmt::format("wheel speed fell below {} % of nominal ({:.4g} rpm) at t = {:.6g} s: the force "
                              "law (F ~ 1/v_g) is singular there, force set to zero while stalled; lowest "
                              "wheel speed {:.4g} rpm",
                              100.0 * stall_fraction, stall_fraction * p_.wheel_speed_rpm, stalled_since_s_,
                              lowest_wheel_rpm_));
  return out;
}

namespace {

const ParamTable<TorsionalCouplingParameters>& parameters_table() {
  using P = TorsionalCouplingParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::mass_kg, "mass_kg", "kg", "transverse (wheel-head) mass m").positive().required();
    t.add(&P::damping_n_s_per_m, "damping_n_s_per_m", "N s/m", "transverse damping c")
        .positive()
        .required();
    t.add(&P::stiffness_n_per_m, "stiffness_n_per_m", "N/m", "transverse stiffness k")
        .positive()
        .required();
    t.add(&P::work_inertia_kg_m2, "work_inertia_kg_m2", "kg m^2", "workpiece + drive inertia Iw")
        .positive()
        .required();
    t.add(&P::work_torsional_damping_n_m_s, "work_torsional_damping_n_m_s", "N m s/rad",
          "workpiece torsional damping cw")
        .positive()
        .required();
    t.add(&P::work_torsional_stiffness_n_m, "work_torsional_stiffness_n_m", "N m/rad",
          "workpiece drive torsional stiffness kw")
        .positive()
        .required();
    t.add(&P::wheel_inertia_kg_m2, "wheel_inertia_kg_m2", "kg m^2", "wheel + spindle inertia Ig")
        .positive()
        .required();
    t.add(&P::wheel_torsional_damping_n_m_s, "wheel_torsional_damping_n_m_s", "N m s/rad",
          "wheel torsional damping cg")
        .positive()
        .required();
    t.add(&P::wheel_torsional_stiffness_n_m, "wheel_torsional_stiffness_n_m", "N m/rad",
          "wheel spindle torsional stiffness kg")
        .positive()
        .required();
    t.add(&P::work_radius_m, "work_radius_m", "m", "workpiece radius Rw0").positive().required();
    t.add(&P::wheel_radius_m, "wheel_radius_m", "m", "wheel radius Rg0").positive().required();
    t.add(&P::work_speed_rpm, "work_speed_rpm", "rpm", "nominal workpiece speed n_w")
        .positive()
        .required();
    t.add(&P::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "nominal wheel speed n_g")
        .positive()
        .required();
    t.add(&P::grinding_width_m, "grinding_width_m", "m", "grinding width b").positive().required();
    t.add(&P::removal_coefficient_n_per_m2, "removal_coefficient_n_per_m2", "N/m^2",
          "lambda_w: force per width per work depth of cut")
        .positive()
        .required();
    t.add(&P::grinding_ratio, "grinding_ratio", "1",
          "grinding ratio Gr (work volume / wheel volume removed)")
        .positive()
        .required();
    t.add(&P::force_angle_deg, "force_angle_deg", "deg",
          "angle alpha of the grinding force from the normal (torque arm: sin alpha)")
        .non_negative()
        .below(90.0)
        .required();
    return t;
  }();
  return table;
}

}  // namespace

TorsionalCoupling::TorsionalCoupling(const ParamValues& values)
    : TorsionalCoupling(parameters_table().read(values)) {}

ProcessConditions TorsionalCoupling::nominal_conditions() const {
  ProcessConditions c;
  c.wheel_speed_rpm = parameters_.wheel_speed_rpm;
  c.work_speed_rpm = parameters_.work_speed_rpm;
  c.contact_width_mm = 1e3 * parameters_.grinding_width_m;
  c.work_radius_mm = 1e3 * parameters_.work_radius_m;
  c.wheel_diameter_mm = 2e3 * parameters_.wheel_radius_m;
  return c;
}

Json TorsionalCoupling::parameters_at(const ProcessConditions& reference_given,
                                      const ProcessConditions& conditions_given,
                                      const ProcessScaling& scaling) const {
  // A condition not given (0) is the model's own, in the reference and in the conditions.
  const ProcessConditions own = nominal_conditions();
  const auto completed = [&](ProcessConditions c) {
    for (auto field : {&ProcessConditions::wheel_speed_rpm, &ProcessConditions::work_speed_rpm,
                       &ProcessConditions::contact_width_mm, &ProcessConditions::work_radius_mm,
                       &ProcessConditions::wheel_diameter_mm})
      if (!(c.*field > 0.0)) c.*field = own.*field;
    return c;
  };
  const ProcessConditions ref = completed(reference_given), at = completed(conditions_given);
  const plunge_dynamics::ProcessFactors f = plunge_dynamics::process_factors(ref, at, scaling);
  TorsionalCouplingParameters p = parameters_;
  p.wheel_speed_rpm = at.wheel_speed_rpm;
  p.work_speed_rpm = at.work_speed_rpm;
  p.grinding_width_m = parameters_.grinding_width_m * f.width;
  p.work_radius_m = parameters_.work_radius_m * at.work_radius_mm / ref.work_radius_mm;
  p.wheel_radius_m = parameters_.wheel_radius_m * at.wheel_diameter_mm / ref.wheel_diameter_mm;
  p.removal_coefficient_n_per_m2 = parameters_.removal_coefficient_n_per_m2 * f.removal;
  return parameters_table().write(p);
}

PluginInfo TorsionalCoupling::info() {
  return plugin_info("torsional_coupling", "G5",
                     parameters_table().specs(),
                     Json::parse(R"({
                         "mass_kg": 50.0, "damping_n_s_per_m": 8000.0, "stiffness_n_per_m": 5.0e7,
                         "work_inertia_kg_m2": 0.05, "work_torsional_damping_n_m_s": 2.0, "work_torsional_stiffness_n_m": 2.0e4,
                         "wheel_inertia_kg_m2": 0.3, "wheel_torsional_damping_n_m_s": 5.0, "wheel_torsional_stiffness_n_m": 5.0e4,
                         "work_radius_m": 0.05, "wheel_radius_m": 0.2, "work_speed_rpm": 55.0, "wheel_speed_rpm": 1450.0,
                         "grinding_width_m": 0.035, "removal_coefficient_n_per_m2": 1.5e9, "grinding_ratio": 30.0,
                         "force_angle_deg": 20.0 })"),
                     "transverse, workpiece-torsion and wheel-torsion modes coupled by a "
                     "speed-dependent grinding force (G5, eqs 2-79..2-87)",
                     ThreadSafety::shareable);  // time-domain instances are per simulation
}

CHATTERLAB_REGISTER_MODEL(TorsionalCoupling);

}  // namespace chatterlab
