#include "shared/plunge_dynamics/grinding_process.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace chatterlab::grinding_process {

double surface_speed_m_per_s(double diameter_mm, double speed_rpm) {
  return std::numbers::pi * diameter_mm * 1e-3 * speed_rpm / 60.0;
}

double equivalent_diameter_m(double dw, double dg, Contact contact) {
  if (!(dw > 0.0 && dg > 0.0)) throw std::invalid_argument("equivalent_diameter_m: diameters must be > 0");
  if (contact == Contact::external) return dw * dg / (dw + dg);
  if (!(dw > dg))
    throw std::invalid_argument("equivalent_diameter_m: internal grinding needs a wheel smaller than the bore");
  return dw * dg / (dw - dg);
}

double speed_ratio(double vw, double vg) { return vw / vg; }

double removal_speed_factor(double kv) { return kv / (1.0 + kv); }

double wear_speed_factor(double kv) { return 1.0 / (1.0 + kv); }

double contact_length_m(double de, double u0) { return std::sqrt(de * u0); }

double dynamic_grinding_coefficient_n_s_per_m(double ks, double de, double u0, double vw) {
  return ks * contact_length_m(de, u0) / vw;
}

double critical_work_speed_m_per_s(double f, double y, double rw, double rg) {
  const double relative_radius = rw * rg / (rw + rg);
  return 2.0 * std::numbers::pi * f * std::sqrt(y * relative_radius);
}

}  // namespace chatterlab::grinding_process
