#include "shared/plunge_dynamics/process_scaling.hpp"

#include "shared/plunge_dynamics/grinding_process.hpp"

namespace chatterlab::plunge_dynamics {

namespace gp = grinding_process;

namespace {

bool given(double reference, double conditions) { return reference > 0.0 && conditions > 0.0; }

// A speed of the conditions or of the reference, the model's own where it is not given.
double or_own(double given_rpm, double own_rpm) { return given_rpm > 0.0 ? given_rpm : own_rpm; }

// Kv = v_w / v_s (G4).
double speed_ratio(const ProcessConditions& c) {
  return gp::speed_ratio(gp::surface_speed_m_per_s(2.0 * c.work_radius_mm, c.work_speed_rpm),
                         gp::surface_speed_m_per_s(c.wheel_diameter_mm, c.wheel_speed_rpm));
}

// The conditions with the model's own speeds where they give none.
ProcessConditions completed(ProcessConditions c, const PlungeRegenerativeParameters& own) {
  c.wheel_speed_rpm = or_own(c.wheel_speed_rpm, own.wheel_speed_rpm);
  c.work_speed_rpm = or_own(c.work_speed_rpm, own.work_speed_rpm);
  return c;
}

}  // namespace

ProcessConditions nominal_conditions(const PlungeRegenerativeParameters& p) {
  ProcessConditions c;
  c.wheel_speed_rpm = p.wheel_speed_rpm;
  c.work_speed_rpm = p.work_speed_rpm;
  return c;
}

ProcessFactors process_factors(const ProcessConditions& ref, const ProcessConditions& at,
                               const ProcessScaling& scaling) {
  ProcessFactors f;
  if (given(ref.contact_width_mm, at.contact_width_mm)) f.width = at.contact_width_mm / ref.contact_width_mm;
  if (scaling.speed_dependent_stiffness && given(ref.work_radius_mm, at.work_radius_mm) &&
      given(ref.wheel_diameter_mm, at.wheel_diameter_mm)) {
    const double kv = speed_ratio(at), kv_ref = speed_ratio(ref);
    f.removal = gp::removal_speed_factor(kv) / gp::removal_speed_factor(kv_ref);
    f.wear = gp::wear_speed_factor(kv) / gp::wear_speed_factor(kv_ref);
  }
  if (scaling.thickness_exponent != 0.0) {
    const double relative_change = at.depth_of_cut_ratio / ref.depth_of_cut_ratio - 1.0;
    f.thickness = 1.0 - 0.5 * scaling.thickness_exponent * relative_change;
  }
  return f;
}

PlungeRegenerativeParameters parameters_at(const PlungeRegenerativeParameters& own,
                                           const ProcessConditions& reference_given,
                                           const ProcessConditions& conditions_given,
                                           const ProcessScaling& scaling) {
  const ProcessConditions at = completed(conditions_given, own);
  const ProcessFactors f = process_factors(completed(reference_given, own), at, scaling);
  PlungeRegenerativeParameters p = own;
  p.wheel_speed_rpm = at.wheel_speed_rpm;
  p.work_speed_rpm = at.work_speed_rpm;
  p.contact_stiffness_n_per_m = own.contact_stiffness_n_per_m * f.width * f.thickness;
  p.work_removal_stiffness_n_per_m = own.work_removal_stiffness_n_per_m * f.width * f.removal;
  p.wheel_wear_stiffness_n_per_m = own.wheel_wear_stiffness_n_per_m * f.width * f.wear * f.thickness;
  return p;
}

double penetration_damping_factor(const PlungeRegenerativeParameters& own,
                                  const ProcessConditions& reference_given,
                                  const ProcessConditions& conditions_given,
                                  const ProcessScaling& scaling) {
  const ProcessConditions ref = completed(reference_given, own);
  const ProcessConditions at = completed(conditions_given, own);
  const double kw_ref = own.work_removal_stiffness_n_per_m;
  const double kw = parameters_at(own, reference_given, conditions_given, scaling).work_removal_stiffness_n_per_m;
  double de_ref = 1.0, de = 1.0;  // relative when not given
  if (given(ref.work_radius_mm, at.work_radius_mm) && given(ref.wheel_diameter_mm, at.wheel_diameter_mm)) {
    de_ref = gp::equivalent_diameter_m(2e-3 * ref.work_radius_mm, 1e-3 * ref.wheel_diameter_mm, gp::Contact::external);
    de = gp::equivalent_diameter_m(2e-3 * at.work_radius_mm, 1e-3 * at.wheel_diameter_mm, gp::Contact::external);
  }
  double vw_ref = ref.work_speed_rpm, vw = at.work_speed_rpm;  // relative: the same radius
  if (given(ref.work_radius_mm, at.work_radius_mm)) {
    vw_ref = gp::surface_speed_m_per_s(2.0 * ref.work_radius_mm, ref.work_speed_rpm);
    vw = gp::surface_speed_m_per_s(2.0 * at.work_radius_mm, at.work_speed_rpm);
  }
  return gp::dynamic_grinding_coefficient_n_s_per_m(kw, de, at.depth_of_cut_ratio, vw) /
         gp::dynamic_grinding_coefficient_n_s_per_m(kw_ref, de_ref, ref.depth_of_cut_ratio, vw_ref);
}

}  // namespace chatterlab::plunge_dynamics
