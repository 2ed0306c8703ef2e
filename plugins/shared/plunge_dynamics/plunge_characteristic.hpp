#pragma once
// MODELS.md G1 (Snoeys type), characteristic equation eq 2-16
//
//   D(s) = 1 + kc [ H(s) + 1/(kg (1 - e^{-Tg s})) + 1/(kw (1 - e^{-Tw s})) ],
//   H(s) = sum_i (1/k_i) / (s^2/w_i^2 + 2 zeta_i s/w_i + 1)     (modal compliances summed),
//
// with Tg = 60/n_wheel, Tw = 60/n_work. Either regeneration chain can be switched off (its term is
// then absent, the limit kg -> inf or kw -> inf of eq 2-16; with the work chain off this is the
// wheel-regenerative model of G3, eq 2-66). The characteristic function of every model of the
// family (plunge_regenerative, thompson's equivalent G1 system, plunge_with_penetration_damping
// builds on two of them). Docs: docs/models/plunge_regenerative.md.
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab {

// E(s) = D(s) * A(s) B(s) * prod_i P_i(s), A = 1 - e^{-Tg s}, B = 1 - e^{-Tw s},
// P_i = s^2/w_i^2 + 2 zeta_i s/w_i + 1, evaluated in the factored form
//   E = Pi * (A B + alpha B + beta A) + A B * sum_i kc/k_i prod_{j != i} P_j,
//   alpha = kc/kg, beta = kc/kw
// (A = 1, alpha = 0 when the wheel chain is off; B = 1, beta = 0 when the work chain is off). Every
// term is O(1) times the modal product, so E is accurate to rounding right next to the roots that
// hug Re s = 0, which the certificate contour passes at ~1e-6 /s.
class PlungeCharacteristic final : public CharacteristicFunction {
 public:
  explicit PlungeCharacteristic(const PlungeRegenerativeParameters& parameters);

  CharacteristicValue evaluate(Complex s) const override;
  // E / (1 + beta - e^{-Tw s}) when the work chain is on: at high frequency (kc H -> 0, alpha << 1)
  // the work chain's roots satisfy 1 - e^{-Tw s} = -beta, so this factor holds their lattice and
  // the quotient is nearly linear near them (Newton needs less than half the steps on the
  // feed_risk problem-2 study's searches). Its zeros lie on Re s = -ln(1 + beta)/Tw.
  CharacteristicValue newton_form(Complex s) const override;
  std::vector<Complex> neutral_roots(double max_angular_frequency_rad_s) const override;
  void initial_guesses(double max_angular_frequency_rad_s,
                       std::vector<Complex>& guesses) const override;
  double real_part_bound() const override;
  double natural_frequency_scale_hz() const override;

  // Machine compliance H(s) = sum_i (1/k_i)/P_i(s) [m/N] (G1), used by the guesses, by the models'
  // StructuralCompliance capability (the compliance chart) and by tests of the closed-form
  // criteria (G1 eq 2-21, G3 eq 2-68).
  Complex structural_compliance(Complex s) const;

 private:
  // E and the work chain's regeneration factor B = 1 - e^{-Tw s} (1 when that chain is off).
  struct Evaluation {
    CharacteristicValue e;
    CharacteristicValue work;
  };
  Evaluation evaluate_with_work_factor(Complex s) const;

  struct Mode {
    double inverse_omega_squared;  // 1/w^2 [s^2]
    double two_zeta_over_omega;    // 2 zeta / w [s]
    double contact_ratio;          // kc / k_i (sum over modes merged for identical w, zeta)
    double omega;                  // w [rad/s]
    double zeta;
  };
  double wheel_period_s_, work_period_s_;
  bool wheel_on_, work_on_;
  double contact_stiffness_;
  double alpha_, beta_;  // kc/kg, kc/kw (0 when that chain is off)
  std::vector<Mode> modes_;
};

}  // namespace chatterlab
