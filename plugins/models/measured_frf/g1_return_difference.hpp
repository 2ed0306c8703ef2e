#pragma once
// MODELS.md G1 on the imaginary axis with any machine compliance H(j w): the return difference
//   F = D / (1 + kc/(kg A) + kc/(kw B)) = 1 + kc H A B / (A B + alpha B + beta A),
//   A = 1 - e^{-Tg s}, B = 1 - e^{-Tw s}, alpha = kc/kg, beta = kc/kw,
// whose Nyquist count is the number of unstable roots of eq 2-16 (chatterlab/nyquist.hpp says why
// F qualifies). H comes from a measured FRF or from fitted modes.
#include <functional>
#include <vector>

#include "chatterlab/nyquist.hpp"

namespace chatterlab {

struct G1Process {
  double contact_stiffness_n_per_m = 0.0;
  double wheel_wear_stiffness_n_per_m = 0.0;
  double work_removal_stiffness_n_per_m = 0.0;
  double wheel_period_s = 0.0, work_period_s = 0.0;
  bool wheel_regeneration = true, work_regeneration = true;

  double alpha() const { return wheel_regeneration ? contact_stiffness_n_per_m / wheel_wear_stiffness_n_per_m : 0.0; }
  double beta() const { return work_regeneration ? contact_stiffness_n_per_m / work_removal_stiffness_n_per_m : 0.0; }
  // min over the closed right half plane of |1 + alpha/A + beta/B| (Re 1/A >= 1/2 there): the
  // process line of eq 2-21 in units of 1/kc.
  double process_margin() const { return 1.0 + 0.5 * (alpha() + beta()); }
};

class G1ReturnDifference final : public ReturnDifference {
 public:
  // H [m/N] and dH/df [m/(N Hz)] at f [Hz] >= 0.
  struct ComplianceValue {
    Complex value, derivative_per_hz;
  };
  using Compliance = std::function<ComplianceValue(double frequency_hz)>;

  G1ReturnDifference(const G1Process& process, Compliance compliance, double winding_limit_rad_s,
                     double natural_frequency_scale_hz);

  CharacteristicValue at(double omega_rad_s) const override;
  double winding_limit_rad_s() const override { return winding_limit_rad_s_; }
  void fast_frequencies(double max_rad_s, std::vector<double>& out) const override;
  double natural_frequency_scale_hz() const override { return natural_frequency_scale_hz_; }

 private:
  G1Process process_;
  double alpha_, beta_;
  Compliance compliance_;
  double winding_limit_rad_s_, natural_frequency_scale_hz_;
};

}  // namespace chatterlab
