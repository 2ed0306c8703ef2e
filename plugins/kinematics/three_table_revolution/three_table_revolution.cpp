#include "kinematics/three_table_revolution/three_table_revolution.hpp"

#include <cmath>
#include <stdexcept>

#include "chatterlab/param_table.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

struct ThreeTableParameters {
  double pivot_to_nut_mm = 0.0, fixture_to_pivot_mm = 0.0, screw_pitch_mm = 0.0, gear_ratio = 0.0;
  double step_angle_deg = 0.0, max_pulse_rate_hz = 0.0;
};

const ParamTable<ThreeTableParameters>& parameters_table() {
  using P = ThreeTableParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::pivot_to_nut_mm, "pivot_to_nut_mm", "mm",
          "R: distance from the upper table's vertical axis to the lead-screw nut")
        .positive()
        .required();
    t.add(&P::fixture_to_pivot_mm, "fixture_to_pivot_mm", "mm",
          "b: distance from the fixture reference plane (generatrix x = 0) to the vertical axis")
        .positive()
        .required();
    t.add(&P::screw_pitch_mm, "screw_pitch_mm", "mm", "lead-screw pitch of every table").positive().required();
    t.add(&P::gear_ratio, "gear_ratio", "1", "motor turns per screw turn (gearbox reduction, 10 for 10:1)")
        .positive()
        .required();
    t.add(&P::step_angle_deg, "step_angle_deg", "deg", "motor step angle per pulse")
        .positive()
        .at_most(360.0)
        .required();
    t.add(&P::max_pulse_rate_hz, "max_pulse_rate_hz", "1/s", "largest pulse rate of every motor").positive().required();
    return t;
  }();
  return table;
}

}  // namespace

PluginInfo ThreeTableRevolution::info() {
  return plugin_info("three_table_revolution", "P1, P2, P4",
                     parameters_table().specs(),
                     {{"pivot_to_nut_mm", 300.0},  {"fixture_to_pivot_mm", 250.0},
                      {"screw_pitch_mm", 12.0},    {"gear_ratio", 10.0},
                      {"step_angle_deg", 1.0},     {"max_pulse_rate_hz", 100.0}},
                     "three-table stepper machine for solids of revolution: lower, middle table and the nut "
                     "turning the upper table (P4 inverse kinematics)",
                     ThreadSafety::shareable);
}

ThreeTableRevolution::ThreeTableRevolution(const ParamValues& params) {
  const ThreeTableParameters p = parameters_table().read(params);
  pivot_to_nut_mm_ = p.pivot_to_nut_mm;
  fixture_to_pivot_mm_ = p.fixture_to_pivot_mm;
  mm_per_pulse_ = p.screw_pitch_mm * p.step_angle_deg / 360.0 / p.gear_ratio;
  max_pulse_rate_hz_ = p.max_pulse_rate_hz;
}

std::vector<MotorAxis> ThreeTableRevolution::motors() const {
  return {{"lower", mm_per_pulse_, max_pulse_rate_hz_, "lower"},
          {"middle", mm_per_pulse_, max_pulse_rate_hz_, "middle"},
          {"upper", mm_per_pulse_, max_pulse_rate_hz_, "upper_nut"}};
}

void ThreeTableRevolution::inverse(const CurvePoint& target, const ToolContact& contact,
                                   std::span<double> positions_mm) const {
  if (!(target.tangent_x > 0.0))
    throw std::domain_error("three_table_revolution: the generatrix tangent must point along +x");
  // theta = atan f'(x_s) - tilt; without tilt tan theta = f'(x_s) exactly (P4).
  const double slope = contact.tilt_rad == 0.0
                           ? target.tangent_y / target.tangent_x
                           : std::tan(std::atan2(target.tangent_y, target.tangent_x) - contact.tilt_rad);
  const double c = 1.0 / std::sqrt(1.0 + slope * slope), s = slope * c;
  const double u = fixture_to_pivot_mm_ - target.x_mm, v = -target.y_mm;
  positions_mm[0] = c * u + s * v + contact.along_mm;
  positions_mm[1] = -s * u + c * v + contact.across_mm;
  positions_mm[2] = -pivot_to_nut_mm_ * slope;
}

ToolInPart ThreeTableRevolution::forward(std::span<const double> positions_mm,
                                         const ToolContact& contact) const {
  const double slope = -positions_mm[2] / pivot_to_nut_mm_;
  const double c = 1.0 / std::sqrt(1.0 + slope * slope), s = slope * c;
  // (b - x_s, -y_s) = Rot(-theta) ((x_g, y_g) - C), Rot(-theta) = [[c, -s], [s, c]].
  const double gx = positions_mm[0] - contact.along_mm, gy = positions_mm[1] - contact.across_mm;
  return {fixture_to_pivot_mm_ - (c * gx - s * gy), -(s * gx + c * gy), 0.0};
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_KINEMATICS(chatterlab::ThreeTableRevolution);
