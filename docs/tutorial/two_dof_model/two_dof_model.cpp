// two_dof_model: a plunge-grinding model with a wheelhead mode and a workpiece mode, both surfaces
// regenerative (MODELS.md G1 with one mode on each side), written ONCE as time-domain physics.
// chatterlab derives the rest from it: the characteristic function and certified roots (the
// Jacobian by automatic differentiation), the time-domain form of its dynamics engine, Floquet
// multipliers for varying speeds. docs/tutorial_model.md walks through every line.
#include <chatterlab/derived_model.hpp>
#include <chatterlab/param_table.hpp>
#include <chatterlab/plugin_api.hpp>

#include <numbers>
#include <span>

namespace {

using chatterlab::Rotor;
constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel), work = static_cast<std::size_t>(Rotor::work);

// State q = (q_h, q_h', q_w, q_w') [m, m/s]: the two modes deflect in series, x = q_h + q_w.
//   q_i'' + 2 zeta_i w_i q_i' + w_i^2 q_i = w_i^2 F / k_i                (i = h, w)
//   F = (u - Wg(t - Tg) - Ww(t - Tw) - x) / (1/kc + 1/kg + 1/kw)          (contact, G1)
//   the wheel loses F / kg, the work F / kw per pass                       (the regenerated surfaces)
struct TwoDof {
  double wheelhead_frequency_hz = 120.0, wheelhead_damping_ratio = 0.05, wheelhead_stiffness_n_per_m = 5e7;
  double workpiece_frequency_hz = 300.0, workpiece_damping_ratio = 0.03, workpiece_stiffness_n_per_m = 8e7;
  double contact_stiffness_n_per_m = 1e8, wheel_wear_stiffness_n_per_m = 5e9, work_removal_stiffness_n_per_m = 5e7;
  double wheel_speed_rpm = 1500.0, work_speed_rpm = 60.0;

  std::size_t state_size() const { return 4; }
  bool regenerates(Rotor) const { return true; }
  double nominal_speed_rpm(Rotor r) const { return r == Rotor::wheel ? wheel_speed_rpm : work_speed_rpm; }
  double displacement_m(std::span<const double> q) const { return q[0] + q[2]; }

  // Written over the scalar type S: double when simulated, a dual number when differentiated.
  template <class S>
  void contact(const chatterlab::ContactInputOf<S>& in, chatterlab::ContactOutputOf<S>& out) const {
    const S interference =
        in.infeed_m - in.state[0] - in.state[2] - in.previous_surface_m[wheel] - in.previous_surface_m[work];
    out.penetration_m = interference;
    out.normal_force_n = interference / (1.0 / contact_stiffness_n_per_m + 1.0 / wheel_wear_stiffness_n_per_m +
                                         1.0 / work_removal_stiffness_n_per_m);
    out.removed_m[wheel] = out.normal_force_n / wheel_wear_stiffness_n_per_m;
    out.removed_m[work] = out.normal_force_n / work_removal_stiffness_n_per_m;
    out.depth_of_cut_m = out.removed_m[work];
  }
  template <class S>
  void derivatives(const chatterlab::ContactInputOf<S>& in, const chatterlab::ContactOutputOf<S>& c,
                   std::span<S> dq) const {
    mode(in.state[0], in.state[1], c.normal_force_n, wheelhead_frequency_hz, wheelhead_damping_ratio,
         wheelhead_stiffness_n_per_m, dq[0], dq[1]);
    mode(in.state[2], in.state[3], c.normal_force_n, workpiece_frequency_hz, workpiece_damping_ratio,
         workpiece_stiffness_n_per_m, dq[2], dq[3]);
  }
  template <class S>
  static void mode(const S& q, const S& v, const S& force, double f_hz, double zeta, double k, S& dq, S& dv) {
    const double w = 2.0 * std::numbers::pi * f_hz;
    dq = v;
    dv = w * w * (force / k - q) - 2.0 * zeta * w * v;
  }
};

// The parameters, declared once: key (units in the name), unit, description, limits.
const chatterlab::ParamTable<TwoDof>& parameters() {
  static const chatterlab::ParamTable<TwoDof> table = [] {
    chatterlab::ParamTable<TwoDof> t;
    t.add(&TwoDof::wheelhead_frequency_hz, "wheelhead_frequency_hz", "Hz", "wheelhead mode").positive();
    t.add(&TwoDof::wheelhead_damping_ratio, "wheelhead_damping_ratio", "1", "its damping ratio").fraction(true);
    t.add(&TwoDof::wheelhead_stiffness_n_per_m, "wheelhead_stiffness_n_per_m", "N/m", "its stiffness").positive();
    t.add(&TwoDof::workpiece_frequency_hz, "workpiece_frequency_hz", "Hz", "workpiece mode").positive();
    t.add(&TwoDof::workpiece_damping_ratio, "workpiece_damping_ratio", "1", "its damping ratio").fraction(true);
    t.add(&TwoDof::workpiece_stiffness_n_per_m, "workpiece_stiffness_n_per_m", "N/m", "its stiffness").positive();
    t.add(&TwoDof::contact_stiffness_n_per_m, "contact_stiffness_n_per_m", "N/m", "contact kc").positive();
    t.add(&TwoDof::wheel_wear_stiffness_n_per_m, "wheel_wear_stiffness_n_per_m", "N/m", "wheel wear kg").positive();
    t.add(&TwoDof::work_removal_stiffness_n_per_m, "work_removal_stiffness_n_per_m", "N/m", "removal kw").positive();
    t.add(&TwoDof::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed").positive();
    t.add(&TwoDof::work_speed_rpm, "work_speed_rpm", "rpm", "work speed").positive();
    return t;
  }();
  return table;
}

class TwoDofModel final : public chatterlab::DerivedModel<TwoDof> {
 public:
  explicit TwoDofModel(const chatterlab::ParamValues& values) : DerivedModel(parameters().read(values.json())) {}
  static chatterlab::PluginInfo info() {
    chatterlab::PluginInfo info;
    info.name = "two_dof_model";
    info.description = "wheelhead and workpiece modes, both surfaces regenerative (tutorial)";
    info.models_md_ids = "G1";
    info.params = parameters().specs();
    info.thread_safety = chatterlab::ThreadSafety::shareable;
    info.example_params = parameters().write(TwoDof{});
    return info;
  }
};

}  // namespace

CHATTERLAB_PLUGIN_ENTRY(registries) { chatterlab::add_plugin<TwoDofModel>(registries.models, registries.origin); }
