#pragma once
// MODELS.md G4 (book eqs 2-71..2-78): grinding-process stiffnesses from a constant specific
// grinding energy, and the critical work speed of geometric filtering. Plain functions (units in
// the names); docs/models/closed_forms.md (G4). Users: the process-condition scaling of the plunge
// models (process_scaling.hpp: kw ~ Kv/(1+Kv), kg ~ 1/(1+Kv), kd ~ ks sqrt(de u0)/vw) and the G4
// indicators of plunge_with_penetration_damping.
//
// Constant specific energy psi (2-72..2-75): the tangential force per width is
//   Ft = psi Bw { (u0 + du/2) Kv/(1 + Kv) + sqrt(de u0)/(vg (1 + Kv)) du/dt },  Kv = vw/vg,
// a part proportional to the depth of cut (static grinding stiffness ks = psi Bw Kv/(1 + Kv),
// 2-76; it sees workpiece regeneration) and a part proportional to the penetration rate (dynamic
// coefficient kd, 2-77/78; damping-like, it does not regenerate). Plane grinding: de = 2 Rg;
// cylindrical plunge: de = dw dg/(dw +/- dg) (+ external, - internal).
namespace chatterlab::grinding_process {

enum class Contact { external, internal };

// Surface speed v = pi d n / 60 of a body of diameter d [mm] turning at n [rpm], in m/s.
double surface_speed_m_per_s(double diameter_mm, double speed_rpm);

// de = dw dg/(dw + dg) (external) or dw dg/(dw - dg) (internal, needs dw > dg) [m].
// Throws std::invalid_argument for non-positive diameters or an internal wheel not smaller than the bore.
double equivalent_diameter_m(double work_diameter_m, double wheel_diameter_m, Contact contact);

// Speed ratio Kv = vw/vg.
double speed_ratio(double work_speed_m_per_s, double wheel_speed_m_per_s);

// The speed dependence of the static grinding stiffness, ks = psi Bw Kv/(1 + Kv) (2-76): Kv/(1 + Kv).
double removal_speed_factor(double speed_ratio);
// The same force over a wheel surface passing vg/vw times faster wears it with the stiffness
// kg = G ks vg/vw = G psi Bw/(1 + Kv) (grinding ratio G): 1/(1 + Kv).
double wear_speed_factor(double speed_ratio);

// kd = ks sqrt(de u0)/vw [N s/m] (2-77 with 2 Rg -> de, 2-78); u0 depth of cut [m].
double dynamic_grinding_coefficient_n_s_per_m(double static_stiffness_n_per_m,
                                              double equivalent_diameter_m, double depth_of_cut_m,
                                              double work_speed_m_per_s);

// Geometric contact length sqrt(de u0) [m] (the chord the wheel sweeps; the factor in kd).
double contact_length_m(double equivalent_diameter_m, double depth_of_cut_m);

// Critical work speed of geometric filtering (2-71, restated): a wave of amplitude y and frequency
// f laid on the work at speed vw has wavelength vw/f; the wheel (relative radius Re = Rw Rg/(Rw +
// Rg)) reaches its troughs only while the wave's curvature y (2 pi f/vw)^2 <= 1/Re, i.e. for
// vw >= v_c = 2 pi f sqrt(y Re). Below v_c the wheel cannot copy the vibration fully.
double critical_work_speed_m_per_s(double frequency_hz, double amplitude_m, double work_radius_m,
                                   double wheel_radius_m);

}  // namespace chatterlab::grinding_process
