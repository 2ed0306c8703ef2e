#include "study_kinds/suppression_map/suppression_measures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "shared/plunge_dynamics/wheel_growth_rate.hpp"

namespace chatterlab::suppression_measures {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}

std::vector<double> revolution_boundaries(const ModulationLaw& law, double mean_rpm, double end_s) {
  if (!(mean_rpm > 0.0) || !(end_s > 0.0))
    throw std::invalid_argument("revolution_boundaries: mean speed and end time must be > 0");
  // Revolutions (in turns) completed by t: mean_rpm/60 * integral of the level.
  auto turns = [&](double t) { return mean_rpm / 60.0 * law.level_integral(t); };
  std::vector<double> times{0.0};
  const double total = turns(end_s);
  const double shortest = 60.0 / (mean_rpm * law.max_level());
  for (double k = 1.0; k <= total; k += 1.0) {
    // Bisection on the monotone turns(t) (the level stays > 0) between the previous boundary
    // and a bracket one slowest revolution later: robust for any shape, kinks and jumps included.
    double lo = times.back(), hi = std::min(end_s, lo + 60.0 / (mean_rpm * law.min_level()) + shortest);
    while (turns(hi) < k && hi < end_s) hi = std::min(end_s, hi + shortest);
    for (int i = 0; i < 200 && hi - lo > 1e-12 * std::max(1.0, hi); ++i) {
      const double mid = 0.5 * (lo + hi);
      (turns(mid) < k ? lo : hi) = mid;
    }
    times.push_back(hi);
  }
  if (times.back() < end_s) times.push_back(end_s);
  return times;
}

double growth_averaging_log_amplification(const ModulationLaw& law, const std::vector<double>& b,
                                          const std::function<double(double)>& growth_rate_per_s) {
  // rho_i = T_i sigma_i / (2 pi) per revolution, then 5-37 through G3's own recursion.
  std::vector<double> rho;
  rho.reserve(b.size());
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const double duration = b[i + 1] - b[i];
    if (!(duration > 0.0)) continue;
    const double mean_level = (law.level_integral(b[i + 1]) - law.level_integral(b[i])) / duration;
    rho.push_back(duration * growth_rate_per_s(mean_level) / kTwoPi);
  }
  return wheel_growth::log_amplification(rho);
}

double continued_root_log_amplification(
    const std::function<std::unique_ptr<CharacteristicFunction>(double)>& characteristic_at,
    const ModulationLaw& law, const std::vector<double>& b, Complex root, bool wave_count_follows_wheel) {
  std::vector<double> rho;
  double previous_level = 1.0;
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const double duration = b[i + 1] - b[i];
    if (!(duration > 0.0)) continue;
    const double level = (law.level_integral(b[i + 1]) - law.level_integral(b[i])) / duration;
    // Wheel period Tg ~ 1/level: keeping w Tg keeps the wave count (a lattice root moves with it).
    Complex s = root;
    if (wave_count_follows_wheel) s = {root.real(), root.imag() * level / previous_level};
    auto fn = characteristic_at(level);
    bool converged = false;
    for (int k = 0; k < 50 && !converged; ++k) {
      const CharacteristicValue e = fn->evaluate(s);
      if (!(std::abs(e.derivative) > 0.0)) break;
      const Complex step = e.value / e.derivative;
      s -= step;
      converged = std::abs(step) <= 1e-12 * std::abs(s);
    }
    if (!converged || !std::isfinite(s.real()))
      throw std::runtime_error("continued_root_log_amplification: Newton did not converge at level " +
                               std::to_string(level));
    root = s;
    previous_level = level;
    rho.push_back(duration * root.real() / kTwoPi);
  }
  return wheel_growth::log_amplification(rho);
}

double quasi_static_phase_drift_rad(double chatter_frequency_hz, double mean_rpm,
                                    double relative_change_per_revolution) {
  return kTwoPi * chatter_frequency_hz * 60.0 / mean_rpm * relative_change_per_revolution;
}

double phase_lag_rad(double chatter_frequency_hz, double speed_rpm) {
  const double waves = 60.0 * chatter_frequency_hz / speed_rpm;  // J + eps
  double eps = waves - std::floor(waves);                          // [0, 1)
  if (eps >= 0.5) eps -= 1.0;                                      // [-0.5, 0.5)
  return -kTwoPi * eps;                                            // corrected sign (header)
}

double energy_per_cycle_j(double c_prime, double amplitude_m, double phase_lag) {
  return std::numbers::pi * c_prime * amplitude_m * amplitude_m * std::sin(phase_lag);
}

EnergyBalance energy_balance(double f, const std::function<double(double)>& speed_rpm, double start_s,
                             double end_s, std::size_t samples) {
  if (!(end_s > start_s) || samples == 0)
    throw std::invalid_argument("energy_balance: needs end_s > start_s and samples > 0");
  EnergyBalance out;
  const double dt = (end_s - start_s) / static_cast<double>(samples);
  std::size_t exciting = 0;
  for (std::size_t i = 0; i < samples; ++i) {
    const double t = start_s + (static_cast<double>(i) + 0.5) * dt;
    const double s = std::sin(phase_lag_rad(f, speed_rpm(t)));
    out.mean_normalised_energy += s;
    exciting += s > 0.0 ? 1 : 0;
  }
  out.mean_normalised_energy /= static_cast<double>(samples);
  out.exciting_fraction = static_cast<double>(exciting) / static_cast<double>(samples);
  return out;
}

namespace {
// 1/k for a stiffness, 0 for a chain that is off (+inf).
double compliance(double k) { return std::isinf(k) ? 0.0 : 1.0 / k; }

double s1_frequency(const FeedChatterModel& m, double da_over_a, double chain_weight) {
  const double scale = 1.0 - 0.5 * m.thickness_exponent * da_over_a;
  if (!(scale > 0.0))
    throw std::invalid_argument("feed_chatter_frequency: 1 - eps/2 da/a must stay > 0");
  const double process = compliance(m.contact_stiffness_n_per_m * scale) +
                         chain_weight * compliance(m.wheel_wear_stiffness_n_per_m * scale) +
                         chain_weight * compliance(m.work_removal_stiffness_n_per_m);
  const double wn2 = m.modal_stiffness_n_per_m / m.modal_mass_kg;
  return std::sqrt(wn2 + 1.0 / (m.modal_mass_kg * process)) / kTwoPi;
}
}  // namespace

double feed_chatter_frequency_hz(const FeedChatterModel& model, double da_over_a) {
  return s1_frequency(model, da_over_a, 0.5);
}

double feed_chatter_frequency_printed_hz(const FeedChatterModel& model, double da_over_a) {
  return s1_frequency(model, da_over_a, 2.0);
}

}  // namespace chatterlab::suppression_measures
