#include "models/plunge_with_penetration_damping/plunge_with_penetration_damping.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

PlungeRegenerativeParameters work_chain_off(PlungeRegenerativeParameters p) {
  p.work_regeneration = false;
  return p;
}

}  // namespace

PenetrationDampingCharacteristic::PenetrationDampingCharacteristic(const PlungeRegenerativeParameters& p,
                                                                   double kd)
    : parameters_(p),
      full_(p),
      work_off_(work_chain_off(p)),
      delay_ratio_(p.work_regeneration ? kd / p.work_removal_stiffness_n_per_m : 0.0) {}

CharacteristicValue PenetrationDampingCharacteristic::evaluate(Complex s) const {
  // E = E_G1 + delta s E_off (E_G1 affine in B: B -> B + delta s adds delta s dE/dB = delta s E_off).
  const CharacteristicValue full = full_.evaluate(s);
  if (delay_ratio_ == 0.0) return full;
  const CharacteristicValue off = work_off_.evaluate(s);
  return {full.value + delay_ratio_ * s * off.value,
          full.derivative + delay_ratio_ * (off.value + s * off.derivative)};
}

std::vector<Complex> PenetrationDampingCharacteristic::neutral_roots(double max_w) const {
  // s = 0 stays (A = 0 and B + delta s = 0 there: cumulative removal); B + delta s has no other
  // zero on the axis (|1 - e^{-jwT}| = |delta w| needs sin(wT) = -delta w with cos(wT) = 1), so
  // the common lattice points of commensurate speeds are no longer neutral once kd > 0.
  if (delay_ratio_ == 0.0) return full_.neutral_roots(max_w);
  if (parameters_.wheel_regeneration && parameters_.work_regeneration) return {Complex(0.0)};
  return {};
}

void PenetrationDampingCharacteristic::initial_guesses(double max_w, std::vector<Complex>& guesses) const {
  full_.initial_guesses(max_w, guesses);
  if (delay_ratio_ == 0.0) return;
  // The work chain's roots move left with kd: e^{-Tw s} = 1 + delta s + beta/K (K = 1 + kc H +
  // kc/kg, the wheel chain averaged), a few fixed-point steps from each lattice point.
  const double tw = 60.0 / parameters_.work_speed_rpm, kc = parameters_.contact_stiffness_n_per_m;
  const double beta = kc / parameters_.work_removal_stiffness_n_per_m;
  const double alpha = parameters_.wheel_regeneration ? kc / parameters_.wheel_wear_stiffness_n_per_m : 0.0;
  for (long m = 1; kTwoPi * static_cast<double>(m) / tw <= max_w; ++m) {
    const Complex lattice(0.0, kTwoPi * static_cast<double>(m) / tw);
    Complex s = lattice;
    for (int it = 0; it < 4; ++it) {
      const Complex k = 1.0 + kc * full_.structural_compliance(s) + alpha;
      s = lattice - std::log(1.0 + delay_ratio_ * s + beta / k) / tw;
    }
    guesses.push_back(Complex(std::min(s.real(), real_part_bound()), s.imag()));
  }
}

double PenetrationDampingCharacteristic::real_part_bound() const {
  // For Re s > 0: Re 1/(1 - e^{-Tg s}) > 1/2, and kw B + kd s has positive real part (Re B > 0,
  // Re kd s > 0), so Re of its inverse is > 0: Re D > nu - kc |H| with nu = 1 + alpha/2 (the work
  // term's 1/2 of G1 is lost), |P_i| >= sigma^2/w_i^2 as in G1.
  const double kc = parameters_.contact_stiffness_n_per_m;
  const double nu = 1.0 + (parameters_.wheel_regeneration ? 0.5 * kc / parameters_.wheel_wear_stiffness_n_per_m : 0.0);
  double sum = 0.0;
  for (const StructuralMode& m : parameters_.modes) {
    const double w = kTwoPi * m.frequency_hz;
    sum += kc / m.stiffness_n_per_m * w * w;
  }
  return std::max(1.001 * std::sqrt(sum / nu) + 1e-9, full_.real_part_bound());
}

double PenetrationDampingCharacteristic::natural_frequency_scale_hz() const {
  return full_.natural_frequency_scale_hz();
}

// ------------------------------------------------------------------ model plugin

namespace {

constexpr const char* kKey = "penetration_damping_n_s_per_m";

PlungeRegenerativeParameters plunge_parameters(const ParamValues& v) {
  Json table = v.json();
  table.erase(kKey);
  return PlungeRegenerative(ParamValues(std::move(table))).parameters();
}

}  // namespace

PlungeWithPenetrationDamping::PlungeWithPenetrationDamping(const ParamValues& values)
    : parameters_(plunge_parameters(values)), penetration_damping_n_s_per_m_(values.real(kKey)) {}

PluginInfo PlungeWithPenetrationDamping::info() {
  PluginInfo info = PlungeRegenerative::info();
  info.name = "plunge_with_penetration_damping";
  info.description =
      "G1 plunge grinding with the dynamic (penetration-rate) grinding force kd of G4, which does "
      "not regenerate";
  info.models_md_ids = "G1, G4";
  ParamSpec kd = param_spec(kKey, ValueKind::real, "N s/m",
                            "dynamic grinding coefficient kd = ks sqrt(de u0)/vw (G4 eq 2-77/2-78)");
  kd.min = 0.0;
  info.params.push_back(kd);
  // The plunge example with kd for kw = 5e7 N/m, de = 0.08 m, u0 = 5 um, vw = 0.29 m/s.
  info.example_params[kKey] = 1.09e5;
  return info;
}

std::unique_ptr<CharacteristicFunction> PlungeWithPenetrationDamping::characteristic() const {
  return std::make_unique<PenetrationDampingCharacteristic>(parameters_, penetration_damping_n_s_per_m_);
}

std::optional<double> PlungeWithPenetrationDamping::wheel_period_s() const {
  return 60.0 / parameters_.wheel_speed_rpm;
}

CHATTERLAB_REGISTER_MODEL(PlungeWithPenetrationDamping);

}  // namespace chatterlab
