#pragma once
// MODELS.md G2: Thompson's time-domain steady-state model of doubly regenerative plunge grinding,
// book eqs 2-22..2-65, with its closed-form criteria. Docs: docs/models/thompson.md.
//
//   m x1'' + c x1' + k x1 = Fd,  x2 = x2(t - Tg) - Kg Fd,  x5 = x5(t - Tw) - Kw Fd,
//   x1 = x2 + x5 - Kc Fd                                     (contact relation, see below)
//
// In the Laplace domain: 1/(m s^2 + c s + k) + Kc + Kg/(1 - e^{-Tg s}) + Kw/(1 - e^{-Tw s}) = 0,
// which is G1's eq 2-16 for one mode with kc = 1/Kc, kg = 1/Kg, kw = 1/Kw (the characteristic
// function is the G1 family's, shared/plunge_dynamics). The printed contact relation 2-28 also adds x3 = Kg Fd; with
// it the sin-balance would read (Kg - Kw)/2 instead of the book's own eq 2-41 (-(Kg + Kw)/2), so
// x2 already contains this revolution's wear and x3 must not be added again (docs/models/thompson.md).
//
// On s = j w every closed form follows from H(jw) = -P + j/a with the process line
// P = K H/2 = Kg/2 + Kw/2 + Kc (eq 2-59) and the stability index a (2-39):
//   1/a = (1/2) [Kg cot(w Tg/2) + Kw cot(w Tw/2)].
#include <memory>
#include <optional>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/closed_form.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "shared/plunge_dynamics/plunge_characteristic.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab {

struct ThompsonParameters {
  double mass_kg = 0.0;                          // m
  double damping_n_s_per_m = 0.0;                // c (measured damping c0)
  double stiffness_n_per_m = 0.0;                // k
  double wheel_wear_compliance_m_per_n = 0.0;    // Kg
  double work_removal_compliance_m_per_n = 0.0;  // Kw
  double contact_compliance_m_per_n = 0.0;       // Kc
  double wheel_speed_rpm = 0.0;                  // Tg = 60/n_g
  double work_speed_rpm = 0.0;                   // Tw = 60/n_w
};

