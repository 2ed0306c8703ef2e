#pragma once
// MODELS.md G1 in the time domain (what the dynamics engine integrates):
//
//   Fn(t) = (U0(t) - Wg(t - Tg) - Ww(t - Tw) - x(t)) / (1/kc + 1/kg + 1/kw)
//   Wg(t) = Wg(t - Tg) + Fn/kg,   Ww(t) = Ww(t - Tw) + Fn/kw,   x = sum_i q_i,
//   q_i''/w_i^2 + 2 zeta_i q_i'/w_i + q_i = Fn / k_i                (modal compliances summed)
//
// "t - Tg" and "t - Tw" are one wheel / work revolution ago by angle (any speed law). A chain
// switched off drops its term (kg or kw -> infinity) and stores no surface. The interference
// U0 - Wg - Ww - x is the contact event: the force is zero when it is negative (one-sided).
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"

namespace chatterlab {

class PlungeTimeDomain final : public TimeDomainModel {
 public:
  explicit PlungeTimeDomain(const PlungeRegenerativeParameters& parameters);

  std::size_t state_size() const override { return 2 * modes_.size(); }
  void initial_state(const Disturbance& disturbance, std::span<double> state) const override;
  void state_scales(double displacement_m, std::span<double> scales) const override;
  double highest_frequency_hz() const override;
  bool regenerates(Rotor rotor) const override;
  double nominal_speed_rpm(Rotor rotor) const override;
  void contact(const ContactInput& in, ContactOutput& out) const override;
  void derivatives(const ContactInput& in, const ContactOutput& contact,
                   std::span<double> state_derivative) const override;
  double displacement_m(std::span<const double> state) const override;

 private:
  struct Mode {
    double omega, zeta, compliance_m_per_n;  // w, zeta, 1/k
  };
  PlungeRegenerativeParameters p_;
  std::vector<Mode> modes_;
  double series_compliance_;  // 1/kc + 1/kg (wheel on) + 1/kw (work on)
  double total_compliance_;   // sum 1/k_i
};

}  // namespace chatterlab
