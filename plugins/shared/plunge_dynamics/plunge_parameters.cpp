#include "shared/plunge_dynamics/plunge_parameters.hpp"

#include <limits>

#include "chatterlab/process_conditions.hpp"

namespace chatterlab::plunge_dynamics {

namespace {

const ParamTable<StructuralMode>& mode_table() {
  static const ParamTable<StructuralMode> table = [] {
    ParamTable<StructuralMode> t;
    t.add(&StructuralMode::frequency_hz, "frequency_hz", "Hz", "modal natural frequency f = w/(2 pi)")
        .positive()
        .required();
    t.add(&StructuralMode::damping_ratio, "damping_ratio", "1", "modal damping ratio zeta")
        .fraction(true)
        .required();
    t.add(&StructuralMode::stiffness_n_per_m, "stiffness_n_per_m", "N/m",
          "modal stiffness k (static compliance 1/k)")
        .positive()
        .required();
    return t;
  }();
  return table;
}

}  // namespace

const ParamTable<PlungeRegenerativeParameters>& plunge_parameters_table() {
  using P = PlungeRegenerativeParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed n_g; wheel period Tg = 60/n_g")
        .positive()
        .required();
    t.add(&P::work_speed_rpm, "work_speed_rpm", "rpm", "workpiece speed n_w; work period Tw = 60/n_w")
        .positive()
        .required();
    t.add(&P::contact_stiffness_n_per_m, "contact_stiffness_n_per_m", "N/m", "wheel-work contact stiffness kc")
        .positive()
        .required();
    t.add(&P::wheel_wear_stiffness_n_per_m, "wheel_wear_stiffness_n_per_m", "N/m",
          "wheel wear stiffness kg (normal force per wheel wear depth)")
        .positive()
        .required();
    t.add(&P::work_removal_stiffness_n_per_m, "work_removal_stiffness_n_per_m", "N/m",
          "workpiece removal (grinding) stiffness kw")
        .positive()
        .required();
    t.add_tables(&P::modes, "modes",
                 "machine structural modes; their compliances (1/k)/(s^2/w^2 + 2 zeta s/w + 1) are summed",
                 mode_table())
        .min_items(1)
        .required();
    t.add(&P::wheel_regeneration, "wheel_regeneration", "1",
          "wheel surface regeneration on (false: kg -> infinity, term absent)");
    t.add(&P::work_regeneration, "work_regeneration", "1",
          "workpiece regeneration on (false: kw -> infinity, term absent; G3)");
    return t;
  }();
  return table;
}

void parameter_values(const PlungeRegenerativeParameters& p, std::vector<double>& values) {
  // The layout of ProcessConditionsModel's default (each container preceded by its size), so that
  // both routes give bitwise the same vector (process_scaling_test checks it): the table's 8 keys,
  // then the modes array's length and each mode's 3 keys.
  constexpr auto size = ProcessConditionsModel::Structure::container_size;
  values.clear();
  values.insert(values.end(), {ProcessConditionsModel::structure_value(size, 8), p.wheel_speed_rpm, p.work_speed_rpm,
                               p.contact_stiffness_n_per_m, p.wheel_wear_stiffness_n_per_m,
                               p.work_removal_stiffness_n_per_m,
                               ProcessConditionsModel::structure_value(size, p.modes.size())});
  const double mode_size = ProcessConditionsModel::structure_value(size, 3);
  for (const StructuralMode& m : p.modes)
    values.insert(values.end(), {mode_size, m.frequency_hz, m.damping_ratio, m.stiffness_n_per_m});
  values.push_back(p.wheel_regeneration ? 1.0 : 0.0);
  values.push_back(p.work_regeneration ? 1.0 : 0.0);
}

Json example_g1_parameters() {
  return Json::parse(R"({
      "wheel_speed_rpm": 1450, "work_speed_rpm": 55,
      "contact_stiffness_n_per_m": 1.0e8, "wheel_wear_stiffness_n_per_m": 5.0e9,
      "work_removal_stiffness_n_per_m": 5.0e7,
      "modes": [ { "frequency_hz": 184.08, "damping_ratio": 0.05, "stiffness_n_per_m": 5.0e7 },
                 { "frequency_hz": 305.6, "damping_ratio": 0.04, "stiffness_n_per_m": 8.0e7 } ]
  })");
}

StiffnessChain stiffness_chain(const PlungeRegenerativeParameters& p) {
  constexpr double off = std::numeric_limits<double>::infinity();
  StiffnessChain chain;
  chain.contact_stiffness_n_per_m = p.contact_stiffness_n_per_m;
  chain.wheel_wear_stiffness_n_per_m = p.wheel_regeneration ? p.wheel_wear_stiffness_n_per_m : off;
  chain.work_removal_stiffness_n_per_m = p.work_regeneration ? p.work_removal_stiffness_n_per_m : off;
  for (const StructuralMode& m : p.modes)
    chain.modes.push_back({m.frequency_hz, m.damping_ratio, m.stiffness_n_per_m});
  return chain;
}

}  // namespace chatterlab::plunge_dynamics
