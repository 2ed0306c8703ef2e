#include "models/plunge_with_penetration_damping/plunge_with_penetration_damping.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/param_table.hpp"
#include "shared/plunge_dynamics/grinding_process.hpp"
#include "shared/plunge_dynamics/process_scaling.hpp"

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

CharacteristicValue PenetrationDampingCharacteristic::newton_form(Complex s) const {
  return delay_ratio_ == 0.0 ? full_.newton_form(s) : evaluate(s);
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

namespace gp = grinding_process;

const ParamTable<PenetrationDampingParameters>& parameters_table() {
  using P = PenetrationDampingParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add_fields(&P::plunge, plunge_dynamics::plunge_parameters_table());
    t.add(&P::penetration_damping_n_s_per_m, "penetration_damping_n_s_per_m", "N s/m",
          "dynamic grinding coefficient kd = ks sqrt(de u0)/vw (G4 eq 2-77/2-78)")
        .non_negative()
        .required();
    t.add(&P::work_diameter_mm, "work_diameter_mm", "mm",
          "workpiece diameter dw (G4 indicators: v_w, de)")
        .positive();
    t.add(&P::wheel_diameter_mm, "wheel_diameter_mm", "mm",
          "wheel diameter dg (G4 indicators: de = dw dg/(dw + dg), external)")
        .positive();
    t.add(&P::depth_of_cut_mm, "depth_of_cut_mm", "mm",
          "depth of cut u0 per work revolution (G4 indicators: contact length sqrt(de u0))")
        .positive();
    return t;
  }();
  return table;
}

// The most compliant structural mode (largest resonant compliance 1/(2 zeta k)): the one chatter
// waves grow on.
const StructuralMode& most_compliant(const std::vector<StructuralMode>& modes) {
  return *std::max_element(modes.begin(), modes.end(), [](const StructuralMode& a, const StructuralMode& b) {
    return a.damping_ratio * a.stiffness_n_per_m > b.damping_ratio * b.stiffness_n_per_m;
  });
}

}  // namespace

PlungeWithPenetrationDamping::PlungeWithPenetrationDamping(const ParamValues& values)
    : PlungeWithPenetrationDamping(parameters_table().read(values)) {}

PlungeWithPenetrationDamping::PlungeWithPenetrationDamping(PenetrationDampingParameters parameters)
    : parameters_(std::move(parameters)), g1_(parameters_.plunge) {}

PluginInfo PlungeWithPenetrationDamping::info() {
  PluginInfo info{
      .name = "plunge_with_penetration_damping",
      .description = "G1 plunge grinding with the dynamic (penetration-rate) grinding force kd of G4, "
                     "which does not regenerate",
      .params = parameters_table().specs(),
      .thread_safety = ThreadSafety::shareable,  // immutable after construction
      .models_md_ids = "G1, G4",
      .example_params = plunge_dynamics::example_g1_parameters(),
  };
  // The G1 example with the kd of its process: kw = 5e7 N/m, work 100 mm and wheel 400 mm
  // (de = 80 mm), u0 = 5 um, vw = 0.29 m/s (55 rpm).
  info.example_params["penetration_damping_n_s_per_m"] = 1.09e5;
  info.example_params["work_diameter_mm"] = 100.0;
  info.example_params["wheel_diameter_mm"] = 400.0;
  info.example_params["depth_of_cut_mm"] = 0.005;
  return info;
}

std::unique_ptr<CharacteristicFunction> PlungeWithPenetrationDamping::characteristic() const {
  return std::make_unique<PenetrationDampingCharacteristic>(parameters_.plunge,
                                                            parameters_.penetration_damping_n_s_per_m);
}

std::optional<double> PlungeWithPenetrationDamping::wheel_period_s() const {
  return 60.0 / parameters_.plunge.wheel_speed_rpm;
}

std::vector<ClosedFormIndicatorSpec> PlungeWithPenetrationDamping::indicator_specs() const {
  return {
      {"work_surface_speed_m_per_s", "v_w = pi dw n_w/60 (needs work_diameter_mm)", false},
      {"contact_length_mm", "geometric contact length sqrt(de u0), de = dw dg/(dw + dg) (G4)", false},
      {"g4_penetration_damping_n_s_per_m",
       "kd = kw sqrt(de u0)/v_w of eq 2-77/2-78 with this kw (compare with the kd given)", false},
      {"critical_work_speed_m_per_s",
       "v_c = 2 pi f sqrt(u0 Re) of eq 2-71 for a wave as deep as the cut at the most compliant "
       "mode's f: below it the wheel cannot copy such waves (geometric filtering)",
       false},
  };
}

std::vector<Json> PlungeWithPenetrationDamping::indicator_values() const {
  const PenetrationDampingParameters& p = parameters_;
  std::vector<Json> values(4);  // null where the geometry is not given
  if (!p.work_diameter_mm) return values;
  const double vw = gp::surface_speed_m_per_s(*p.work_diameter_mm, p.plunge.work_speed_rpm);
  values[0] = vw;
  if (!p.wheel_diameter_mm || !p.depth_of_cut_mm) return values;
  const double dw = 1e-3 * *p.work_diameter_mm, dg = 1e-3 * *p.wheel_diameter_mm, u0 = 1e-3 * *p.depth_of_cut_mm;
  const double de = gp::equivalent_diameter_m(dw, dg, gp::Contact::external);
  values[1] = 1e3 * gp::contact_length_m(de, u0);
  values[2] = gp::dynamic_grinding_coefficient_n_s_per_m(p.plunge.work_removal_stiffness_n_per_m, de, u0, vw);
  values[3] = gp::critical_work_speed_m_per_s(most_compliant(p.plunge.modes).frequency_hz, u0, 0.5 * dw, 0.5 * dg);
  return values;
}

std::optional<StiffnessChain> PlungeWithPenetrationDamping::stiffness_chain() const {
  StiffnessChain chain = plunge_dynamics::stiffness_chain(parameters_.plunge);
  if (parameters_.plunge.work_regeneration)  // kd acts in the work chain only
    chain.penetration_damping_n_s_per_m = parameters_.penetration_damping_n_s_per_m;
  return chain;
}

Complex PlungeWithPenetrationDamping::compliance_m_per_n(Complex s) const { return g1_.structural_compliance(s); }

ProcessConditions PlungeWithPenetrationDamping::nominal_conditions() const {
  return plunge_dynamics::nominal_conditions(parameters_.plunge);
}

Json PlungeWithPenetrationDamping::parameters_at(const ProcessConditions& reference,
                                                 const ProcessConditions& conditions,
                                                 const ProcessScaling& scaling) const {
  PenetrationDampingParameters p = parameters_;
  p.plunge = plunge_dynamics::parameters_at(parameters_.plunge, reference, conditions, scaling);
  p.penetration_damping_n_s_per_m *=
      plunge_dynamics::penetration_damping_factor(parameters_.plunge, reference, conditions, scaling);
  // The geometry of the indicators follows the conditions it is given.
  if (conditions.work_radius_mm > 0.0) p.work_diameter_mm = 2.0 * conditions.work_radius_mm;
  if (conditions.wheel_diameter_mm > 0.0) p.wheel_diameter_mm = conditions.wheel_diameter_mm;
  if (p.depth_of_cut_mm) *p.depth_of_cut_mm *= conditions.depth_of_cut_ratio / reference.depth_of_cut_ratio;
  return parameters_table().write(p);
}

CHATTERLAB_REGISTER_MODEL(PlungeWithPenetrationDamping);

}  // namespace chatterlab
