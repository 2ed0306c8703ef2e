#include "models/amplitude_modulated/amplitude_modulated.hpp"

#include <cmath>
#include <numbers>

#include "chatterlab/param_table.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

AmplitudeModulatedParameters floquet_parameters(const AmplitudeModulatedModalParameters& p) {
  const double omega = 2.0 * std::numbers::pi * p.frequency_hz;
  AmplitudeModulatedParameters f;
  f.stiffness_n_per_m = p.stiffness_n_per_m;
  f.mass_kg = p.stiffness_n_per_m / (omega * omega);
  f.damping_n_s_per_m = 2.0 * p.damping_ratio * std::sqrt(p.stiffness_n_per_m * f.mass_kg);
  f.grinding_stiffness_n_per_m = p.grinding_stiffness_n_per_m;
  f.contact_stiffness_n_per_m = p.contact_stiffness_n_per_m;
  f.overlap_factor = p.overlap_factor;
  f.modulation_depth = p.modulation_depth;
  f.wheel_speed_rpm = p.wheel_speed_rpm;
  return f;
}

AmplitudeModulatedEquations::AmplitudeModulatedEquations(const AmplitudeModulatedModalParameters& parameters)
    : p(parameters), omega_rad_s(2.0 * std::numbers::pi * parameters.frequency_hz) {}

void AmplitudeModulatedEquations::initial_state(const Disturbance& d, std::span<double> x) const {
  x[0] = d.displacement_m;
  x[1] = d.velocity_m_per_s;
}

void AmplitudeModulatedEquations::state_scales(double displacement_m, std::span<double> scales) const {
  scales[0] = displacement_m;
  scales[1] = displacement_m * omega_rad_s;
}

double AmplitudeModulatedEquations::highest_frequency_hz() const {
  // Stiffened by at most the series grinding/contact stiffness at full modulation; sidebands add
  // a few wheel rotation frequencies.
  const double g = p.grinding_stiffness_n_per_m * (1.0 + p.modulation_depth);
  const double series = g / (1.0 + g / p.contact_stiffness_n_per_m);
  return 1.5 * p.frequency_hz * std::sqrt(1.0 + series / p.stiffness_n_per_m) + 4.0 * p.wheel_speed_rpm / 60.0;
}

namespace {

const ParamTable<AmplitudeModulatedModalParameters>& parameters_table() {
  using P = AmplitudeModulatedModalParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::frequency_hz, "frequency_hz", "Hz", "structural natural frequency").positive().required();
    t.add(&P::damping_ratio, "damping_ratio", "1", "structural damping ratio zeta").fraction(true).required();
    t.add(&P::stiffness_n_per_m, "stiffness_n_per_m", "N/m", "structural stiffness k").positive().required();
    t.add(&P::grinding_stiffness_n_per_m, "grinding_stiffness_n_per_m", "N/m", "grinding stiffness kg b (times width)")
        .positive()
        .required();
    t.add(&P::contact_stiffness_n_per_m, "contact_stiffness_n_per_m", "N/m", "contact stiffness kc b (times width)")
        .positive()
        .required();
    t.add(&P::overlap_factor, "overlap_factor", "1",
          "overlap factor mu: share of the previous wheel surface seen again")
        .fraction();
    t.add(&P::modulation_depth, "modulation_depth", "1",
          "modulation depth Q of the grinding stiffness per wheel revolution")
        .fraction(true)
        .required();
    t.add(&P::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed n_g; w0 = 2 pi n_g / 60").positive().required();
    t.add(&P::work_speed_rpm, "work_speed_rpm", "rpm", "workpiece speed (reported; not regenerated here)").positive();
    return t;
  }();
  return table;
}

}  // namespace

AmplitudeModulated::AmplitudeModulated(const ParamValues& values)
    : DerivedModel(AmplitudeModulatedEquations(parameters_table().read(values))) {}

PluginInfo AmplitudeModulated::info() {
  return plugin_info("amplitude_modulated", "G7",
                     parameters_table().specs(),
                     Json::parse(R"({
                         "frequency_hz": 800.0, "damping_ratio": 0.05, "stiffness_n_per_m": 5.0e7,
                         "grinding_stiffness_n_per_m": 5.0e6, "contact_stiffness_n_per_m": 1.0e8,
                         "modulation_depth": 0.3, "wheel_speed_rpm": 1450.0 })"),
                     "wheel-regenerative chatter with the grinding stiffness modulated once per "
                     "wheel revolution (G7, eqs 3-9..3-20): beats, sidebands at +/- k n_g/60",
                     ThreadSafety::shareable);
}

CHATTERLAB_REGISTER_MODEL(AmplitudeModulated);

}  // namespace chatterlab
