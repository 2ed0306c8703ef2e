#pragma once
// The three quantifications of variable-speed chatter suppression (MODELS.md S1-S3, book 5.3).
// Each is a plain function; the `suppression_map` study kind compares them with simulations.
// Docs: docs/suppression.md (derivations and the corrections to the printed equations).
#include <functional>
#include <memory>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/suppression.hpp"

namespace chatterlab::suppression_measures {

// ------------------------------------------------------------------ S2 (eqs 5-36..5-39, G3)

// Times at which a rotor of mean speed mean_rpm, following level(t) (angle = 2 pi/60 mean_rpm
// * level_integral), completes revolutions 1, 2, ... up to end_s; starts with 0 and ends with
// end_s (a last partial revolution).
std::vector<double> revolution_boundaries(const ModulationLaw& law, double mean_rpm, double end_s);

// Growth-rate averaging (5-36/5-37): revolution i, [t_i, t_{i+1}], grows by e^{2 pi rho_i} with
// rho_i = T_i sigma(level_i)/(2 pi), level_i = the mean level of the modulated quantity over that
// revolution and sigma(level) the growth rate [1/s] of the rightmost root at those frozen
// conditions. Returns ln(A_n/A_0) = 2 pi sum rho_i (the log of 5-39; constant speed: 5-38).
// Valid while the conditions change slowly against the chatter build-up: see
// quasi_static_phase_drift_rad.
double growth_averaging_log_amplification(const ModulationLaw& law, const std::vector<double>& boundaries,
                                          const std::function<double(double level)>& growth_rate_per_s);

// The frozen-root approximation's small parameter: the change of the regenerative phase
// w Tg over one revolution caused by the modulation, 2 pi f_c Tg * (largest relative change of
// the speed from one revolution to the next). The chatter pattern written on the surface keeps
// its wave count while the speed drifts; 5-37 treats each revolution as if the pattern had
// settled on the rightmost root of the new speed, which needs this << 1 (and no switch of the
// rightmost root to another lobe inside the speed range; docs/suppression.md).
double quasi_static_phase_drift_rad(double chatter_frequency_hz, double mean_rpm,
                                    double relative_change_per_revolution);

// The same sum with the chatter pattern locked to its wave count (the book's reading of 5-39:
// "the chatter frequency follows the wheel speed") instead of the rightmost root: the root of the
// nominal chatter is continued revolution by revolution by Newton's method on the characteristic
// function at that revolution's frozen conditions, from the previous root with w Tg kept (the
// wave count on the wheel) when `wave_count_follows_wheel`, else from the previous root itself.
// `characteristic_at(level)` gives E(s) at modulation level q/q_mean. Returns ln(A_n/A_0);
// throws std::runtime_error if Newton fails to converge.
double continued_root_log_amplification(
    const std::function<std::unique_ptr<CharacteristicFunction>(double level)>& characteristic_at,
    const ModulationLaw& law, const std::vector<double>& boundaries, Complex start_root,
    bool wave_count_follows_wheel);

// ------------------------------------------------------------------ S3 (eqs 5-40..5-45)

// 5-40: 60 f / n = J + eps with J an integer and -0.5 <= eps < 0.5; returns the lag phi of the
// current wave behind the previous one, in (-pi, pi]. Corrected sign: phi = -2 pi eps. (One
// revolution advances the vibration by 2 pi (J + eps), so the current wave x(t) = X cos(wt) and
// the previous x0 = X cos(wt - 2 pi eps): the current one LEADS by 2 pi eps, and in the book's
// x = X cos(wt - phi) that is phi = -2 pi eps, not the printed 2 pi eps. Checked against the
// rightmost roots of G1: every chattering root has eps < 0, work-regenerative chatter near
// eps = -1/4, i.e. phi = pi/2, the book's point of largest energy input.)
double phase_lag_rad(double chatter_frequency_hz, double speed_rpm);

// 5-45: energy fed into the vibration per cycle, E = pi C' X^2 sin(phi) [J] (C' = dF/da [N/m],
// X the wave amplitude [m]); > 0 for 0 < phi < pi (the exciting zone).
double energy_per_cycle_j(double force_per_depth_n_per_m, double amplitude_m, double phase_lag_rad);

struct EnergyBalance {
  double mean_normalised_energy = 0.0;  // time mean of E/(pi C' X^2) = sin(phi(t)) over the span
  double exciting_fraction = 0.0;       // fraction of the span with E > 0 (0 < phi < pi)
};
// The energy balance of a chatter frequency f over [start_s, end_s] while the speed follows
// speed_rpm(t) (a constant f: the chatter locked to a structural mode, as 5.3.3 assumes),
// sampled at `samples` uniform times (midpoint rule).
EnergyBalance energy_balance(double chatter_frequency_hz, const std::function<double(double)>& speed_rpm,
                             double start_s, double end_s, std::size_t samples = 20000);

// ------------------------------------------------------------------ S1 (eqs 5-23..5-29)

// The single-mode grinder of 5.3.1: modal mass and stiffness (m, k), contact and wheel wear
// stiffness at the nominal thickness (kc0, kg0), work removal stiffness kw, the exponent
// epsilon of k = k0 (1 - eps/2 da/a) (reference [111]; with F = C a^beta, 5-43, the tangent
// stiffness dF/da goes as a^(beta - 1), so eps = 2 (1 - beta)). A chain switched off (wheel or
// work regeneration absent) has its stiffness = +inf.
struct FeedChatterModel {
  double modal_mass_kg = 0.0;
  double modal_stiffness_n_per_m = 0.0;
  double contact_stiffness_n_per_m = 0.0;
  double wheel_wear_stiffness_n_per_m = 0.0;
  double work_removal_stiffness_n_per_m = 0.0;
  double thickness_exponent = 0.6;
};

// Critical chatter frequency [Hz] at relative thickness change da/a, corrected 5-29:
//   w^2 = wn^2 + 1 / ( m/kc + m/(2 kg) + m/(2 kw) ),  kc = kc0 (1 - eps/2 da/a), kg likewise.
// (1/(1 - e^{-j theta}) = 1/2 - (j/2) cot(theta/2): the printed 5-24 has 2/kg and 2/kw where
// 1/(2 kg) and 1/(2 kw) belong, which 5-28/5-29 inherit; 5-27's sign is misplaced.)
double feed_chatter_frequency_hz(const FeedChatterModel& model, double relative_thickness_change);
// The same as printed (2m/kg, 2m/kw), for comparison only.
double feed_chatter_frequency_printed_hz(const FeedChatterModel& model, double relative_thickness_change);

}  // namespace chatterlab::suppression_measures