namespace thompson {

// The same system as G1 (eq 2-16) with one mode: kc = 1/Kc, kg = 1/Kg, kw = 1/Kw,
// f = sqrt(k/m)/(2 pi), zeta = c/(2 sqrt(k m)), modal stiffness k.
PlungeRegenerativeParameters equivalent_g1(const ThompsonParameters& p);

// K = Kg + Kw (2-42) [m/N].
double cutting_compliance_m_per_n(const ThompsonParameters& p);
// Hertz contact parameter H = 1 + 2 Kc/K (2-60); 1 for rigid contact.
double hertz_parameter(const ThompsonParameters& p);
// P = K H/2 [m/N]: minus the process line Re = -(1/2)(2/kc + 1/kg + 1/kw) of G1 eq 2-21.
double process_line_m_per_n(const ThompsonParameters& p);

// Eq 2-43 generalised to contact: c^2 = 2 m a^2 / (alpha a^4 + beta a^2 + 2 k) with
// alpha = 2 P^3 (1 + k P), beta = 2 P (1 + 2 k P); for H = 1 these are the book's
// alpha = (K^3/4)(1 + kK/2), beta = K (1 + kK).
struct BoundaryQuartic {
  double alpha;  // [m^3/N^3 * N/m] = m^2/N^2
  double beta;   // [m/N]
};
BoundaryQuartic boundary_quartic(const ThompsonParameters& p);
// The damping that holds the system on the stability boundary at stability index a < 0 [N/m].
double boundary_damping_n_s_per_m(const ThompsonParameters& p, double stability_index_n_per_m);

// c_m (2-48, with D -> D/H for contact): the largest boundary damping over all a; c0 > c_m is
// stable at every wheel and work speed. Closed form sqrt(m) (sqrt(k + 1/P) - sqrt(k)).
double unconditional_damping_n_s_per_m(const ThompsonParameters& p);
// The book's printed form 2-48, 2m (D + k)[1 - sqrt(1 - D^2/(k + D)^2)] with D = 1/(K H)
// (an independent route to the same number, kept for the tests and the docs).
double unconditional_damping_eq_2_48_n_s_per_m(const ThompsonParameters& p);
// The damping c solving the frequency-domain absolute-stability condition (2-65)
// K H/2 = 1/(2 c sqrt(k/m) + c^2/m), i.e. the single-mode compliance circle touching the process line.
double absolute_stability_damping_eq_2_65_n_s_per_m(const ThompsonParameters& p);

// Conditional boundaries a1 > a2 (both < 0) of eq 2-51 (corrected) at the measured damping c0:
// chatter when a2 < a < a1 (2-52). Empty when c0 >= c_m (no band: unconditionally stable).
struct StabilityIndexBand {
  double a1_n_per_m;
  double a2_n_per_m;
};
std::optional<StabilityIndexBand> conditional_boundaries(const ThompsonParameters& p);
// The same band in z = a K/2 by the printed formula 2-64 (typo "2H^3 kKH^4" read as
// 2H^3 + kKH^4): an independent route; z1 = z2 exactly when c0 = c_m.
struct DimensionlessBand {
  double z1;  // closer to 0
  double z2;
};
std::optional<DimensionlessBand> dimensionless_boundaries(const ThompsonParameters& p);
// The discriminant of 2-64 (its inner root's radicand); zero at c0 = c_m, the identity with 2-65.
double eq_2_64_discriminant(const ThompsonParameters& p);
// Boundary frequency for a given z (2-63; 2-54 when H = 1) [rad/s].
double boundary_frequency_rad_s(const ThompsonParameters& p, double z);

// 1/a(w) = (1/2)[Kg cot(w Tg/2) + Kw cot(w Tw/2)] [m/N] at these wheel/work speeds (2-35, 2-36,
// 2-39): the stability index that the speeds impose at frequency w.
double inverse_stability_index_m_per_n(const ThompsonParameters& p, double frequency_rad_s);

// The speed-dependent criterion: the frequencies w in (wn, wn sqrt(1 + 2/(kKH))) where the
// boundary relation (2-63, i.e. 2-61 with 2-62) and the speeds' a(w) agree, one per interval
// between the poles of a(w); at each the damping that makes these speeds marginal (2-43).
// Chatter at the measured damping c0 iff c0 < the largest of them, i.e. iff a(w) lies in
// (a2, a1) at one of these frequencies.
struct SpeedCriterion {
  double critical_damping_n_s_per_m = 0.0;  // largest marginal damping over the crossings
  double frequency_rad_s = 0.0;             // the crossing where it occurs
  double stability_index_n_per_m = 0.0;     // a at that crossing (< 0)
  int crossings = 0;                        // self-consistent frequencies found
  // c_crit/c0 - 1: > 0 chatter predicted at these speeds, < 0 stable.
  double chatter_margin = 0.0;
};
SpeedCriterion speed_criterion(const ThompsonParameters& p);

}  // namespace thompson

class Thompson final : public Model, public ClosedFormIndicators, public StructuralCompliance {
 public:
  explicit Thompson(const ParamValues& values);
  explicit Thompson(ThompsonParameters parameters);

  static PluginInfo info();

  // G1 eq 2-16 with one mode and kc = 1/Kc, kg = 1/Kg, kw = 1/Kw (the G1 family's E(s)).
  std::unique_ptr<CharacteristicFunction> characteristic() const override;
  std::optional<double> wheel_period_s() const override;

  const ClosedFormIndicators* closed_forms() const override { return this; }
  std::vector<ClosedFormIndicatorSpec> indicator_specs() const override;
  std::vector<Json> indicator_values() const override;

  // The equivalent G1 system's chain and compliance (one mode: 1/(m s^2 + c s + k)).
  std::optional<StiffnessChain> stiffness_chain() const override;
  const StructuralCompliance* structural_compliance() const override { return this; }
  Complex compliance_m_per_n(Complex s) const override;

  const ThompsonParameters& parameters() const { return parameters_; }

 private:
  ThompsonParameters parameters_;
  PlungeCharacteristic equivalent_;  // of thompson::equivalent_g1(parameters_)
};

}  // namespace chatterlab
